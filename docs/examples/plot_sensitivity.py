r"""
Flutter-speed sensitivities (``casflutter sensitivity``)
========================================================

How much does the flutter speed move when a parameter of the problem changes?
:func:`casflutter.study.flutter_sensitivity` answers at the flutter point itself, by
first-order eigenvalue perturbation: at the crossing ``Re λ(V_f, p) = 0``, so
``dV_f/dp = -Re(∂λ/∂p) / Re(∂λ/∂V)``, with ``∂λ/∂x = wᴴ (∂A/∂x) v / (wᴴ v)`` from the left
and right eigenvectors of the critical eigenvalue of the state matrix ΣAE(V) (paper §III.B).
Each derivative is checked against central finite differences of the re-computed flutter
speed (:func:`casflutter.study.flutter_speed_fd`).

The configuration is ``problems/studies/sensitivity_hp1.toml``: the HP-1 typical section with
1 % structural damping.  The table is ranked by the normalised sensitivity
:math:`(p / V_f)\, \mathrm{d}V_f/\mathrm{d}p` (per cent change of :math:`V_f` per per cent change of :math:`p`).
"""

import os
import tomllib

import matplotlib.pyplot as plt
import numpy as np

from casflutter.pipeline import default_config_path
from casflutter.study import flutter_sensitivity, flutter_speed_fd

QUICK = os.environ.get("CASFLUTTER_DOCS_QUICK") == "1"   # set by `make docs`

path = default_config_path().parents[1] / "studies" / "sensitivity_hp1.toml"
with open(path, "rb") as fh:
    config = tomllib.load(fh)
sec, params = config["sensitivity"], config["params"]
V_range = (sec["V_min"], sec["V_max"])
n_grid = 41 if QUICK else sec["n_grid"]

res = flutter_sensitivity(sec["problem"], sec["parameters"], params=params, V_range=V_range,
                          n_grid=n_grid, rel_step=sec["rel_step"])
print(res.table())

# %%
# The check against finite differences of the flutter speed.
print(f"{'parameter':<12} {'dVf/dp':>14} {'finite diff.':>14} {'rel. diff.':>11}")
fd = {}
for s in res.sensitivities:
    fd[s.name] = flutter_speed_fd(sec["problem"], s.name, params=params, V_range=V_range,
                                  n_grid=n_grid)
    rel = abs(s.dVf_dp - fd[s.name]) / max(abs(fd[s.name]), 1e-12)
    print(f"{s.name:<12} {s.dVf_dp:>+14.7g} {fd[s.name]:>+14.7g} {rel:>11.1e}")

# %%
# The ranked normalised sensitivities.
ranked = res.ranked()
fig, ax = plt.subplots(figsize=(6, 3.5))
y = np.arange(len(ranked))[::-1]
ax.barh(y, [s.normalized for s in ranked], color=["C3" if s.normalized < 0 else "C0"
                                                  for s in ranked])
ax.set_yticks(y, [f"{s.name} ({s.normalized_by})" for s in ranked])
ax.axvline(0.0, color="k", lw=0.8)
ax.set_xlabel(r"normalised sensitivity $(p/V_f)\,\mathrm{d}V_f/\mathrm{d}p$")
ax.set_title(f"HP-1, 1 % damping: V_f = {res.Vf:.4f}", fontsize=9)
fig.tight_layout()
