import control
import numpy as np
import pytest


@pytest.fixture(scope="session")
def wing_sensor_plant():
    """``plant(run_result, V)``: the truth's own flap-to-accelerometer plant at ``V`` (the flap
    behind the servo of the run's ``controller.servo_omega``, the accelerometers' rows of the
    run's Σs), built here from the truth's state space, for checks that share no code with
    the verification layer."""

    def plant(r, V: float) -> control.StateSpace:
        P = r.truth.statespace(V, actuator_omega=r.config.controller.servo_omega)
        N = r.truth.n_modes
        A, B = np.asarray(P.A), np.asarray(P.B)[:, :1]
        Hs = r.system.structure.Hs
        return control.ss(A, B, Hs @ A[N:2 * N], Hs @ B[N:2 * N])      # zm = Hs ü

    return plant
