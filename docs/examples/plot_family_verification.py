"""
A controller on a grid of state-space models: certified interval, absolute and robust flutter speeds
====================================================================================================

An aeroelastic model usually reaches an engineer as linear state-space models at a grid of
flight speeds.  This example loads such a grid from a family file, the package's
``problems/goland_4flaps`` (the Goland wing with four trailing-edge flaps behind 25 Hz
actuators, two rate gyros and six accelerometers: 50 states, 4 inputs, 8 outputs, 41 airspeeds
from 60 to 200 m/s, interpolated linearly between them), finds its open-loop flutter, and
verifies a controller on it with :func:`casflutter.verify.verify_family`:

* the **absolute flutter speed**, the end of the *certified* stable interval that starts at
  the range's start (eigenvalue-inclusion chains on each linear piece of the grid, the exact
  guardian map where they stall: no grid scan);
* the **robust flutter speed**, the lowest speed at which a loop-at-a-time gain or phase
  margin (each loop broken, the others closed; at the plant inputs and at the plant outputs)
  falls below 6 dB / 45°.

The same is one command on the family file and a controller file that names its signals:
``casflutter verify goland_4flaps CONTROLLER.json --figure margins.png``.
"""

import control
import numpy as np

from casflutter.aeroelastic import family_flutter, load_family
from casflutter.report import plot_family_verification
from casflutter.verify import verify_family

# %%
# The grid and its flutter
# ------------------------
# Every input and output is named in the file, with its role (the flaps are the controls,
# the gyros and accelerometers the measurements) and unit.
family = load_family("goland_4flaps")
print(family.describe())
flutter = family_flutter(family)
print(flutter.message)

# %%
# A controller
# ------------
# A classical damper, not an optimised design: the tip gyro's pitch rate, through a
# second-order low-pass filter (70 rad/s, damping 0.7), commands all four flaps alike; the
# family's convention is MATLAB's ``u = -K y``.  The gain was picked among a few tried on this
# grid.  The controller's inputs and outputs carry the family's signal names, so it is
# matched by name (a controller file does the same with its ``"inputs"``/``"outputs"``).
wf, gain = 70.0, 0.03
low_pass = control.ss([[0.0, 1.0], [-wf ** 2, -2 * 0.7 * wf]], [[0.0], [wf ** 2]],
                      [[gain, 0.0]], [[0.0]])
K = control.ss(low_pass.A, low_pass.B, np.ones((4, 1)) @ low_pass.C, np.zeros((4, 1)),
               inputs=["gyro_100"], outputs=list(family.signals.controls))

result = verify_family(family, K)
print(result.format())
print(f"time: {result.wall_time['total']:.1f} s (certificate "
      f"{result.wall_time['interval']:.1f} s, margins {result.wall_time['margins']:.1f} s)")

# %%
# Margins and damping against the speed
# -------------------------------------
fig = plot_family_verification(result)

# %%
# What the picture says
# ---------------------
# The damper moves the wing's flutter from about 140 m/s (open loop) to the certified
# absolute flutter speed near 184 m/s, where a closed-loop pair near 38 rad/s crosses.  Its
# margins shrink with the speed long before that: the gyro loop's gain margin at the plant
# outputs falls below 6 dB near 122 m/s, the robust flutter speed, and the flaps' phase
# margins close in on the absolute flutter speed.  The gain of a damper trades the two: more
# gain holds the wing further, with less margin at the lower speeds.
