"""Write the gridded family ``aircraft_sym`` ONCE (run from anywhere:
``python problems/aircraft_sym/make_problem.py``); its outputs are committed.

A synthetic, aircraft-like aeroservoelastic plant family: the symmetric (longitudinal)
small-perturbation dynamics of a small jet about level flight at altitude, its rigid body
coupled to a flexible wing, sampled at 37 airspeeds from 120 to 300 m/s (51 states,
2 inputs, 6 outputs):

* **Rigid body** (stability axes): ``[u, alpha, q, theta]`` with the classical dimensional
  derivatives of a ~5.5 t jet (wing = the Goland wing, S = 22.3 m², c = 1.83 m, AR 6.7),
  trimmed at every speed (CL = m g / (qbar S), parabolic drag, constant thrust), so that the
  short period (about 2 -> 4.6 rad/s) and the phugoid (about sqrt(2) g / V, lightly damped)
  scale with dynamic pressure and speed as they should.
* **Flexible wing**: :class:`casflutter.aeroelastic.FlapWingFamily` (Goland-type cantilever,
  5 bending + 5 torsion assumed modes, 1 % modal damping, strip theory with Jones' two-lag
  Wagner function), stiffened (EI, GJ x 1.46) and flown at rho = 0.41 kg/m³ (about 7.5 km)
  so that it flutters near 260 m/s; its one trailing-edge flap segment (20 % chord,
  65-100 % of the semispan) is the ``aileron_sym``, behind the family's 25 Hz, zeta 0.7
  actuator.  The wing's gyro filter state is dropped (the wing gyro is not used); the
  wing's own accelerometer rows are reused for the tip accelerometers.
* **Rigid <-> flexible coupling** (mean axes: no inertial coupling; quasi-steady strip
  aerodynamics, C(k) = 1, the same lift-curve slope and geometry as the wing model): the
  rigid angle of attack seen at the 3/4-chord line, ``alpha + x_34 q / V``, loads every
  strip (lift at the quarter chord, generalised onto the wing's modes); the wing's
  deformation (twist, plunge rate, twist rate at the 3/4 chord) and the aileron deflection
  add lift and pitching moment (about the CG) to the rigid-body equations.
* **Elevator**: 25 Hz, zeta 0.7 actuator; quasi-steady tail lift and moment.
* **Sensors**: pitch-rate gyro (30 Hz first-order filter), angle-of-attack vane on a nose
  boom (``alpha - l q / V``), fuselage normal accelerometers fore and aft of the CG, and
  front / rear accelerometers at the wing tip (15 / 65 % chord).  Accelerations are
  body-z, positive down, m/s² (exact, with the feed-through of the commands).

The states are ``[u, alpha, q, theta]`` (4), the wing's modal coordinates and velocities
(20), its Jones lag blocks (22), the aileron angle and rate (2), the elevator angle and
rate (2) and the pitch-gyro filter (1).  Written beside this script:

- ``models.npz``: the arrays (``casflutter.data.FamilyFile`` layout);
- ``problem.toml`` (reads ``models.npz``): the problem file, ``kind = "plant_family"``,
  with the open-loop flutter of the grid (what ``casflutter flutter problems/aircraft_sym``
  finds) as the reference: the aircraft is assembled speed by speed here, and there is no
  continuous model in the package to take a reference from.
"""

import math
from pathlib import Path

import numpy as np

from casflutter.aeroelastic import FlapWingFamily, family_flutter, load_family
from casflutter.data import FamilyFile
from casflutter.truth import GolandParams
# Private helpers, used here because the strip coupling between the rigid body and the wing
# must integrate the very assumed-mode shapes and flap coefficients the wing model is built
# from (no public function exposes them): the bending shapes of the cantilever and
# Theodorsen's flap coefficient T10.
from casflutter.truth._aero import theodorsen_T
from casflutter.truth._goland import _bending_shapes

HERE = Path(__file__).resolve().parent
SPEEDS = np.linspace(120.0, 300.0, 37)
G = 9.81                     # m/s^2
RHO = 0.41                   # kg/m^3, about 7.5 km
STIFF = 1.46                 # EI, GJ scale over the Goland wing's
AILERON = (0.65, 1.0)        # the wing's flap segment, fractions of the semispan

