"""
Fixed-order H∞ synthesis on a COMPleib plant (paper §III.C)
===========================================================

The flutter controller of the paper is a fixed-order H∞ controller found by nonsmooth local
optimisation (HIFOO).  :func:`casflutter.design.synthesize` solves the same problem as a
sequence of CasADi/Ipopt NLPs (a stabilisation phase, then a minimax phase over the peaks of
the closed-loop frequency response, with an epigraph variable).  Here it runs on the COMPleib
plant AC4 (Leibfritz 2004: 4 states, open-loop unstable, 2 measurements, 1 control) for
controller orders 0, 1 and 2.  Every controller is re-checked by independent code
(:func:`casflutter.verify.hinf_norm`, exact norm by the Hamiltonian/SLICOT algorithm) and
compared with the full-order optimum: python-control's ``control.hinfsyn`` (SLICOT
``SB10AD``, γ-iteration to the optimum) gives 0.55729; the LMI value stored with the plant,
0.55919, is a slightly inaccurate solve of the same bound.
"""

import os

import control
import matplotlib.pyplot as plt
import numpy as np

from casflutter.design import load_compleib, synthesize
from casflutter.pipeline import default_config_path
from casflutter.verify import hinf_norm, lft_closed_loop

QUICK = os.environ.get("CASFLUTTER_DOCS_QUICK") == "1"   # set by `make docs`

compleib = default_config_path().parents[1] / "compleib"   # the shipped problems/ folder
P, nmeas, ncon, info = load_compleib(compleib / "AC4.json")
print(f"{info['name']}: {P.nstates} states, {nmeas} measurements, {ncon} control; "
      f"open-loop poles {np.round(np.linalg.eigvals(P.A), 3)}")
_, _, gamma_full, _ = control.hinfsyn(P, nmeas, ncon)   # full order (4 states)
print(f"full-order optimum: gamma = {gamma_full:.5f} (hinfsyn), "
      f"{info['gamma_full_order_lmi']} (LMI value in the problem file)")

orders = [0, 1, 2]
results = {}
for order in orders:
    res = synthesize(P, nmeas, ncon, order, starts=2 if QUICK else 4, seed=0)
    check = hinf_norm(lft_closed_loop(P, res.controller, nmeas, ncon))
    results[order] = res
    print(f"order {order}: gamma = {res.gamma:.5f} ({100 * (res.gamma / gamma_full - 1):+.3f} %) (independent check {check.gamma:.5f}, "
          f"peak at {check.omega_peak:.3g} rad/s), closed-loop spectral abscissa "
          f"{res.spectral_abscissa:.3f}, {res.wall_time:.1f} s, converged={res.converged}")

# %%
# The verified γ against the controller order, and the largest singular value of the
# closed loop from :math:`w` to :math:`z` for each controller.
fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(9, 3.5))
ax0.plot(orders, [results[k].gamma for k in orders], "o-", label="fixed order")
ax0.axhline(gamma_full, color="C3", ls="--", label="full order (hinfsyn)")
ax0.set_xticks(orders)
ax0.set_xlabel("controller order")
ax0.set_ylabel(r"verified $\|T_{wz}\|_\infty$")
ax0.legend(fontsize=8)
omega = np.logspace(-2, 3, 400)
for k in orders:
    cl = lft_closed_loop(P, results[k].controller, nmeas, ncon)
    sv = [np.linalg.svd(cl(1j * w), compute_uv=False)[0] for w in omega]
    ax1.loglog(omega, sv, label=f"order {k}")
ax1.set_xlabel(r"$\omega$ [rad/s]")
ax1.set_ylabel(r"$\sigma_{max}(T_{wz}(j\omega))$")
ax1.legend(fontsize=8)
fig.tight_layout()
