"""Write the gridded family ``seed_wing_family`` ONCE (run from anywhere:
``python problems/seed_wing_family/make_problem.py``); its outputs are committed.

The seed wing's own linearisation with its 40 Hz flap servo,
``casflutter.aeroelastic.TruthLoop(SeedWing(), 251.3)`` (the loop the paper's ROM stands in
for: five structural modes, the Wagner lags of its strips, the servo; 32 states), sampled at
26 speed indices from 0.6 to 1.6 — what an engineer would export from an aeroelastic code:

- ``models.npz`` / ``models.mat``: the arrays (``casflutter.data.FamilyFile`` layout; the
  ``.mat`` file stacks them as MATLAB pages, ``n x n x k``);
- ``problem.toml`` (reads ``models.npz``) and ``problem_mat.toml`` (reads ``models.mat``).

Inputs: the modal disturbances ``w[0] .. w[4]`` (disturbances) and the servo command ``v``
(the control, rad); outputs: the two tip-store accelerometers (the measurements); positive
feedback (the paper's ``v = K zm``).  The reference is the flutter of the continuous loop.
"""

from pathlib import Path

import numpy as np

from casflutter.aeroelastic import TruthLoop, family_flutter, write_family
from casflutter.truth import SeedWing

HERE = Path(__file__).resolve().parent
SPEEDS = np.linspace(0.6, 1.6, 26)
SERVO_OMEGA = 251.3     # rad/s: the 40 Hz servo of the seed wing's runs

DESCRIPTION = ("The seed wing's full-order linearisation (5 modes, Wagner lags per strip) with "
               "its flap behind a 40 Hz servo (zeta 0.7), 26 speed indices 0.6-1.6; inputs: "
               "modal disturbances and the servo command; outputs: tip-store accelerometers")
SOURCE = ("casflutter.aeroelastic.TruthLoop(casflutter.truth.SeedWing(), 251.3) sampled at "
          "numpy.linspace(0.6, 1.6, 26) by problems/seed_wing_family/make_problem.py")


def main() -> None:
    """Compute the reference flutter of the continuous loop and write the files."""
    loop = TruthLoop(SeedWing(), SERVO_OMEGA)
    fl = family_flutter(loop, speeds=np.linspace(SPEEDS[0], SPEEDS[-1], 201))
    reference = {"flutter": {
        "speed_index": round(fl.Vf, 6), "omega_rad_s": round(fl.omega_f, 6),
        "freq_hz": round(fl.frequency_hz, 6),
        "route": "TruthLoop(SeedWing(), 251.3), the continuous loop: "
                 "casflutter.aeroelastic.family_flutter"}}
    for fmt, toml in (("npz", "problem.toml"), ("mat", "problem_mat.toml")):
        write_family(loop, HERE / toml, SPEEDS, fmt, data_file=f"models.{fmt}",
                     name="seed_wing_family", description=DESCRIPTION, source=SOURCE,
                     reference=reference)
    print(f"wrote {HERE}: flutter of the continuous loop V = {fl.Vf:.6f}, "
          f"{fl.omega_f:.6f} rad/s")


if __name__ == "__main__":
    main()
