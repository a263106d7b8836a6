"""
How many controller states does a plant need? A certified bound (HE6)
=====================================================================

COMPleib's HE6 (a helicopter H∞ problem, Skogestad & Postlethwaite §12.2.3: 20 states,
4 controls, 6 measurements) has four tracking errors weighted almost like integrators
(poles at −0.005 to −0.012 rad/s) and a control weight that grows with frequency.  The
full-order optimum is γ* = 2.388, but at order 3 the synthesis stops near γ = 10.  Is that
the optimiser, or the order?

An order-3 controller has fewer states than the plant has controls, so some real direction
``q`` of the controls has no state behind it: ``qᵀK(s) = qᵀDk`` at every frequency.  That
static combination must provide the integral action the low-frequency weights ask for
(ω = 0) and pay for the same gain where the control weight sees it (ω = ∞).
:func:`casflutter.design.static_direction_bound` turns this into two quadratic inequalities
in ``(q, qᵀDk)`` and proves them incompatible below a γ with an S-procedure multiplier: a
certificate, found by bisection without local searches, valid for *every* controller with
fewer than 4 states.  With ``exact=True`` the multiplier is re-checked in exact rational
arithmetic on the plant's numbers, so the bound is a proof.
"""

import os

import control
import matplotlib.pyplot as plt
import numpy as np

from casflutter.design import load_compleib, static_direction_bound, synthesize
from casflutter.pipeline import default_config_path
from casflutter.verify import hinf_norm, lft_closed_loop

QUICK = os.environ.get("CASFLUTTER_DOCS_QUICK") == "1"   # set by `make docs`

problems = default_config_path().parents[1]   # the shipped problems/ folder
P, nmeas, ncon, info = load_compleib(problems / "compleib_large" / "HE6.json")
gstar = info["gamma_full_order_lmi"]
cert = static_direction_bound(P, nmeas, ncon, exact=True)
print(f"{info['name']}: {P.nstates} states, {ncon} controls, {nmeas} measurements; "
      f"full-order optimum gamma* = {gstar}")
print(f"proven (exact arithmetic: {cert.exact}): every controller of order <= {cert.order} "
      f"has gamma >= {cert.value:.4f} (= {cert.value / gstar:.2f} gamma*)")
for k in range(cert.order):      # lower orders leave more static directions
    low = static_direction_bound(P, nmeas, ncon, order=k, exact=True)
    print(f"  order <= {k} ({low.directions} static directions): gamma >= {low.value:.4f}")

# %%
# The synthesis at order 3 (and, for contrast, the full-order H∞ controller of
# python-control), both checked by the independent verification layer.
res = synthesize(P, nmeas, ncon, 3, starts=1 if QUICK else 3, seed=0)
cl3 = lft_closed_loop(P, res.controller, nmeas, ncon)
g3 = hinf_norm(cl3)
K_full, cl_full, _, _ = control.hinfsyn(P, nmeas, ncon)
g_full = hinf_norm(cl_full)
print(f"order 3: verified gamma = {g3.gamma:.4f} ({g3.gamma / cert.value:.3f} x the certificate), "
      f"peak at {g3.omega_peak:.3g} rad/s")
print(f"full order ({K_full.nstates} states, hinfsyn): verified gamma = {g_full.gamma:.4f}")

# %%
# The largest singular value of the closed loop over frequency.  The order-3 loop sits on
# the certificate at both ends the certificate ties together: at low frequency, where its
# static control direction cannot integrate, and at high frequency, where the control weight
# sees that direction's gain.  The full-order controller has a state for every direction and
# stays at γ* (its curve lies on the γ* line).
omega = np.logspace(-4, 3, 300)
fig, ax = plt.subplots(figsize=(7, 3.6))
for cl, label in ((cl3, "order 3 (synthesis)"), (cl_full, "full order (hinfsyn)")):
    sv = [np.linalg.svd(cl(1j * w), compute_uv=False)[0] for w in omega]
    ax.loglog(omega, sv, label=label)
ax.axhline(cert.value, color="C3", ls="--", label="proven bound, orders 0-3")
ax.axhline(1.5 * gstar, color="0.5", ls=":", label=r"1.5 $\gamma^*$")
ax.axhline(gstar, color="0.5", ls="-.", lw=0.8, label=r"$\gamma^*$ (LMI, full order)")
ax.set_xlabel(r"$\omega$ [rad/s]")
ax.set_ylabel(r"$\bar\sigma\, T_{zw}(j\omega)$")
ax.set_title("HE6: what fewer states than controls cannot reach")
ax.legend(fontsize=8, loc="lower left")
fig.tight_layout()
plt.show()
