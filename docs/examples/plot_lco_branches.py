"""
LCO branches: bifurcation diagrams from the flutter point
=========================================================

Above (or below) the flutter speed a nonlinear aeroelastic system settles on a limit-cycle
oscillation (LCO).  Whether that LCO grows gently from zero at the flutter speed
(*supercritical* Hopf point) or jumps in at a finite amplitude and persists below the
flutter speed (*subcritical*, with a fold of cycles and hysteresis) is the first question an
aeroelastician asks of a nonlinear model.  :func:`casflutter.lco.lco_branch` answers it:
periodic orbits by orthogonal collocation, continued in the speed by pseudo-arclength from
the Hopf point, their stability from Floquet multipliers, and the criticality from the first
Lyapunov coefficient, cross-checked by the direction in which the branch leaves.

Three systems:

1. the Hodges & Pierce typical section (Jones' Wagner lags) with a hardening cubic pitch
   spring, beside a one-harmonic balance of the same equations;
2. the Texas A&M NATA rig section, read from ``problems/nata/problem.toml``;
3. the paper's seed wing (saturating lift, leading-edge suction), and the sampled-data loop
   of its HWL ROM, whose LCO is an invariant circle of a discrete map.
"""

import os

import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import fsolve

from casflutter.ident import HWLModel
from casflutter.lco import LCOSettings, lco_branch, rom_lco_branch
from casflutter.report import plot_bifurcation, plot_bifurcation_pair
from casflutter.truth import TypicalSection, TypicalSectionParams, load_problem
from casflutter._resources import problems_dir

QUICK = os.environ.get("CASFLUTTER_DOCS_QUICK") == "1"   # set by `make docs`
settings = LCOSettings()                                  # 120 points at most per branch
wing_settings = LCOSettings(max_points=12 if QUICK else 120)

# %%
# 1. Typical section with a cubic pitch spring
# --------------------------------------------
# The pitch spring moment is ``r² θ (1 + 3 θ²)`` (``kappa2 = 3``).  The Hopf point is the
# linear flutter speed ``V_F = 2.170`` of the Jones model; the first Lyapunov coefficient
# is negative, so the LCO grows from zero above it and is stable.
p = TypicalSectionParams(kappa2=3.0)
ts = lco_branch(TypicalSection(p), (1.5, 2.8), settings)
h = ts.hopf
print(f"Hopf point V = {h.V:.4f}, Omega/omega_theta = {h.omega:.4f}, l1 = {h.lyapunov:.4g} "
      f"({h.kind}; branch leaves towards {'higher' if h.branch_direction > 0 else 'lower'} V)")


def jones_C(k):
    ik = 1j * k
    return 1 - 0.165 * ik / (ik + 0.0455) - 0.335 * ik / (ik + 0.3)


def harmonic_balance(Theta, V0, w0):
    """One harmonic: theta^3 -> (3/4) Theta^2 theta, then Theodorsen's flutter determinant."""
    a, mu, xt = p.a, p.mu, p.e - p.a
    M = np.array([[1.0, xt], [xt, p.r2]])
    K = np.diag([p.sigma ** 2, p.r2 * (1 + 0.75 * p.kappa2 * Theta ** 2)])

    def forces(V, w, xi, th):
        s = 1j * w
        Q = s * xi + V * th + (0.5 - a) * s * th
        C = jones_C(w / V)
        L = (s * s * xi + V * s * th - a * s * s * th) / mu + 2 / mu * V * C * Q
        Mo = (a * s * s * xi - V * (0.5 - a) * s * th - (0.125 + a * a) * s * s * th) / mu \
            + 2 / mu * V * (a + 0.5) * C * Q
        return np.array([-L, Mo])

    def res(z):
        F = np.array([forces(z[0], z[1], 1.0, 0.0), forces(z[0], z[1], 0.0, 1.0)]).T
        d = np.linalg.det(-z[1] ** 2 * M + K - F)
        return [d.real, d.imag]

    return fsolve(res, [V0, w0])


pts = ts.points[::max(1, len(ts.points) // 8)]
hb = [harmonic_balance(q.amplitude["theta"], q.V, 2 * np.pi * q.freq_hz) for q in pts]
fig = plot_bifurcation(ts, ["theta"], hb_points={
    "theta": ([v for v, _ in hb], [q.amplitude["theta"] for q in pts])})

# %%
# 2. The NATA rig section from its TOML file
# ------------------------------------------
# Quasi-steady aerodynamics and the rig's polynomial pitch spring.  Here the Hopf point is
# *subcritical*: the branch leaves towards lower speeds, unstable, turns at a fold of cycles
# and comes back stable at a large amplitude.  Between the fold and the flutter speed the
# rig is bistable -- a disturbance large enough throws it onto the LCO, which then persists
# down to the fold speed.
nata = lco_branch(load_problem("nata"), None, settings)
print(f"NATA: {nata.kind} flutter at {nata.speed(nata.hopf.V):.3f} m/s, "
      f"fold at {', '.join(f'{nata.speed(f.V):.3f} m/s' for f in nata.folds) or 'none found'}")
fig = plot_bifurcation(nata)

# %%
# 3. The seed wing: truth and ROM loop
# ------------------------------------
# The truth flutters on the lateral-mode branch; its lift saturates, which bounds a stable
# LCO (supercritical).  The sampled-data loop of the HWL ROM identified by ``casflutter run``
# (saved in ``problems/seed_wing_rom``) is a discrete map; its LCO is an invariant circle
# whose rotation number gives the frequency.  The ROM is identified from small-amplitude
# chirps, so its LCO amplitude is not expected to match the truth's.
truth = load_problem("seed_wing")
wing = lco_branch(truth, (0.8, 1.5), wing_settings)
ms = truth.modal_structure()
rom = HWLModel.load(problems_dir() / "seed_wing_rom" / "rom.npz")
structure = ms.with_sensors(kind="displacement")
rom_branch = rom_lco_branch(rom, structure, (0.8, 1.5), LCOSettings(max_points=10 if QUICK else 60),
                            mode_names=ms.mode_names, sensor_names=ms.sensor_names,
                            problem="seed wing ROM loop", speed_scale=truth.airspeed(1.0),
                            speed_unit="m/s")
for br, name in ((wing, "truth"), (rom_branch, "ROM loop")):
    print(f"{name:>9}: {br.kind} at {br.speed(br.hopf.V):.2f} m/s, {br.hopf.freq_hz:.2f} Hz")
fig = plot_bifurcation_pair(wing, rom_branch, ["lateral 1", "Acc2 (lateral)"])
plt.show()
