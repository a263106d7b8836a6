"""
Bring your own wing: the study from a wing file with records
=============================================================

An aeroelastician arrives with modal data (from FEA) and records of the generalised forces
(from CFD or a wind tunnel), not with a simulator.  A wing file (``kind = "wing"``, TOML)
holds them: the in-vacuo frequencies [Hz], damping ratios and the flow constant α of eq. 6,
the sensor rows ``Hs`` of eq. 7 with names and units, the speed scale (speed index ↔ m/s,
dynamic pressure) and the record files (CSV, NPZ or MATLAB) with the names of their channels
(modal displacements, flap, generalised forces).  A run configuration whose ``[problem]``
names the file runs the paper's stages on it: identification → Σf → ΣAE → flutter → (LCO of
a nonlinear ROM) → LFT → synthesis → verification.  The stages that need a simulator (the
truth's flutter and LCO, suppression on the truth) are skipped and listed in the summary.

The example wing ``problems/example_wing`` carries the seed wing's modal data and records
that ``make_records.py`` wrote once from the seed-wing truth (six chirp records at 20 m/s,
five NPZ archives and a MATLAB file).  From the command line the same run is
``casflutter run problems/example_wing/run.toml``.
"""

import matplotlib.pyplot as plt
import numpy as np

import casflutter as cf
from casflutter.pipeline import config_path
from casflutter.report import plot_vg_vf
from casflutter.truth import load_problem

run_toml = config_path("example_wing", "run")
wing_toml = run_toml.parent / "problem.toml"
print("\n".join(line for line in wing_toml.read_text().splitlines()
                if line and not line.startswith("#")))

# %%
# The wing file read and checked (every key, shape, file and channel, before any work):
# the modal structure Σs of eq. 6–7 and six records, one per input channel.
wing = load_problem("example_wing")
ms = wing.modal_structure()
print(wing)
print("frequencies [Hz]:", np.round(ms.omega / (2 * np.pi), 2), "; sensors:",
      ", ".join(f"{n} [{u}]" for n, u in zip(ms.sensor_names, wing.sensor_units)))
print(f"records at V0 = {wing.V0} (U = {wing.airspeed(wing.V0):.1f} m/s, "
      f"q = {wing.dynamic_pressure(wing.V0):.0f} Pa), dt = {wing.records.dt * 1e3:.1f} ms")

rec = wing.records.records[3]            # the torsion chirp
t = np.arange(rec.n_samples) * wing.records.dt
fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(7, 4.2))
a1.plot(t, rec.u[:, 3], "k", lw=0.8)
a1.set_ylabel(wing.records.u_names[3])
a2.plot(t, rec.y, lw=0.8)
a2.set_ylabel("generalised forces y")
a2.legend(wing.records.output_names, fontsize=6, ncol=3)
a2.set_xlabel("t [s]")
fig.tight_layout()

# %%
# The study.  ``run.toml`` chooses the linear common-denominator ROM (seconds of least
# squares) and a modest synthesis budget, and asks for the ``controller`` stage; the truth's
# flutter search is skipped (a linear ROM has no LCO, and the suppression run needs a truth
# simulator, so neither stage is asked for).
result = cf.run(cf.load_config(run_toml), write=False, quiet=True)
s = result.summary()
fl = s["flutter"]
print(f"ROM fit error per mode [%]: {np.round(s['fit_error_percent'], 3)}")
print(f"flutter: V = {fl['V']:.4f} (U = {fl['airspeed_m_s']:.2f} m/s), {fl['freq_hz']:.2f} Hz, "
      f"mode {fl['mode']}")
c = s["controller"]
print(f"controller of order {c['order']}: gamma = {c['gamma']:.3f}, verified stable for V in "
      f"[{c['lft_stable_V'][0]:.3f}, {c['lft_stable_V'][1]:.3f}] "
      f"({c['lft_stable_V'][1] / fl['V']:.2f} Vf) on the LFT at Vf, certified on the ROM loop "
      f"for V in [{c['stable_interval'][0]:.3f}, {c['stable_interval'][1]:.3f}]")
print("\n".join(result.skipped_notes()))

# %%
# V–g / V–f diagram of the ROM loop ΣAE(V): the lateral mode crosses zero damping at the
# flutter speed.
plot_vg_vf(result.flutter)
plt.show()
