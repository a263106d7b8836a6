"""
The Goland wing from frequency-domain aerodynamics: Q(ik) -> RFA -> ΣAE(U) -> flutter
=====================================================================================

The route of an engineer who brings generalised aerodynamic forces ``Q(ik)`` (from NASTRAN,
ZAERO, a doublet-lattice code, here strip theory) instead of time records.  The Goland wing's
strip-theory ``Q(ik)`` is computed with the exact Theodorsen function on its assumed modes
(columns: the seven modes and the flap), in the normalisation of the paper's eq. (6)
(``u'' + 2ζωu' + ω²u = αV² Q(ik) [u; v]``, ``V = U/U_ref``).  A rational-function approximation
(Roger's method, lag roots optimised by Ipopt) turns it into a state space whose lag states
scale with ``U/b``, ΣAE(U) in m/s, whose flutter is compared with the p–k solution on the same
table and with the published 137.2 m/s and 70.7 rad/s.
"""

import os

import matplotlib.pyplot as plt
import numpy as np

import casflutter as cf
from casflutter.aeroelastic import RFASystem, find_flutter, pk_flutter
from casflutter.data import GAFTable
from casflutter.pipeline import config_path
from casflutter.realize import fit_roger
from casflutter.report import plot_vg_vf
from casflutter.structure import ModalStructure
from casflutter.truth import load_problem, problem_definition

QUICK = os.environ.get("CASFLUTTER_DOCS_QUICK") == "1"   # set by `make docs`

wing = load_problem("goland")
ms = wing.modal_structure()
structure = ms.with_sensors(kind="displacement")
ref = problem_definition("goland")["reference"]["flutter"]

# dense near k = 0, where Theodorsen's C(k) has its k log k branch point
k = np.concatenate([np.linspace(0.0, 0.2, 9), np.linspace(0.25, 2.0, 36)])
table = GAFTable.from_truth(wing, k)          # could be load_gaf("goland_q.npz")
print(f"Q(ik): {table.Q.shape[0]} reduced frequencies, {table.n_modes} modes + flap, "
      f"b = {table.b} m, U_ref = {table.U_ref:.2f} m/s per unit speed index")

fits = {n: fit_roger(table, n) for n in ((2, 4) if QUICK else (2, 4, 6))}
for fit in fits.values():
    print(fit.summary())

# %%
# Three elements of ``Q(ik)`` (symbols: the table) and the Roger fits (lines), in the complex
# plane as k runs from 0 to 2: the torsion--torsion and bending--torsion couplings and the
# flap's moment on the first torsion mode, the element fitted worst.
kf = np.linspace(0.0, 2.0, 400)
elements = [("torsion 1", "torsion 1"), ("bending 1", "torsion 1"), ("torsion 1", "flap")]
fig, axes = plt.subplots(1, 3, figsize=(10, 3.4))
for ax, (row, col) in zip(axes, elements):
    i, j = table.mode_names.index(row), table.input_names.index(col)
    ax.plot(table.Q[:, i, j].real, table.Q[:, i, j].imag, "k.", label="exact Theodorsen")
    for n, fit in fits.items():
        q = fit.evaluate(kf)[:, i, j]
        ax.plot(q.real, q.imag, lw=1, label=f"Roger, {n} lags "
                f"(error {fit.error_rel[i, j]:.1e})")
    ax.set_title(f"Q[{row}, {col}]", fontsize=9)
    ax.set_xlabel("Re")
    ax.legend(fontsize=6)
axes[0].set_ylabel("Im")
fig.tight_layout()

