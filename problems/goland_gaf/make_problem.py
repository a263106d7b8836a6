"""Write the Goland wing's route-2 problem ONCE (run from anywhere:
``python problems/goland_gaf/make_problem.py``); both outputs are committed.

- ``q_table.npz``: the strip-theory generalised aerodynamic forces ``Q(ik)`` of the Goland
  wing's seven assumed modes and its flap, with the exact Theodorsen function, at 45 reduced
  frequencies (dense near ``k = 0``, where ``C(k)`` has its ``k log k`` branch point), in the
  normalisation of eq. (6) (:class:`casflutter.data.GAFTable`, NPZ layout);
- ``problem.toml``: the wing file (``kind = "gaf"``) with the same modes' frequencies, damping,
  flow constant, the tip sensors and the speed scale, and the RFA and flutter-search settings.

What a NASTRAN SOL145 user brings: modal data and a ``Q(ik)`` table, no simulator.
"""

import json
from pathlib import Path

import numpy as np

from casflutter.data import GAFTable
from casflutter.truth import load_problem

HERE = Path(__file__).resolve().parent
K = np.concatenate([np.linspace(0.0, 0.2, 9), np.linspace(0.25, 2.0, 36)])

TEMPLATE = '''# The Goland wing (Goland 1945) from frequency-domain aerodynamics: the
# modal data and a table of generalised aerodynamic forces Q(ik), no simulator.  Written by
# make_problem.py from casflutter's Goland strip model (exact Theodorsen function); the layout
# is documented in casflutter/truth/_wing_file.py (casflutter.truth.GAFProblem).
#   casflutter flutter problems/goland_gaf         RFA flutter in m/s and rad/s, p-k beside it
#   casflutter run problems/goland_gaf/run.toml    flutter, LFT, synthesis, verification
# Published flutter (exact strip theory, rho = 1.225 kg/m^3): 137.2 m/s, 70.7 rad/s.
kind = "gaf"

[problem]
name = "goland_gaf"
description = "Goland cantilever wing: 7 assumed modes, strip-theory Q(ik) with the exact Theodorsen function, trailing-edge flap"
source = "Goland (1945), Goland & Luke (1948); Q(ik) from casflutter's strip model (make_problem.py)"

[modes]
names = {names}
frequencies_hz = {freqs}
damping = {zeta}
alpha = {alpha!r}   # flow constant of eq. 6: u'' + omega^2 u = alpha V^2 Q(ik) [u; v]

[speed]
U_ref = {U_ref!r}   # m/s per unit speed index (V = U / (b omega_ref))
rho = {rho!r}

[sensors]
# modal displacements of the wing tip: plunge [m] and pitch [rad] (the LFT's measured outputs)
kind = "displacement"
names = {snames}
units = ["m", "rad"]
rows = {rows}

[gaf]
file = "q_table.npz"
U_range = [60.0, 200.0]   # m/s, flutter search of the RFA system
n_grid = 141
# Roger's RFA with six optimised lag roots and no p, p^2 terms (poly_order = 0: a proper RFA,
# whose aerodynamics frozen at the flutter speed are Σf of eq. 5 exactly, for the LFT)
method = "roger"
n_lags = 6
poly_order = 0

[reference.flutter]
airspeed = 137.2     # m/s
frequency = 70.7     # rad/s
rtol = 0.01
'''


def main() -> None:
    wing = load_problem("goland")
    ms = wing.modal_structure()
    table = GAFTable.from_truth(wing, K, theodorsen="exact")
    table.save(HERE / "q_table.npz")
    rows = ms.Hs[:2]
    text = TEMPLATE.format(
        names=json.dumps(list(ms.mode_names)),
        freqs=json.dumps([float(f) for f in ms.omega / (2 * np.pi)]),
        zeta=json.dumps([float(z) for z in ms.zeta]), alpha=float(ms.alpha),
        U_ref=float(table.U_ref), rho=float(table.rho),
        snames=json.dumps([s.split(" [")[0] for s in ms.sensor_names[:2]]),
        rows="[" + ",\n        ".join(json.dumps([float(x) for x in r]) for r in rows) + "]")
    (HERE / "problem.toml").write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
