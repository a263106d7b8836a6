"""Block observer-canonical realisation of the linearised HWL ROM (paper §III.A.1, eq. 5).

ERA (:func:`casflutter.realize.era`) returns a *balanced* realisation whose state basis is
fixed by an SVD, so two ROMs identified at neighbouring speeds can have unrelated bases and
interpolating their matrices is meaningless.  The block observer-canonical form below is a
fixed, explicit function of the model's coefficients ``{A, H, h, B, b}``: a ROM whose
coefficients depend continuously on the speed index (:class:`casflutter.realize.ParametricROM`) gets a realisation of fixed dimension whose matrices, and hence
whose eigenvalues and eigenvectors, depend continuously on V.

Write the linearised model (eq. 3 with ``p = q = 1``) with every lag ``l = 0..L``
(``L`` = ``max_lag``) as

    y(k) = - sum_{l=1}^{L} Abar_l y(k-l) + sum_{l=0}^{L} Bbar_l w(k-l),   w = [u; v],

where ``Abar_l = A^(m)`` for ``l = mu + m - 1`` and ``Bbar_l`` collects ``[H^(d), h^(d)]``
(``l = r + d``) and ``[B^(d), b^(d)]`` (``l = r + mu + d``), zero elsewhere.  With the state
``x = (x_1, ..., x_L)``, ``x_i`` of length N,

    x_i(k+1) = -Abar_i y(k) + x_{i+1}(k) + Bbar_i w(k),   y(k) = x_1(k) + Bbar_0 w(k),

i.e. ``Ad = [[-Abar_1, I, 0, ...], [-Abar_2, 0, I, ...], ..., [-Abar_L, 0, ..., 0]]``,
``Bd_i = Bbar_i - Abar_i Bbar_0``, ``Cd = [I, 0, ..., 0]``, ``Dd = Bbar_0``.  Its Markov
parameters are exactly :meth:`HWLModel.markov_parameters`.  The realisation is not minimal in
general (``N L`` states); the delay states sit at ``z = 0``, which Tustin's transform maps to
``s = -2/dt``, far to the left of the aeroelastic poles.
"""

from __future__ import annotations

import control
import numpy as np

from ..errors import DimensionError

__all__ = ["lag_coefficients", "canonical_matrices", "canonical_realization"]


def lag_coefficients(model) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients of the linearised model per lag.

    Parameters
    ----------
    model : casflutter.ident.HWLModel

    Returns
    -------
    Abar : ndarray, shape (L + 1, N, N)
        ``Abar[l]`` multiplies ``y(k - l)`` (``Abar[0] = 0``), with the sign convention
        ``y(k) = -sum Abar_l y(k-l) + ...``.
    Bbar : ndarray, shape (L + 1, N, m)
        ``Bbar[l]`` multiplies ``[u; v](k - l)``; inputs ordered ``[u_1..u_N, v]`` (those
        that exist), as in :meth:`HWLModel.markov_parameters`.
    """
    o = model.orders
    N = model.n_modes
    L = model.max_lag
    c = model.coefficients()
    cols = []
    if model.has_u:
        cols.append(np.concatenate([c["H"], c["B"]], axis=0))
    if model.has_v:
        cols.append(np.concatenate([c["h"], c["b"]], axis=0)[:, :, None])
    num = np.concatenate(cols, axis=2)
    Abar = np.zeros((L + 1, N, N))
    for m, lag in enumerate(o.ar_lags()):
        Abar[lag] += c["A"][m]
    Bbar = np.zeros((L + 1, N, num.shape[2]))
    for d, lag in enumerate(o.input_lags()):
        Bbar[lag] += num[d]
    return Abar, Bbar


def canonical_matrices(Abar: np.ndarray, Bbar: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(Ad, Bd, Cd, Dd)`` of the block observer-canonical form of lag coefficients.

    Parameters
    ----------
    Abar, Bbar : ndarray
        As returned by :func:`lag_coefficients` (``L >= 1`` lags).

    Returns
    -------
    Ad : ndarray, shape (N L, N L)
    Bd : ndarray, shape (N L, m)
    Cd : ndarray, shape (N, N L)
    Dd : ndarray, shape (N, m)
        Module docstring; polynomial (linear) in the coefficients.
    """
    L = Abar.shape[0] - 1
    N, m = Bbar.shape[1], Bbar.shape[2]
    n = N * L
    Ad = np.zeros((n, n))
    Bd = np.zeros((n, m))
    D0 = Bbar[0]
    for i in range(1, L + 1):
        rows = slice((i - 1) * N, i * N)
        Ad[rows, :N] = -Abar[i]
        if i < L:
            Ad[rows, i * N:(i + 1) * N] = np.eye(N)
        Bd[rows] = Bbar[i] - Abar[i] @ D0
    Cd = np.zeros((N, n))
    Cd[:, :N] = np.eye(N)
    return Ad, Bd, Cd, D0


def canonical_realization(model) -> control.StateSpace:
    """Discrete block observer-canonical realisation of an HWL model's linearisation.

    Parameters
    ----------
    model : casflutter.ident.HWLModel
        Any orders; only the linear part ``{A, H, h, B, b}`` is used (the normalisation
        ``alpha^[1] = gamma^[1] = beta^[1] = 1`` makes it the exact linearisation about zero).

    Returns
    -------
    control.StateSpace
        Discrete (``dt = model.dt``) with ``N * max_lag`` states, inputs ``[u_1..u_N, v]``
        (those that exist) and outputs ``y_1..y_N``; convert it to Σf with
        :func:`casflutter.realize.tustin_to_continuous`.  Its matrices are polynomial
        (linear) in the model's coefficients, hence continuous in them.

    Raises
    ------
    DimensionError
        If the model has no lag (``max_lag = 0``): a static map needs no states; use its
        ``Bbar_0`` directly.

    See Also
    --------
    realize : the balanced (ERA) realisation and Σf.

    Examples
    --------
    >>> import casflutter as cf
    >>> rom = cf.example_rom()
    >>> sys_d = cf.canonical_realization(rom)
    >>> sys_d.dt, sys_d.ninputs, sys_d.noutputs
    (0.1, 3, 2)
    """
    Abar, Bbar = lag_coefficients(model)
    L = Abar.shape[0] - 1
    N = Bbar.shape[1]
    if L == 0:
        raise DimensionError("the model has no lag (max_lag = 0): it is a static gain with no "
                             "state to realise; use lag_coefficients(model)[1][0] as D")
    Ad, Bd, Cd, Dd = canonical_matrices(Abar, Bbar)
    inputs = list(model.u_names) * model.has_u + [model.v_name] * model.has_v
    return control.ss(Ad, Bd, Cd, Dd, model.dt, inputs=inputs,
                      outputs=list(model.output_names),
                      states=[f"x{i}_{j}" for i in range(1, L + 1) for j in range(1, N + 1)],
                      name="hwl_canonical")
