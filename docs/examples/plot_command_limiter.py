"""
Late or in phase?  The flap at its rate limit
==============================================

At 1.2 times the wing's flutter speed the established LCO asks the flap for more rate than the
tunnel's 300 deg/s servo has.  A flap at its rate limit chases its command and turns only when
it meets it again: the deeper the saturation, the later it pushes, up to a quarter period.
A controller designed for the linear loop then pushes at the wrong moment.
``[suppression] command_limiter = "phase_compensated"`` puts a software limiter before the
servo that turns the flap as soon as the command turns
(:func:`casflutter.truth.limit_command`).  It is the identity below the limit, so no linear
certificate changes.

First the limiters on a command five times faster than the rate limit, then the controller of
the default study (``problems/seed_wing/run.toml``) against the wing's established LCO at
1.2 Vf, with the bare servo and with the limiter (same controller, same LCO, same turbulence,
the default tunnel's 40 s of full gain).
"""

from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np

import casflutter as cf
from casflutter.truth import limit_command, suppression_run, truth_lco

RATE, DT = np.radians(300.0), 0.002
W = 2 * np.pi * 9.26                  # rad/s: the wing's LCO at 1.2 Vf
t = np.arange(0.0, 0.5, DT)
command = 5 * RATE / W * np.sin(W * t)

fig, ax = plt.subplots(figsize=(9.0, 3.6))
ax.plot(t, np.degrees(command), color="0.6", lw=1.2, label="command")
for kind, style in (("rate", "C3--"), ("phase_compensated", "C0-")):
    ax.plot(t, np.degrees(limit_command(command, RATE, DT, kind)), style, lw=1.6,
            label={"rate": "rate-limited (late)",
                   "phase_compensated": "phase-compensated (turns with the command)"}[kind])
ax.set_xlabel("time [s]")
ax.set_ylabel("flap [deg]")
ax.set_title("a 9.26 Hz command with 5x the servo's 300 deg/s")
ax.legend(loc="upper right", fontsize=8)
ax.grid(alpha=0.3)
fig.tight_layout()

# %%
# The wing at 1.2 Vf
# ------------------
# The controller stage of the default study (the multi-speed design of order 3), then the
# truth's LCO at 1.2 times its flutter speed, and two tunnel runs from it.
config = cf.load_config(updates={"stages": ["controller"]})   # problems/seed_wing/run.toml
r = cf.run(config, quiet=True, write=False)
ss, dt = config.suppression, config.data.dt
V = 1.2 * r.Vf_truth
mode = int(r.flutter.flutter_mode)
lco = truth_lco(r.truth, V, config.lco.duration, mode, config.lco.initial_deflection, dt=dt)
runs = {kind: suppression_run(r.truth, r.controller, r.Vf_truth,
                              replace(ss, command_limiter=kind), dt=dt, mode=mode,
                              deflection=config.lco.initial_deflection, x0=lco.final_state,
                              speed_factor=1.2, seed=config.seed)
        for kind in ("none", "phase_compensated")}
lo, hi = r.truth_stable_V
print(f"the wing's loop with this controller is certified stable over ({lo:.3f}, {hi:.3f}); "
      f"the run is at V = {V:.3f}")
for kind, sup in runs.items():
    print(f"{kind}: attenuation {sup.attenuation_percent:.1f} %, flap rate peak "
          f"{np.degrees(sup.flap_rate_peak):.0f} deg/s")

fig, ax = plt.subplots(figsize=(9.0, 4.0))
t_full = ss.settle + ss.ramp
window = int(round(0.5 / dt))                     # a moving rms over 0.5 s
for kind, color in (("none", "C3"), ("phase_compensated", "C0")):
    sup = runs[kind]
    sim = sup.simulation
    keep = sim.timepts < t_full + ss.hold
    z = sim.zm[keep, sup.dominant_sensor]
    moving = np.sqrt(np.convolve(z ** 2, np.ones(window) / window, mode="valid"))
    ax.plot(sim.timepts[keep][window - 1:], moving, color=color, lw=1.6,
            label=f"{kind}: attenuation {sup.attenuation_percent:.0f} %")
ax.axvspan(ss.settle, t_full, color="0.9", label="gain ramp")
ax.axvspan(t_full, t_full + ss.hold, color="C0", alpha=0.06, label="full gain")
ax.set_xlabel("time [s]")
ax.set_ylabel("rms of the dominant accelerometer [m/s²] (0.5 s)")
ax.set_ylim(bottom=0.0)
ax.legend(loc="lower left", fontsize=8)
ax.grid(alpha=0.3)
ax.set_title("the established LCO at 1.2 Vf through the 300 deg/s servo")
fig.tight_layout()

# %%
# Through the bare servo the LCO stays.  In phase, the 6.6° of fundamental that 300 deg/s
# allows at 9.26 Hz, :math:`4R/(\pi\omega)`, are enough for this controller, but slowly: the
# LCO shrinks for 15-30 s of full gain (the default tunnel holds it 40 s) before it dies out
# to what the turbulence leaves.
plt.show()
