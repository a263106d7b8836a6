"""Small analytic test cases shared by the aeroelastic tests."""

from __future__ import annotations

import control
import numpy as np

from casflutter.aeroelastic import AeroelasticSystem
from casflutter.structure import ModalStructure

#: Two-mode binary-flutter case: static Σf with a non-symmetric stiffness coupling.
OMEGA2 = np.array([10.0, 25.0])
ZETA2 = np.array([0.02, 0.03])
DF2 = np.array([[0.0, 60.0], [-150.0, -40.0]])
DFLAP2 = np.array([1.0, 2.0])


def binary_system(sensor: str = "acceleration", dynamic: bool = False) -> AeroelasticSystem:
    """Binary flutter case; ``dynamic`` adds a stable first-order aerodynamic lag per mode."""
    if sensor == "state":
        Hs = np.array([[1.0, 0.2, 0.5, 0.0], [0.0, 1.0, 0.3, 0.1]])
    else:
        Hs = np.array([[1.0, 0.5], [0.3, 1.0], [-0.4, 0.8]])
    s = ModalStructure(OMEGA2, ZETA2, alpha=1.3, Hs=Hs, sensor=sensor)
    if dynamic:
        Af = np.diag([-8.0, -12.0])
        Bf = np.array([[1.0, 0.5], [-0.3, 2.0]])
        bf = np.array([[0.7], [-1.1]])
        Cf = np.array([[3.0, -1.0], [2.0, 4.0]])
        sf = control.ss(Af, np.hstack([Bf, bf]), Cf, np.hstack([DF2, DFLAP2[:, None]]))
    else:
        sf = control.ss([], [], [], np.hstack([DF2, DFLAP2[:, None]]))
    return AeroelasticSystem.from_parts(sf, s)


def spectral_abscissa_bisection(matrix_fn, lo: float, hi: float, tol: float = 1e-13) -> float:
    """Independent flutter check: bisection on sign(max Re λ(A(V))), no branch tracking."""
    f = lambda V: np.max(np.linalg.eigvals(matrix_fn(V)).real)  # noqa: E731
    assert f(lo) < 0 < f(hi)
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) < 0 else (lo, mid)
    return 0.5 * (lo + hi)