# aircraft (rigid body)
MASS = 5500.0                # kg
IYY = 2.5e4                  # kg m^2
CLA = 4.8                    # 1/rad, aircraft lift-curve slope
CD0, OSW = 0.018, 0.8        # zero-lift drag, Oswald factor
CMA, CMQ, CMAD = -0.75, -14.0, -5.0
CLDE, CMDE = 0.35, -1.1      # elevator
X_QC = -0.10                 # wing quarter chord, m aft of the CG
X_ACC_FWD, X_ACC_AFT = -4.0, 5.0   # fuselage accelerometers, m aft of the CG
L_VANE = 5.0                 # AoA vane, m ahead of the CG
ACT_W, ACT_Z = 2 * math.pi * 25.0, 0.7    # actuators (elevator and aileron)
GYRO_HZ = 30.0               # pitch-gyro filter

CONTROLS = ("elevator", "aileron_sym")
MEASUREMENTS = ("gyro_q", "aoa_vane", "acc_fwd", "acc_aft", "acc_tip_fwd", "acc_tip_aft")
OUTPUT_UNITS = ("rad/s", "rad", "m/s^2", "m/s^2", "m/s^2", "m/s^2")

DESCRIPTION = ("Synthetic symmetric (longitudinal) aircraft: rigid body [u, alpha, q, theta] "
               "of a 5.5 t jet coupled (quasi-steady strips, mean axes) to a Goland-type "
               "flexible wing (5 bending + 5 torsion modes, 1 % damping, Jones' Wagner lags, "
               "EI and GJ x 1.46, rho = 0.41 kg/m^3), elevator and symmetric aileron "
               "(65-100 % span) behind 25 Hz actuators, pitch-rate gyro (30 Hz filter), "
               "AoA vane, fuselage fwd/aft and wing-tip fwd/aft accelerometers; 51 states, "
               "37 airspeeds")
SOURCE = ("problems/aircraft_sym/make_problem.py (synthetic: rigid body + "
          "casflutter.aeroelastic.FlapWingFamily, quasi-steady coupling) sampled at "
          "numpy.linspace(120, 300, 37)")


def wing_family() -> FlapWingFamily:
    """The flexible wing: stiffened Goland-type cantilever at 7.5 km with the aileron.

    Returns
    -------
    FlapWingFamily
        One flap segment (:data:`AILERON`), one gyro at the tip (dropped by the aircraft),
        front and rear accelerometers at the tip.
    """
    p = GolandParams(n_bending=5, n_torsion=5, zeta=0.01, flap_chord=0.2, rho=RHO)
    p = p.with_updates(EI=p.EI * STIFF, GJ=p.GJ * STIFF)
    return FlapWingFamily(params=p, flap_segments=(AILERON,), gyro_stations=(1.0,),
                          accel_stations=(1.0,), accel_chord=(0.15, 0.65),
                          actuator_omega=ACT_W, actuator_zeta=ACT_Z,
                          speed_range=(float(SPEEDS[0]), float(SPEEDS[-1])),
                          name="aircraft_sym_wing")


