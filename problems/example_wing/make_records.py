"""Write the records of the example wing ONCE, from the seed-wing truth (run from anywhere:
``python problems/example_wing/make_records.py``); the records are committed.

They stand in for the CFD runs of a user's wing (paper §IV.A): one chirp record per input
channel (each modal displacement, then the flap) at the speed index ``V0 = 0.69``, forces
delayed by one sample (a loosely coupled CFD time march), sampled at 4 ms for 4 s.  The
five modal records are NPZ archives of named 1-D channels, the flap record a MATLAB file,
all in single precision (a few hundred kB in all).  ``problem.toml`` describes the wing with
the seed wing's modal data (frequencies, damping, alpha, the tip-store accelerometer rows).
"""

from pathlib import Path

import numpy as np
from scipy.io import savemat

from casflutter.truth import RecordSettings, load_problem, truth_records

HERE = Path(__file__).resolve().parent
#: the record settings (also the reference computation of tests/wing)
SETTINGS = RecordSettings(V0=0.69, dt=0.004, duration=4.0, band=(0.2, 60.0), amplitude=0.01,
                          coupling_delay=1)
MODES = ("bending_1", "lateral_1", "bending_2", "torsion_1", "bending_3")


def main() -> None:
    truth = load_problem("seed_wing")
    data = truth_records(truth, SETTINGS)
    out = HERE / "records"
    out.mkdir(exist_ok=True)
    for j, rec in enumerate(data.records):
        channels = {"t": np.arange(rec.n_samples) * data.dt}
        for i, m in enumerate(MODES):
            channels[f"u_{m}"] = rec.u[:, i]
            channels[f"Q_{m}"] = rec.y[:, i]
        channels["flap"] = rec.v
        channels = {k: np.asarray(v, dtype=np.float32) for k, v in channels.items()}
        channels["t"] = np.arange(rec.n_samples) * data.dt        # time stays exact
        if j < len(MODES):
            np.savez_compressed(out / f"chirp_{MODES[j]}.npz", **channels)
        else:
            savemat(out / "chirp_flap.mat", channels, do_compression=True)


if __name__ == "__main__":
    main()
