"""
The paper's study end to end on the seed wing (``casflutter run``)
==================================================================

:func:`casflutter.run` is what ``make demo`` (``casflutter run``) does:
on the seed wing (the paper's wind-tunnel wing with tip store: five modes at 2.19, 10.07,
13.55, 16.48 and 38.09 Hz, nonlinear strip aerodynamics standing in for the CFD)

1. chirp records of the truth at :math:`V_0 = 0.69` (paper §IV.A);
2. the HWL ROM with orders ``(mu, na, nb, r, p, q) = (3, 1, 1, 1, 2, 2)`` (eq. 1–4);
3. Σf by ERA and Tustin with :math:`n_f = 15` (eq. 5); Σs (eq. 6–7, two tip accelerometers) and
   ΣAE (eq. 8–9, 25 states);
4. the Hopf point :math:`V_f` and the nonlinear LCO of the ROM (Fig. 9);
5. the LFT at :math:`V_f` (eq. 10–15) and a fixed-order controller (§III.C), designed to
   keep the ROM loop, made to follow the wing over speed, decaying over a speed interval;
6. independent verification: γ, the small-gain interval of eq. 10/16 and the exact interval
   of closed-loop stability, on the ROM loop and on the wing's own linearisation;
7. the gain-ramp suppression of the truth's established LCO at 1.05 and 1.2 times its flutter
   speed, in a tunnel's turbulence with noisy sensors (Fig. 11).

The example runs the default configuration ``problems/seed_wing/run.toml`` exactly as
``make demo`` does (one to two minutes), also in the documentation build:
a shorter run changes the identified ROM slightly, and the nonconvex synthesis can then end
in another local optimum with another controller, so a reduced run would not show what the
study does.  The numbers printed below are those of this run, of the version of casflutter
this page was built with (other pages point here rather than repeat them); the files are
written to a temporary folder.
"""

import tempfile

import numpy as np

import casflutter as cf
from casflutter.report import plot_gain_ramp, plot_lco, plot_pole_loci

config = cf.load_config()   # problems/seed_wing/run.toml
out_dir = tempfile.mkdtemp(prefix="casflutter-run-")
result = cf.run(config, out_dir=out_dir, quiet=True)
s = result.summary()        # the content of summary.json

print(f"HWL orders {s['orders']}, {s['n_params']} parameters; fit error per mode [%]:",
      ", ".join(f"{e:.2f}" for e in s["fit_error_percent"]))
print(f"orders: nf = {s['nf']}, ns = {s['ns']}, nAE = {s['nae']}   (paper: 15, 10, 25)")
fl, ft = s["flutter"], s["flutter_truth"]
print(f"ROM flutter:   Vf = {fl['V']:.3f} at {fl['freq_hz']:.2f} Hz, mode {fl['mode']}   "
      "(paper: Vf = 1.20, lateral mode 2)")
print(f"truth flutter: Vf = {ft['V']:.3f} at {ft['freq_hz']:.2f} Hz, mode {ft['mode']}")
lco = s["lco"]      # a frequency is a cycle's: None for a decay or a divergence


def hz(f):
    return "no cycle" if f is None else f"{f:.2f} Hz"


print(f"ROM LCO at V = {lco['V']:.3f}: {lco['kind']}, {hz(lco['freq_hz'])} (paper: 8.5 Hz)")
print(f"truth LCO at V = {lco['truth_V']:.3f}: {lco['truth_kind']}, {hz(lco['truth_freq_hz'])}")
c = s["controller"]
print(f"controller order {c['order']}: gamma = {c['gamma']:.4g}, small-gain V interval "
      f"({c['small_gain_V'][0]:.3f}, {c['small_gain_V'][1]:.3f}), exact stable V interval "
      f"({c['lft_stable_V'][0]:.3f}, {c['lft_stable_V'][1]:.3f}) of the LFT at Vf")
print(f"  certified on the ROM loop, flap behind the {c['servo_omega']} rad/s servo: V in "
      f"({c['stable_interval'][0]:.3f}, {c['stable_interval'][1]:.3f}); robust flutter speed "
      f"(6 dB / 45 deg) {c['robust_flutter_speed']:.3f}")
if c.get("truth_stable_interval") is not None:   # the same controller on the wing itself
    print(f"  certified on the truth's own linearisation, same servo: V in "
          f"({c['truth_stable_interval'][0]:.3f}, {c['truth_stable_interval'][1]:.3f}); "
          f"robust flutter speed {c['truth_robust_flutter_speed']:.3f}")
for run in s["suppression"]["runs"]:
    print(f"suppression of the truth's LCO at {run['speed_factor']:g} Vf (V = {run['V']:.3f}): "
          f"{run['attenuation_percent']:.1f} % attenuation, flap rate peak "
          f"{np.degrees(run['flap_rate_peak']):.0f} deg/s")
print("timings [s]:", {k: round(v, 2) for k, v in s["timings_s"].items()})
print("files:", sorted(p.name for p in result.files.values()))

# %%
# The nonlinear ROM in feedback with the structure at the LCO speed, beside the truth (paper
# Fig. 9): sensor time histories and their spectra.  This figure, Fig. 7, 8, 10 and 11 and
# ``summary.json`` are also written to the output folder and embedded in ``report.html``
# beside the paper's Table I; here they are drawn again from the typed results of the run.
fig = plot_lco(result.lco.rom, truth=result.lco.truth)

# %%
# The poles of ΣAE(V) over the speed range, open loop and closed with the controller (paper
# Fig. 10), zoomed on the structural modes: the far aerodynamic and controller poles would set
# the scale otherwise.  ``result.controlled_rom`` is the loop the run certifies (ΣAE(V) here;
# with the flap behind the servo for a ROM whose time scales with V).
V_grid = np.linspace(max(config.flutter.V_range[0], 1e-3), config.flutter.V_range[1], 60)
fig = plot_pole_loci(result.controlled_rom, V_grid, controller=result.controller)
w_max = 1.3 * float(np.max(result.system.structure.omega))
fig.axes[0].set_xlim(-0.125 * w_max, 0.05 * w_max)
fig.axes[0].set_ylim(0.0, w_max)

# %%
# The truth's sensors above its own flutter speed while the controller gain ramps from 0 to 1
# and is released again (paper Fig. 11), at the first speed; the attenuation printed above is
# measured on it.
sim = result.suppression.runs[0].simulation
fig = plot_gain_ramp(sim.timepts, sim.zm, sim.gain, sim.v)
