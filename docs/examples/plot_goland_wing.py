"""
The Goland wing: flutter of a cantilever wing and the ROM route
===============================================================

The Goland (1945) wing: a uniform cantilever (semi-span 6.096 m, chord 1.829 m) with
assumed bending and torsion modes and strip-theory aerodynamics with Jones' two-lag Wagner
function.  The speed index is ``V = U/(b ω_ref)`` with ``ω_ref = (π/2L) sqrt(GJ/I)``
(87.1 rad/s), time is in seconds.  The truth's flutter speed and frequency are compared with
the published values stored beside the problem (``problems/goland/problem.toml``), then the
paper's ROM route (records at one speed, HWL ROM, Σf, ΣAE(V) with the ``V²`` scaling) runs on
it.
"""

import os

import matplotlib.pyplot as plt
import numpy as np

from casflutter.aeroelastic import find_flutter
from casflutter.pipeline import config_path, load_config, run
from casflutter.report import plot_vg_vf
from casflutter.truth import load_problem, problem_definition

QUICK = os.environ.get("CASFLUTTER_DOCS_QUICK") == "1"   # set by `make docs`

wing = load_problem("goland")
structure = wing.modal_structure()
definition = problem_definition("goland")
p = definition["parameters"]
b = p["chord"] / 2
omega_ref = np.pi / (2 * p["semispan"]) * np.sqrt(p["GJ"] / p["inertia"])
print("in-vacuo frequencies [rad/s]:", np.round(structure.omega[:4], 1),
      "reference", definition["reference"]["in_vacuo"]["frequencies"])

result = find_flutter(wing.state_matrix, (0.2, 3.0), n_grid=61 if QUICK else 201,
                      omega=structure.omega)
U_f = result.Vf * b * omega_ref
ref = definition["reference"]["flutter"]
print(f"flutter: V_f = {result.Vf:.4f}, U_f = {U_f:.1f} m/s (reference {ref['airspeed']} m/s), "
      f"omega_f = {result.omega_f:.1f} rad/s (reference {ref['frequency']} rad/s), "
      f"mode {structure.mode_names[result.flutter_mode]!r}")

# %%
# V–g and V–f diagrams of the two lowest modes, first bending and first torsion, whose
# frequencies approach each other until the torsion branch goes unstable (the branches of
# the aerodynamic lag states and of the stiffer modes are left out).
lam = result.tracking.eigenvalues
low = [k for k in result.tracking.upper_branches()
       if 0.5 * structure.omega[0] < np.mean(lam[:, k].imag) < 1.3 * structure.omega[1]]
fig = plot_vg_vf(result, branches=low, hz=False, mode_names=structure.mode_names,
                 speed_scale=b * omega_ref, speed_unit="m/s", speed_label="airspeed U [m/s]",
                 index_label=r"speed index $V = U/(b\,\omega_{ref})$")

# %%
# The ROM route.  Records of the truth are taken at :math:`V_0`; the single-speed ROM with the
# :math:`V^2` scaling over-predicts the flutter speed, and the truth with its aerodynamics frozen
# at :math:`V_0` shows that this error is the scaling's, not the identification's.  A parametric
# ROM (ROMs at several speeds, interpolated in V) follows the truth.  The route is the
# configuration ``problems/goland/flutter.toml`` of the study run (``casflutter flutter``).
config = load_config(config_path("goland", "flutter"), updates={
    "parametric.n_speeds": 3 if QUICK else 7, "data.duration": 1.0 if QUICK else 2.0,
    "flutter.n_grid": 61 if QUICK else 201})
route = run(config, quiet=True, write=False)
models = (("truth", route.flutter_truth), (f"ROM at V0 = {config.data.V0}", route.flutter),
          ("frozen-aero truth", route.flutter_frozen),
          ("parametric ROM", route.parametric.flutter))
for name, res in models:
    print(f"{name:>20}: V_f = {res.Vf:.4f} ({res.Vf * b * omega_ref:6.1f} m/s), "
          f"omega_f = {res.omega_f:.1f} rad/s")
print(route.explanation())

fig, ax = plt.subplots(figsize=(6.5, 3.5))
for (label, res), style in zip(models, ("k-", "C1--", "C0:", "C2-.")):
    tr = res.tracking
    ax.plot(tr.V, tr.damping_ratio[:, res.flutter.branch], style, label=label)
ax.axhline(0.0, color="0.6", lw=0.8)
ax.set_ylim(-0.1, 0.1)
ax.set_xlabel("speed index V")
ax.set_ylabel("damping ratio of the flutter branch")
ax.legend(fontsize=8)
fig.tight_layout()
