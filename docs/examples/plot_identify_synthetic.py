"""
Identifying an HWL ROM from chirp data (paper §II)
===================================================

A known Hammerstein--Wiener-like model with the paper's orders
``(mu, na, nb, r, p, q) = (3, 1, 1, 1, 2, 2)`` and ``N = 5`` modes is excited by
band-limited chirps on the five modal displacements and the flap (as the CFD runs of §IV.A),
its outputs are corrupted by 2 % white noise, and the two-stage identification recovers it:
stage 1 (over-parameterised least squares and rank-one SVD, Bai 1998) and stage 2 (Ipopt
through CasADi).  The linear part is then realised by ERA and Tustin as Σf (eq. 5).
"""

import matplotlib.pyplot as plt
import numpy as np

from casflutter.ident import identify, random_hwl_model, synthetic_data
from casflutter.realize import realize

truth = random_hwl_model(5, (3, 1, 1, 1, 2, 2), seed=1)
data = synthetic_data(truth, 4000, seed=2, noise=0.02)
result = identify(data, (3, 1, 1, 1, 2, 2))
print(result.summary())

# %%
# Free-run simulation on a fresh record (the paper's Fig. 7 compares ROM and CFD this way).
val = synthetic_data(truth, 1000, seed=5).records[0]
ysim = result.model.simulate(val.u, val.v, y0=val.y[:truth.max_lag])
t = np.arange(val.n_samples) * data.dt
fig, axes = plt.subplots(5, 1, sharex=True, figsize=(7, 8))
for i, ax in enumerate(axes):
    ax.plot(t, val.y[:, i], "k", lw=1.5, label="truth")
    ax.plot(t, ysim[:, i], "C1--", lw=1, label="ROM")
    err = 100 * np.linalg.norm(ysim[:, i] - val.y[:, i]) / np.linalg.norm(val.y[:, i])
    ax.set_ylabel(f"$y_{i + 1}$")
    ax.set_title(f"mode {i + 1}: error {err:.2f} %", fontsize=8, loc="right")
axes[0].legend(loc="upper left", fontsize=8)
axes[-1].set_xlabel("time [s]")
fig.tight_layout()

# %%
# Hankel singular values of the linearised model and the order of Σf.  The exact McMillan
# degree is :math:`N \max(\mu + n_a - 1,\ r + \mu + n_b) = 25`; the paper's :math:`n_f = 15` is a
# balanced truncation of it.
real = realize(result.model)
S = real.hankel_singular_values
fig, ax = plt.subplots(figsize=(6, 3))
ax.semilogy(np.arange(1, 41), S[:40] / S[0], "o-", ms=3)
ax.axvline(15, color="C2", ls=":", label="paper nf = 15")
ax.axvline(real.order, color="C3", ls="--", label=f"exact order {real.order}")
ax.set_xlabel("index")
ax.set_ylabel(r"$\sigma_i / \sigma_1$")
ax.legend()
fig.tight_layout()
