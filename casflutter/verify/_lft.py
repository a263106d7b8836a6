"""Lower linear fractional transformation of a partitioned plant and a controller.

The plant is partitioned as in :func:`control.hinfsyn` ``(P, nmeas, ncon)``: the last
``ncon`` inputs are the controls ``v`` (``u``), the last ``nmeas`` outputs the measurements
``zm`` (``y``); the rest are the exogenous inputs ``w̄ = (wf, w)`` and outputs ``zf``
(eq. 14 of Lum et al. 2016).  Independent of :mod:`casflutter.design`.
"""

from __future__ import annotations

import control
import numpy as np

from ..errors import DimensionError
from ._common import IllPosedError, SystemLike, as_statespace, ssdata

__all__ = ["lft_closed_loop", "partition_plant"]


def partition_plant(P: control.StateSpace, nmeas: int, ncon: int) -> dict[str, np.ndarray]:
    """Split ``P`` into ``A, B1, B2, C1, C2, D11, D12, D21, D22``.

    Parameters
    ----------
    P : control.StateSpace
        Plant with inputs ``[w; u]`` and outputs ``[z; y]``.
    nmeas, ncon : int
        Number of measurements (last outputs) and controls (last inputs).

    Returns
    -------
    dict of numpy.ndarray
        The nine blocks of eq. (14).

    Raises
    ------
    DimensionError
        If ``nmeas``/``ncon`` do not fit the plant's outputs/inputs.
    """
    A, B, C, D = ssdata(P)
    m, p = B.shape[1], C.shape[0]
    if not (isinstance(nmeas, (int, np.integer)) and isinstance(ncon, (int, np.integer))):
        raise DimensionError(f"nmeas and ncon must be integers, got {nmeas!r}, {ncon!r}")
    if not 0 < nmeas <= p or not 0 < ncon <= m:
        raise DimensionError(
            f"plant has {m} inputs and {p} outputs; nmeas={nmeas} must be in 1..{p} and "
            f"ncon={ncon} in 1..{m} (last nmeas outputs are measurements, last ncon inputs "
            "controls, as in control.hinfsyn)")
    nw, nz = m - ncon, p - nmeas
    return dict(A=A, B1=B[:, :nw], B2=B[:, nw:], C1=C[:nz], C2=C[nz:],
                D11=D[:nz, :nw], D12=D[:nz, nw:], D21=D[nz:, :nw], D22=D[nz:, nw:])


def lft_closed_loop(P: control.StateSpace, K: SystemLike, nmeas: int, ncon: int,
                    *, rcond: float = 1e-10) -> control.StateSpace:
    """Closed loop ``F_l(P, K)`` from the exogenous inputs to the exogenous outputs.

    With ``u = K y`` and the blocks of eq. (14),
    ``T = P11 + P12 K (I - P22 K)^-1 P21``; the state is ``[x; xK]``.  A nonzero
    ``D22`` is handled through ``R = (I - Dk D22)^-1``.

    Parameters
    ----------
    P : control.StateSpace
        Partitioned plant (continuous time).
    K : control.StateSpace, TransferFunction or array_like
        Controller from the ``nmeas`` measurements to the ``ncon`` controls; a matrix
        (or a 0-state system) is a static gain.
    nmeas, ncon : int
        Number of measurements and controls.
    rcond : float
        ``I - Dk D22`` is declared singular when its reciprocal condition number is
        below this.

    Returns
    -------
    control.StateSpace
        Closed loop with ``nw = P.ninputs - ncon`` inputs, ``nz = P.noutputs - nmeas``
        outputs and ``P.nstates + K.nstates`` states.

    Raises
    ------
    DimensionError
        If ``K`` is not ``ncon x nmeas`` (both shapes are named).
    IllPosedError
        If ``I - Dk D22`` is singular (the loop is not well posed).
    ConfigError
        If either system is discrete time.
    """
    P = as_statespace(P, "plant P")
    K = as_statespace(K, "controller K")
    blk = partition_plant(P, nmeas, ncon)
    if K.ninputs != nmeas or K.noutputs != ncon:
        raise DimensionError(
            f"controller K has {K.noutputs} outputs x {K.ninputs} inputs but the plant "
            f"(P: {P.noutputs} outputs x {P.ninputs} inputs, nmeas={nmeas}, ncon={ncon}) "
            f"needs K to map {nmeas} measurements to {ncon} controls ({ncon} x {nmeas})")
    Ak, Bk, Ck, Dk = ssdata(K)
    A, B1, B2 = blk["A"], blk["B1"], blk["B2"]
    C1, C2 = blk["C1"], blk["C2"]
    D11, D12, D21, D22 = blk["D11"], blk["D12"], blk["D21"], blk["D22"]

    M = np.eye(ncon) - Dk @ D22
    if np.linalg.cond(M) * rcond > 1.0:
        raise IllPosedError(
            "the loop is not well posed: I - Dk D22 is singular "
            f"(condition number {np.linalg.cond(M):.3g}); change the controller's "
            "feedthrough Dk or use a strictly proper plant (D22 = 0)")
    R = np.linalg.solve(M, np.eye(ncon))
    # u = R (Dk C2 x + Ck xk + Dk D21 w);  y = C2 x + D21 w + D22 u
    RDk = R @ Dk
    Ux, Uk, Uw = RDk @ C2, R @ Ck, RDk @ D21
    Yx, Yk, Yw = C2 + D22 @ Ux, D22 @ Uk, D21 + D22 @ Uw
    Acl = np.block([[A + B2 @ Ux, B2 @ Uk], [Bk @ Yx, Ak + Bk @ Yk]])
    Bcl = np.vstack([B1 + B2 @ Uw, Bk @ Yw])
    Ccl = np.hstack([C1 + D12 @ Ux, D12 @ Uk])
    Dcl = D11 + D12 @ Uw
    return control.ss(Acl, Bcl, Ccl, Dcl)