class SymmetricAircraft:
    """The rigid body, the flexible wing and their coupling (module docstring).

    Attributes
    ----------
    wing : FlapWingFamily
        The flexible wing (:func:`wing_family`).
    """

    def __init__(self):
        self.wing = wing_family()
        p = self.p = self.wing.params
        # the wing's assumed-mode structure (private: the modal shapes Phi and the wing
        # whose strip operator is used below), the same as the wing family's own model
        wing, omega, _, Phi = self.wing._structure
        self.Phi = np.asarray(Phi, float)
        self.N = omega.size
        L, nb, nt = p.semispan, p.n_bending, p.n_torsion
        xg, wg = np.polynomial.legendre.leggauss(200)
        y = 0.5 * L * (xg + 1.0)
        w = 0.5 * L * wg
        phi, _ = _bending_shapes(y, L, nb)
        gam = (2 * np.arange(1, nt + 1) - 1) * np.pi / (2 * L)
        th = np.sin(np.outer(gam, y))
        self.int_phi = phi @ w          # int_0^L phi_k dy
        self.int_th = th @ w            # int_0^L vartheta_s dy
        self.c = p.chord
        self.b = p.b
        self.S = 2 * L * p.chord
        self.AR = (2 * L) ** 2 / self.S
        self.e = (p.ea_chord - 0.25) * p.chord        # quarter chord ahead of the EA
        self.x_ea = X_QC + self.e
        self.x34 = X_QC + 0.5 * p.chord
        self.a_w = p.lift_slope
        self.nb, self.nt = nb, nt
        self.T10 = float(theodorsen_T(1.0 - 2.0 * p.flap_chord)["T10"])

    def matrices(self, V: float):
        """``(A, B, C, D)`` at airspeed ``V``.

        Parameters
        ----------
        V : float
            Airspeed [m/s].

        Returns
        -------
        tuple of ndarray
            51 states, inputs :data:`CONTROLS`, outputs :data:`MEASUREMENTS`.
        """
        p, N = self.p, self.N
        Aw, Bw, _, _ = self.wing.matrices(V)
        nw = Aw.shape[0] - 1                     # drop the wing gyro filter (last state)
        Aw, Bw = Aw[:nw, :nw], Bw[:nw]
        qbar = 0.5 * p.rho * V * V
        S, c = self.S, self.c
        # trim and derivatives
        CL = MASS * G / (qbar * S)
        k_ind = 1.0 / (math.pi * OSW * self.AR)
        CD = CD0 + k_ind * CL * CL
        CDA = 2 * k_ind * CL * CLA
        qS = qbar * S
        Xu, Xa = -qS * 2 * CD / (MASS * V), qS * (CL - CDA) / MASS
        Zu, Za = -qS * 2 * CL / (MASS * V), -qS * (CLA + CD) / MASS
        Zde = -qS * CLDE / MASS
        Ma, Mq = qS * c * CMA / IYY, qS * c * c * CMQ / (2 * V * IYY)
        Mad = qS * c * c * CMAD / (2 * V * IYY)
        Mde = qS * c * CMDE / IYY
        # state layout: rigid [u, alpha, q, theta], wing, elevator [de, de_dot], gyro
        iw = slice(4, 4 + nw)
        ie = 4 + nw
        ig = ie + 2
        nx = ig + 1
        A = np.zeros((nx, nx))
        B = np.zeros((nx, len(CONTROLS)))
        iu, ia, iq, it = 0, 1, 2, 3
        # wing block (its states: modal coordinates, velocities, lags, aileron)
        A[iw, iw] = Aw
        B[iw, 1:] = Bw
        w0 = 4
        ieta, ietad = slice(w0, w0 + N), slice(w0 + N, w0 + 2 * N)
        ng = N + 1
        ibeta = w0 + 2 * N + 2 * ng                          # the aileron angle
        # rigid body
        A[iu, iu], A[iu, ia], A[iu, it] = Xu, Xa, -G
        A[ia, iu], A[ia, ia], A[ia, iq] = Zu / V, Za / V, 1.0
        A[ia, ie] = Zde / V
        A[iq, ia], A[iq, iq] = Ma, Mq
        A[iq, ie] = Mde
        A[it, iq] = 1.0
        # flexible wing and aileron -> rigid body: quasi-steady strip lift (both halves)
        Pb, Pt = self.Phi[:self.nb], self.Phi[self.nb:]      # assumed coords per mode
        kl = 2 * qbar * c * self.a_w                          # lift per unit "angle" x span
        dL = np.zeros(nx)
        dL[ieta] = kl * (self.int_th @ Pt)
        dL[ietad] = kl / V * (self.int_phi @ Pb + self.b * (0.5 - p.a) * (self.int_th @ Pt))
        ya, yb = AILERON
        dL[ibeta] = 2 * qbar * c * 2 * self.T10 * (yb - ya) * p.semispan
        A[ia] += -dL / (MASS * V)
        A[iq] += -X_QC * dL / IYY
        # alpha-dot term of the pitching moment
        A[iq] += Mad * A[ia]
        # rigid body -> wing: strips see alpha + x34 q / V; lift at the quarter chord,
        # generalised onto the modes through the wing's (private) strip operator at V
        mL = p.mass * p.semispan
        f = np.concatenate([-self.int_phi, self.e * self.int_th]) * qbar * c * self.a_w
        strips = self.wing._structure[0]
        wing_am = strips.aero_matrices(strips.speed_index(V))
        Minv = np.linalg.inv(np.eye(N) - self.Phi.T @ wing_am.Mx @ self.Phi)
        gq = Minv @ (self.Phi.T @ f) / mL                     # modal accel per rad of alpha
        A[ietad, ia] += gq
        A[ietad, iq] += gq * self.x34 / V
        # elevator actuator
        A[ie, ie + 1] = 1.0
        A[ie + 1, ie], A[ie + 1, ie + 1] = -ACT_W ** 2, -2 * ACT_Z * ACT_W
        B[ie + 1, 0] = ACT_W ** 2
        # pitch-rate gyro filter
        tau = 1.0 / (2 * math.pi * GYRO_HZ)
        A[ig, iq], A[ig, ig] = 1.0 / tau, -1.0 / tau
        # outputs
        C = np.zeros((len(MEASUREMENTS), nx))
        D = np.zeros((len(MEASUREMENTS), len(CONTROLS)))
        C[0, ig] = 1.0
        C[1, ia], C[1, iq] = 1.0, -L_VANE / V

        def acc(x_aft, flex_row=None):
            """Body-z acceleration (positive down) x_aft aft of the CG, plus the wing's
            ``h + x theta`` row at the tip."""
            row = V * (A[ia] - np.eye(nx)[iq]) + x_aft * A[iq]
            drow = V * B[ia] + x_aft * B[iq]
            if flex_row is not None:
                row = row + flex_row @ A[ietad]
                drow = drow + flex_row @ B[ietad]
            return row, drow

        # the wing's own (private) accelerometer rows: h + x theta at the tip, front, rear
        _, acc_rows = self.wing._sensor_rows
        C[2], D[2] = acc(X_ACC_FWD)
        C[3], D[3] = acc(X_ACC_AFT)
        for r, xc in enumerate((0.15, 0.65)):
            C[4 + r], D[4 + r] = acc(self.x_ea + (xc - p.ea_chord) * c, acc_rows[r])
        return A, B, C, D


