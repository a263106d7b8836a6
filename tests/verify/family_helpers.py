"""Plant families for the tests of :func:`casflutter.verify.verify_family`: small seeded
gridded families that flutter, a polynomial family of degree 2 with breakpoints, the seed
wing's truth loop sampled on a grid, and an independent closed-loop map (python-control's
``feedback``)."""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np

from casflutter.aeroelastic import FamilySignals, GriddedFamily, PlantFamily, TruthLoop
from casflutter.truth import SeedWing

#: the test witnesses (tests/witnesses/README.md)
WITNESSES = Path(__file__).resolve().parents[1] / "witnesses"
SERVO = 251.3     # rad/s: the seed wing's 40 Hz servo (run.toml: controller.flap_rate_bandwidth)


def coupled_modes(rng: np.random.Generator, n_modes: int, n_in: int, n_out: int, *,
                  with_d: bool) -> tuple:
    """``(A0, A1, A2, B, C, D, B1, C1, D1)`` of a structure whose aerodynamic coupling grows with
    q (∝ V², normalised so that q = 1 near the top of the range): lightly damped modes, a
    circulatory coupling between two of them that makes them flutter."""
    om = np.sort(rng.uniform(1.0, 6.0, n_modes))
    n = 2 * n_modes
    A0 = np.zeros((n, n))
    A0[:n_modes, n_modes:] = np.eye(n_modes)
    A0[n_modes:, :n_modes] = -np.diag(om ** 2)
    A0[n_modes:, n_modes:] = -np.diag(2 * 0.03 * om)
    A2 = np.zeros((n, n))
    Ka = 0.2 * rng.standard_normal((n_modes, n_modes))
    a = 0.6 * (om[1] ** 2 - om[0] ** 2)
    Ka[0, 1] += a
    Ka[1, 0] -= a
    A2[n_modes:, :n_modes] = Ka
    A1 = np.zeros((n, n))
    A1[n_modes:, n_modes:] = -0.05 * np.diag(om) + 0.02 * rng.standard_normal((n_modes,) * 2)
    B = np.zeros((n, n_in))
    B[n_modes:] = rng.standard_normal((n_modes, n_in))
    C = rng.standard_normal((n_out, n))
    D = 0.3 * rng.standard_normal((n_out, n_in)) if with_d else np.zeros((n_out, n_in))
    B1 = np.zeros((n, n_in))
    B1[n_modes:] = 0.3 * rng.standard_normal((n_modes, n_in))
    C1 = 0.2 * rng.standard_normal((n_out, n))
    D1 = 0.1 * rng.standard_normal((n_out, n_in)) if with_d else np.zeros((n_out, n_in))
    return A0, A1, A2, B, C, D, B1, C1, D1


def random_family(seed: int, *, n_modes: int = 4, n_in: int = 2, n_out: int = 2,
                  n_speeds: int = 9, with_d: bool = False, feedback: str = "negative"
                  ) -> GriddedFamily:
    """A small gridded family over q in [0.1, 1.5] (speeds = q) that flutters inside it."""
    rng = np.random.default_rng(seed)
    A0, A1, A2, B, C, D, B1, C1, D1 = coupled_modes(rng, n_modes, n_in, n_out, with_d=with_d)
    speeds = np.linspace(0.1, 1.5, n_speeds)
    As = [A0 + q * A1 + q * q * A2 for q in speeds]
    Bs = [B + q * B1 for q in speeds]
    Cs = [C + q * C1 for q in speeds]
    Ds = [D + q * D1 for q in speeds]
    sig = FamilySignals([f"u{i}" for i in range(n_in)], [f"y{j}" for j in range(n_out)])
    return GriddedFamily(speeds, As, Bs, Cs, Ds, sig, speed_unit="q", feedback=feedback,
                         name=f"random family {seed}")


class QuadraticFamily(PlantFamily):
    """``A0 + V A1 + V² A2`` (B, C, D affine in V), declared of degree 2 with breakpoints
    (a family of degree 2 on pieces, as a speed-following ROM would be)."""

    speed_degree = 2
    feedback = "negative"
    name = "quadratic family"

    def __init__(self, seed: int, *, with_d: bool = False, breakpoints=(0.6, 1.0)):
        rng = np.random.default_rng(seed)
        self.parts = coupled_modes(rng, 3, 1, 2, with_d=with_d)
        self.speed_range = (0.1, 1.5)
        self.breakpoints = tuple(breakpoints)
        self._sig = FamilySignals(["u"], ["y0", "y1"])

    @property
    def signals(self) -> FamilySignals:
        """One input, two outputs."""
        return self._sig

    def plant(self, V: float) -> control.StateSpace:
        """The plant at V."""
        A0, A1, A2, B, C, D, B1, C1, D1 = self.parts
        return control.ss(A0 + V * A1 + V * V * A2, B + V * B1, C + V * C1, D + V * D1,
                          inputs=["u"], outputs=["y0", "y1"])


def seed_wing_grid(speeds) -> GriddedFamily:
    """The seed wing's truth loop with its servo sampled at ``speeds`` (a gridded family)."""
    fam = TruthLoop(SeedWing(), SERVO)
    Ps = [fam.plant(float(v)) for v in speeds]
    return GriddedFamily(speeds, [P.A for P in Ps], [P.B for P in Ps], [P.C for P in Ps],
                         [P.D for P in Ps], fam.signals, speed_unit="speed index",
                         time_unit=fam.time_unit, feedback="positive",
                         name="seed wing truth grid")


def abscissa(family, K, V, controls=None, measurements=None, sign=None) -> float:
    """Spectral abscissa of the loop closed by python-control's ``feedback`` (independent of
    the verification layer's closed-loop map)."""
    sign = family.feedback_sign if sign is None else sign
    P = family.control_plant(V, controls, measurements)
    return float(np.max(control.feedback(P, K, sign=sign).poles().real))


def small_controller(rng: np.random.Generator, n_out: int, n_in: int, order: int, *,
                     gain: float, with_d: bool) -> control.StateSpace:
    """A stable random controller of small gain (measurements ``n_in`` → controls ``n_out``)."""
    A = -np.diag(rng.uniform(0.5, 3.0, order)) + 0.3 * rng.standard_normal((order, order))
    A -= (max(0.0, np.max(np.linalg.eigvals(A).real)) + 0.3) * np.eye(order)
    B = gain * rng.standard_normal((order, n_in))
    C = rng.standard_normal((n_out, order))
    D = gain * rng.standard_normal((n_out, n_in)) if with_d else np.zeros((n_out, n_in))
    return control.ss(A, B, C, D)
