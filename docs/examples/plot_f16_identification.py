"""
Real data: an HWL model of the F-16 ground-vibration test
=========================================================

The F-16 nonlinear benchmark (Noël & Schoukens 2017): a shaker under the right wing of a
full-scale F-16 drives the structure with a multisine force; three accelerometers measure the
response, and the wing-to-payload mounting is nonlinear.  Here there is no modal-displacement
input (``u`` absent), ``v`` is the shaker force and ``N = 3`` accelerations are the outputs.

Each model is fitted on the low-level record (12.4 N RMS) by the mu-step prediction error
(the paper's two-stage method) and by the *simulation error* (free run, the way a ROM is used:
Gauss--Newton with exact sensitivities through the recursion of eq. 3, started from the
prediction-error optimum), and scored by free-run simulation on the high-level validation
record (24.6 N RMS, twice the amplitude: the nonlinear terms must extrapolate).  The score is
the RMS error after the first 50 samples, as the benchmark convention asks.  The linear models
have the same structure with polynomial degrees p = q = 1; the HWL model fitted by simulation
error is compared with the better linear model on the validation record.

Two choices matter on these real records.  The records start from their measured outputs
(``estimate_initial=False``): with free initial outputs a lightly damped mode that the shaker
hardly excites can drift unstable unseen.  And the high-order multi-output autoregression is
nearly redundant, so Gauss--Newton converges slowly: the simulation fits run for a fixed budget
of iterations (deterministic, unlike a time budget) and their last iterate is used, with the
status ``Maximum_Iterations_Exceeded`` printed below (``identify`` raises
``ConvergenceError`` carrying that result).  The documentation build
(``CASFLUTTER_DOCS_QUICK=1``) uses two periods of each record instead of eight.

The two records (5 MB) are in the source tree's ``problems/f16gvt`` (see its README for the
benchmark they come from); the installed package does not carry them, as no package function
needs them.
"""

import os
import warnings

import matplotlib.pyplot as plt
import numpy as np

from casflutter.data import IOData
from casflutter.errors import ConvergenceError
from casflutter.ident import IdentificationWarning, fit_report, identify
from casflutter.pipeline import default_config_path

QUICK = os.environ.get("CASFLUTTER_DOCS_QUICK") == "1"   # set by `make docs`

PERIOD = 8192            # samples per multisine period (the first holds transients)
DECIMATE = 4             # 400 Hz -> 100 Hz; the excitation band is 2-15 Hz
ORDERS = (1, 16, 15, 0, 2, 2)   # mu, na, nb, r, p, q
PERIODS = (1, 3) if QUICK else (1, 9)
folder = default_config_path().resolve().parents[1] / "f16gvt"   # the source tree's problems/


def load(name, periods):
    data = IOData.from_mat(folder / name, y="Acceleration", v="Force", fs="Fs",
                           output_names=("acc. shaker", "acc. wing", "acc. payload"))
    return data.window(PERIOD * periods[0], PERIOD * periods[1]).decimated(DECIMATE)


estimation = load("F16Data_FullMSine_Level1.mat", PERIODS)
validation = load("F16Data_FullMSine_Level2_Validation.mat", PERIODS)

BUDGET = 20      # Gauss--Newton iterations per simulation-error fit


def fit(orders, **settings):
    """The identification, or the unconverged one with its status (printed below)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentificationWarning)
            return identify(estimation, orders, **settings)
    except ConvergenceError as exc:
        return exc.result


LINEAR = ORDERS[:4] + (1, 1)
fits = {
    "HWL, prediction": fit(ORDERS),
    "HWL, simulation": fit(ORDERS, criterion="simulation", estimate_initial=False,
                           max_iter=BUDGET),
    "linear, prediction": fit(LINEAR),
    "linear, simulation": fit(LINEAR, criterion="simulation", estimate_initial=False,
                              max_iter=BUDGET),
}
scores = {}
for name, res in fits.items():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")    # a diverging free run is scored as inf
        rep = fit_report(res.model, validation, "simulation", skip=50)
    total = float(np.sqrt(np.mean(rep.rms_error ** 2)))
    scores[name] = (rep, total if np.isfinite(total) else np.inf)
    print(f"{name:>19}: {res.n_params} parameters, {res.iterations} iterations, "
          f"{res.t_stage2:.1f} s, status {res.return_status}, validation RMS {total:.4f}")
best_linear = min(("linear, prediction", "linear, simulation"), key=lambda k: scores[k][1])
score_lin, total_lin = scores[best_linear]
score_nl, total_nl = scores["HWL, simulation"]
nonlinear, linear = fits["HWL, simulation"], fits[best_linear]
print(f"HWL (simulation error) against the best linear model ({best_linear}):")
print(f"{'channel':>14} {'linear RMS':>12} {'HWL RMS':>10} {'change':>8}")
for name, a, b in zip(validation.output_names, score_lin.rms_error, score_nl.rms_error):
    print(f"{name:>14} {a:12.4f} {b:10.4f} {100 * (b - a) / a:7.1f}%")
print(f"{'all':>14} {total_lin:12.4f} {total_nl:10.4f} {100 * (total_nl - total_lin) / total_lin:7.1f}%")

# %%
# The payload accelerometer over one second of the validation record.
rec = validation.records[0]
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    sim_nl = nonlinear.model.simulate(rec.v, y0=rec.y[:nonlinear.model.max_lag])
    sim_lin = linear.model.simulate(rec.v, y0=rec.y[:linear.model.max_lag])
t = np.arange(rec.n_samples) * validation.dt
window = slice(1000, 1100)
fig, ax = plt.subplots(figsize=(7, 3))
ax.plot(t[window], rec.y[window, 2], "k", lw=1.5, label="measured")
ax.plot(t[window], sim_lin[window, 2], "C0--", lw=1, label="linear")
ax.plot(t[window], sim_nl[window, 2], "C1-", lw=1, label="HWL")
ax.set_xlabel("time [s]")
ax.set_ylabel("payload acceleration")
ax.legend(fontsize=8)
fig.tight_layout()
