"""
Why is one controller over (0, 2.4) hard?  The flap's grip on the flutter mode turns round
==========================================================================================

The paper's claim is one linear controller that keeps the seed wing stable from V = 0 to
2.4, more than twice its flutter speed.  A controller ``v = K(s) zm`` moves the open-loop
flutter eigenvalue λ, to first order, by ``δλ = K(λ) r``: ``r`` is the flutter mode's residue
in the loop from the flap command to the two accelerometers
(:func:`casflutter.aeroelastic.mode_residues`).  To damp the mode, ``K(jω)`` near the flutter
frequency must have the phase that makes ``Re(K r)`` negative.

This example follows ``r`` along the speed on two models:

* the wing itself: the truth's linearisation with the flap behind its 40 Hz servo
  (:class:`casflutter.aeroelastic.TruthLoop`);
* the default run's ROM loop (eq. 8, identified at V0 = 0.69 and scaled by V²,
  ``problems/seed_wing_rom/rom_loop_seed0.npz``), behind the same servo.
"""

import matplotlib.pyplot as plt
import numpy as np

from casflutter._resources import problems_dir
from casflutter.aeroelastic import TruthLoop, load_rom_loop, mode_residues
from casflutter.truth import SeedWing

SERVO = 251.3                            # rad/s: the wind-tunnel servo, 40 Hz
speeds = np.linspace(1.1, 2.45, 136)     # from just below flutter to past the paper's 2.4

wing = TruthLoop(SeedWing(), SERVO)
rom, Vf = load_rom_loop(problems_dir() / "seed_wing_rom" / "rom_loop_seed0.npz")
models = {"wing (truth linearisation)": mode_residues(wing, speeds),
          "default ROM loop (frozen, eq. 8)": mode_residues(rom.with_servo(SERVO), speeds)}

for name, res in models.items():
    k = res.weakest_index()
    print(f"{name:34s} residues turn by {np.round(res.phase_swing_deg).astype(int)} deg; "
          f"weakest grip at V = {res.weakest_V:.2f}, where the mode grows at "
          f"{res.eigenvalue[k].real:.2f} rad/s ({res.eigenvalue[k].imag:.1f} rad/s)")

# %%
# Growth, grip and phase of the flutter mode
# ------------------------------------------
fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.0), sharex=True)
for (name, res), color in zip(models.items(), ("k", "C3")):
    axes[0].plot(res.V, res.eigenvalue.real, color=color, label=name)
    axes[1].semilogy(res.V, res.grip, color=color)
    for j, style in enumerate(("-", "--")):
        axes[2].plot(res.V, res.phase_deg[:, j], style, color=color,
                     label=f"{name.split(' (')[0]}, Acc{j + 1}")
    for ax in axes:
        ax.axvline(res.weakest_V, color=color, lw=0.8, ls=":")
axes[0].axhline(0.0, color="0.5", lw=0.8)
axes[0].set_ylabel("open-loop Re λ [rad/s]")
axes[0].legend(fontsize=8)
axes[0].set_title("The seed wing's flutter mode along the speed")
axes[1].set_ylabel("‖r‖: the flap's grip")
axes[2].set_ylabel("arg r_j [deg], unwrapped")
axes[2].set_xlabel("speed index V")
axes[2].legend(fontsize=8, ncol=2)
fig.tight_layout()

# %%
# What the picture says
# ---------------------
# On both models the residues turn by about 180 degrees or more between flutter and
# V = 2.4, while the mode's frequency moves only from about 59 to 48 rad/s.  The turn happens
# where the grip ``‖r‖`` dips (dotted lines): a controller phase that damps the mode below the
# dip pushes it the wrong way above it, to first order, so one controller has to move the mode
# far (large gain), or change its phase quickly in frequency (controller states).
#
# On the wing the dip lies near V = 1.46, where the mode grows at only 1.3 rad/s; on the
# frozen ROM loop it lies near V = 1.93, where the mode already grows at 6.6 rad/s, with a
# grip almost four times weaker than at its flutter speed.  The interval designs
# (continuation in speed, :func:`casflutter.design.design_over_speeds`) meet it:
#
# * on the frozen ROM loop every route stalls around the dip, whatever the order: continued
#   up from V = 0.05, the paper's order-3 design reaches 1.88 and the wing's own order-3,
#   order-4, order-8 and full-order (32) controllers 1.87, 1.83, 1.97 and 2.01; continued
#   down from 2.4, full-order LQG controllers stop between 1.79 and 2.05 (with or without
#   the servo);
# * on the wing, order-3 controllers continued up from V = 0.05 reach 2.24-2.27, and
#   order-3 controllers that stabilise V = 2.4 continued down stop either just above the dip
#   (1.48-1.53) or, with a resonator at 68-76 rad/s, cross it and stop at 1.03-1.23, where they
#   destabilise the same mode below its flutter speed (the flutter mode grows out of the
#   lateral mode, 63 rad/s at rest and damped 0.5 %, and there its residue points the other
#   way).  Two order-3
#   controllers hold (0, 2.26) and (1.03, 2.40) (``tests/witnesses/``, certified in the
#   tests); one order-4 controller holds (0, 2.41).
#
# The frozen ROM puts the flutter mode's control reversal half a speed unit too high, where
# the mode is five times as unstable.  That is a property of the model (eq. 8 keeps the
# aerodynamic time scale of V0; *Which ROM predicts a controller on the wing?* shows the ROM
# whose lags scale with V following the wing), and it is why the default run's design,
# made on that loop, is not certified over the paper's interval.