# %%
# ΣAE(U) of the 4-lag fit: V–g / V–f diagram in the airspeed (damping ratio ``-Re λ/|λ|``)
# of the first bending and first torsion branches, with the p–k points on the same Q(ik)
# (circles).  The torsion branch crosses zero at the flutter speed, where p–k is exact.  Away
# from zero damping p–k is an approximation (it treats ``Im Q`` as a damping at the root's
# own frequency): for the heavily damped bending branch above about 150 m/s its root leaves
# the eigenvalue of ΣAE and becomes real.
fit = fits[4]
system = RFASystem(fit, structure, table.U_ref)
U_lo, U_hi = 60.0, 200.0
result = find_flutter(system, (U_lo, U_hi), n_grid=57 if QUICK else 141)
pk = pk_flutter(table, structure, np.linspace(U_lo, U_hi, 15 if QUICK else 29), modes=(0, 1))
lam = result.tracking.eigenvalues          # the oscillatory branches of the two modes
low = [b for b in result.tracking.upper_branches()
       if result.origin[b] in (0, 1) and np.mean(np.abs(lam[:, b].imag)) > 0]
fig = plot_vg_vf(result, branches=low, hz=False, mode_names=table.mode_names, speed_unit="m/s",
                 speed_label="airspeed U [m/s]")
ag, af = fig.axes
for j in range(2):
    ag.plot(pk.U, pk.damping_ratio[:, j], "ko", ms=4, mfc="none",
            label="p–k" if j == 0 else None)
    af.plot(pk.U, pk.omega[:, j], "ko", ms=4, mfc="none")
ag.axhline(0.0, color="0.6", lw=0.8)
ag.set_ylim(-0.15, 0.7)
ag.legend(fontsize=7)

# %%
# The flutter point beside the published values (the remaining −1 % in frequency is the
# assumed-mode strip model's own: p–k with the exact Theodorsen function on the same modes
# gives the same number; the RFA reproduces it).
print(f"{'':>22} {'U_F [m/s]':>10} {'omega_F [rad/s]':>16}")
print(f"{'published':>22} {ref['airspeed']:10.2f} {ref['frequency']:16.2f}")
print(f"{'RFA -> ΣAE(U)':>22} {result.Vf:10.2f} {result.omega_f:16.2f}   "
      f"({result.Vf / ref['airspeed'] - 1:+.2%}, {result.omega_f / ref['frequency'] - 1:+.2%})")
print(f"{'p–k on the same Q(ik)':>22} {pk.flutter_speed:10.2f} {pk.flutter_omega:16.2f}   "
      f"({pk.flutter_speed / ref['airspeed'] - 1:+.2%}, "
      f"{pk.flutter_omega / ref['frequency'] - 1:+.2%})")

# %%
# The same route from files, as an engineer with a NASTRAN SOL145 model would take it: the
# wing file ``problems/goland_gaf/problem.toml`` (``kind = "gaf"``: the modal data, the tip
# sensors, the speed scale and the RFA settings) names the table ``q_table.npz`` written once
# by ``make_problem.py`` with the same exact-Theodorsen ``Q(ik)``.  The driver fits the RFA
# the file asks for (six lag roots and no ``p``, ``p²`` terms, so that Σf frozen at the
# flutter speed is exactly eq. 5 for the LFT), finds the flutter of ΣAE(U) and solves p–k
# beside it: ``casflutter flutter problems/goland_gaf`` prints the same numbers, and
# ``casflutter run problems/goland_gaf/run.toml`` continues with the LFT, the synthesis and
# the verification.
run_toml = config_path("goland_gaf", "run")
from_file = cf.run(cf.load_config(run_toml, updates={"stages": []}), write=False, quiet=True)
r = from_file.summary()["rfa"]
print(f"wing file: {r['method']} RFA, {r['n_lags']} lag roots, poly_order {r['poly_order']}, "
      f"fit error {r['fit_error']:.2e}")
for label, b in (("RFA -> ΣAE(U)", r["flutter"]), ("p–k on the same Q(ik)", r["pk"])):
    print(f"{label:>22} {b['airspeed_m_s']:10.2f} {b['omega_rad_s']:16.2f}   "
          f"({b['airspeed_m_s'] / ref['airspeed'] - 1:+.2%}, "
          f"{b['omega_rad_s'] / ref['frequency'] - 1:+.2%})")
