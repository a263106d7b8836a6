"""Write the gridded family ``goland_4flaps`` ONCE (run from anywhere:
``python problems/goland_4flaps/make_problem.py``); its outputs are committed.

The model is :class:`casflutter.aeroelastic.FlapWingFamily` with its defaults: the Goland
wing (four bending and four torsion assumed modes, 1 % modal damping, strip theory with
Jones' two-lag Wagner function), four trailing-edge flaps of 20 % chord along the span, each
behind a 25 Hz second-order actuator, two rate gyros (30 Hz filters) and six accelerometers:
50 states, 4 inputs, 8 outputs.  It is sampled at 41 airspeeds from 60 to 200 m/s:

- ``models.npz`` / ``models.mat``: the arrays (``casflutter.data.FamilyFile`` layout; the
  ``.mat`` file stacks them as MATLAB pages, ``n x n x k``);
- ``problem.toml`` (reads ``models.npz``) and ``problem_mat.toml`` (reads ``models.mat``):
  the problem files, ``kind = "plant_family"``, with the flutter of the continuous model
  (``FlapWingFamily`` itself, strip theory exact at every airspeed) as the reference.
"""

from pathlib import Path

import numpy as np

from casflutter.aeroelastic import FlapWingFamily, family_flutter, write_family

HERE = Path(__file__).resolve().parent
SPEEDS = np.linspace(60.0, 200.0, 41)

DESCRIPTION = ("Goland cantilever wing (4 bending + 4 torsion assumed modes, 1 % damping, "
               "strip theory with Jones' Wagner lags), four 20 %-chord trailing-edge flaps at "
               "20-40-60-80-100 % span behind 25 Hz actuators, two rate gyros (30 Hz "
               "filters) at 50 and 100 % span, front/rear accelerometers (15 and 65 % chord, "
               "positive down) at 33, 67 and 100 % span; 50 states, 41 airspeeds")
SOURCE = ("casflutter.aeroelastic.FlapWingFamily() sampled at numpy.linspace(60, 200, 41) "
          "by problems/goland_4flaps/make_problem.py")


def main() -> None:
    """Compute the reference flutter of the continuous model and write the files."""
    wing = FlapWingFamily()
    fl = family_flutter(wing, speeds=wing.speed_grid(281))
    reference = {"flutter": {
        "speed": round(fl.Vf, 6), "omega_rad_s": round(fl.omega_f, 6),
        "freq_hz": round(fl.frequency_hz, 6),
        "route": "FlapWingFamily (the continuous model, not the grid): "
                 "casflutter.aeroelastic.family_flutter"}}
    for fmt, toml in (("npz", "problem.toml"), ("mat", "problem_mat.toml")):
        write_family(wing, HERE / toml, SPEEDS, fmt, data_file=f"models.{fmt}",
                     name="goland_4flaps", description=DESCRIPTION, source=SOURCE,
                     reference=reference)
    print(f"wrote {HERE}: flutter of the continuous model {fl.Vf:.6f} m/s, "
          f"{fl.omega_f:.6f} rad/s")


if __name__ == "__main__":
    main()
