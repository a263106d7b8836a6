"""
Typical-section flutter: V–g and V–f plots (paper §III.B)
=========================================================

The Hodges & Pierce HP-1 pitch–plunge typical section (problem 5.5: ``a = -0.2``,
``e = -0.1``, ``mu = 20``, ``r² = 0.24``, ``sigma = 0.4``) with unsteady aerodynamics in
R. T. Jones' two-lag form.  Its linear state matrix in the speed index ``V = U/(b ω_θ)`` is
tracked over ``V`` by eigenvector continuity; flutter is the Hopf point where a branch crosses
the imaginary axis (paper §III.B), divergence the speed where a real eigenvalue passes
through zero.  The speeds are compared with the published values stored beside the problem
(``problems/typical_section/problem.toml``).

Then the paper's ROM route is run on the same truth: chirp records at one speed :math:`V_0`, an
identified ROM, Σf (eq. 5) and ΣAE(V) with the :math:`V^2` scaling of eq. 8, next to the truth.
"""

import os

import matplotlib.pyplot as plt

from casflutter.aeroelastic import find_flutter
from casflutter.pipeline import config_path, load_config, run
from casflutter.report import plot_root_locus, plot_vg_vf
from casflutter.truth import load_problem, problem_definition

QUICK = os.environ.get("CASFLUTTER_DOCS_QUICK") == "1"   # set by `make docs`

truth = load_problem("typical_section")
structure = truth.modal_structure()
print(truth.params)
print("modes:", structure.mode_names, "natural frequencies:", structure.omega)

result = find_flutter(truth.state_matrix, (0.02, 4.0), n_grid=41 if QUICK else 161,
                      omega=structure.omega)
ref = problem_definition("typical_section")["reference"]
print(f"flutter:    V_f = {result.Vf:.4f} (Jones reference {ref['jones']['flutter_speed']}), "
      f"omega_f/omega_theta = {result.omega_f:.4f} "
      f"(reference {ref['jones']['flutter_frequency_ratio']})")
print(f"            mode {structure.mode_names[result.flutter_mode]!r}")
print(f"divergence: V_d = {result.divergence.V:.4f} (reference {ref['divergence']['speed']})")

# %%
# The V–g and V–f diagrams: the damping ratio of the pitch branch falls through zero at
# :math:`V_f`, where its frequency has nearly merged with the plunge branch.
fig = plot_vg_vf(result, hz=False, frequency_unit="Ω/ω_θ", mode_names=structure.mode_names,
                 speed_label=r"speed index $V = U/(b\,\omega_\theta)$")

# %%
# The same branches in the complex plane, coloured by the speed index.
fig = plot_root_locus(result)

# %%
# The ROM route (the paper's method on this truth).  The ROM is identified at a single
# speed :math:`V_0`; the :math:`V^2` scaling of ΣAE then freezes the aerodynamic time scale at :math:`V_0`
# (reduced frequency and lag rates), which is the error the explanation quantifies.  A
# parametric ROM identified at several speeds and interpolated in :math:`V` removes it.  The
# route is the configuration ``problems/typical_section/flutter.toml`` of the study run.
config = load_config(config_path("typical_section", "flutter"), updates={
    "parametric.n_speeds": 3 if QUICK else 7, "flutter.n_grid": 61 if QUICK else 201})
route = run(config, quiet=True, write=False)
models = (("truth", route.flutter_truth), (f"ROM at V0 = {config.data.V0}", route.flutter),
          ("parametric ROM", route.parametric.flutter))
for name, res in models:
    print(f"{name:>20}: V_f = {res.Vf:.4f}, omega_f = {res.omega_f:.4f}")
print(route.explanation())

fig, axes = plt.subplots(2, 1, sharex=True, figsize=(6.5, 5.5))
for (label, res), style in zip(models, ("k-", "C1--", "C2:")):
    tr = res.tracking
    b = res.flutter.branch
    axes[0].plot(tr.V, tr.damping_ratio[:, b], style, label=label)
    axes[1].plot(tr.V, abs(tr.eigenvalues[:, b].imag), style)
axes[0].axhline(0.0, color="0.6", lw=0.8)
axes[0].set_ylabel("damping ratio of the flutter branch")
axes[1].set_ylabel(r"frequency / $\omega_\theta$")
axes[1].set_xlabel("speed index V")
axes[0].legend(fontsize=8)
fig.tight_layout()