def main() -> None:
    """Sample the aircraft, find the grid's open-loop flutter and write the files."""
    aircraft = SymmetricAircraft()
    mats = [aircraft.matrices(V) for V in SPEEDS]
    A, B, C, D = (np.array([mt[i] for mt in mats]) for i in range(4))
    fields = dict(speeds=SPEEDS, A=A, B=B, C=C, D=D, speed_unit="m/s", time_unit="s",
                  feedback="negative", name="aircraft_sym", description=DESCRIPTION,
                  source=SOURCE, input_names=CONTROLS, output_names=MEASUREMENTS,
                  controls=CONTROLS, measurements=MEASUREMENTS,
                  input_units=("rad",) * len(CONTROLS), output_units=OUTPUT_UNITS)
    # the reference: the flutter of the grid itself, as `casflutter flutter` finds it
    fl = family_flutter(load_family(FamilyFile(**fields)))
    reference = {"flutter": {
        "speed": round(fl.Vf, 6), "omega_rad_s": round(fl.omega_f, 6),
        "freq_hz": round(fl.frequency_hz, 6),
        "route": "the grid (casflutter flutter): casflutter.aeroelastic.family_flutter on "
                 "the 37 models, linear between them; no continuous-model reference (the "
                 "aircraft is assembled speed by speed in make_problem.py, not a family of "
                 "the package)"}}
    FamilyFile(**fields, reference=reference).write(HERE / "problem.toml",
                                                    data_file="models.npz")
    print(f"wrote {HERE}: flutter of the grid {fl.Vf:.6f} m/s, {fl.omega_f:.6f} rad/s")


if __name__ == "__main__":
    main()
