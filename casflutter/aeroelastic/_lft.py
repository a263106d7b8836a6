"""Uncertainty model and linear fractional transform of ΣAE (paper eq. 10-15, Lemmas 1-2).

With ``V² = Vf² + ΔV`` (eq. 10), ``Â = A + ΔA``, ``B̂2 = B2 + ΔB2`` (eq. 11) and
(Lemma 1, eq. 12)

    [ΔA ΔB1 ΔB2] = −Mx ΔV [Nx Nw Nv],   Mx = [−Bs; 0], Nx = [Df Cs, Cf], Nw = 0, Nv = df.

With the fictitious signals ``zf = Nx x + Nw w + Nv v`` (eq. 13; note ``zf`` is exactly
the generalised force y) and ``wf = −ΔV zf`` (eq. 15), ΣAE is the LFT (eq. 14)

    ẋ  = A x  + B̄1 w̄ + B2 v,         w̄ = [wf; w],  B̄1 = [Mx B1]
    zf = C1 x + D11 w̄ + D12 v,        C1 = Nx, D11 = [0 Nw], D12 = Nv
    zm = C2 x + D21 w̄ + D22 v.

For state sensors (``sensor="state"``, the paper's ``zm = Hs x_s``) ``C2 = [Hs 0]`` and
``D21 = D22 = 0`` exactly as in eq. 14.  For accelerometers the measured acceleration
``Hs ü`` contains ``α Hs (V² y + w)``; since ``V² y = Vf² zf − wf`` this gives
``C2 = [Hx 0] + Vf² Hf Nx``, ``D21 = [−Hf, Hf]``, ``D22 = Vf² Hf Nv`` (``Hf = α Hs``),
keeping the structure of eq. 14 with non-zero D21/D22.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from .._format import result_repr
from ..errors import ConfigError
from ._loop import AeroelasticSystem

__all__ = ["AeroelasticLFT", "build_lft"]


@dataclass(frozen=True)
class AeroelasticLFT:
    """The LFT of eq. 14 at a nominal flutter speed index Vf.

    Attributes
    ----------
    Vf : float
        Nominal speed index; ``ΔV = V² − Vf²``.
    A, B1bar, B2, C1, D11, D12, C2, D21, D22 : ndarray
        Blocks of eq. 14 (``B2``, ``D12`` and ``D22`` as column matrices).
    Mx, Nx, Nw, Nv, B1 : ndarray
        Lemma 1 factors and the disturbance input matrix.
    P : control.StateSpace
        Generalised plant with inputs ``[wf_1..wf_N, w_1..w_N, v]`` and outputs
        ``[zf_1..zf_N, zm_1..zm_m]``, ordered for ``control.hinfsyn(P, nmeas, ncon)``
        (measurements last, control last).
    n_delta : int
        dim(wf) = dim(zf) = N (the scalar ΔV repeated N times).
    nmeas : int
        dim(zm).
    ncon : int
        1 (the flap v).
    sensor : str
        Sensor kind of Σs (see :mod:`casflutter.structure`).
    """

    __repr__ = result_repr

    Vf: float
    A: np.ndarray
    B1bar: np.ndarray
    B2: np.ndarray
    C1: np.ndarray
    D11: np.ndarray
    D12: np.ndarray
    C2: np.ndarray
    D21: np.ndarray
    D22: np.ndarray
    Mx: np.ndarray
    Nx: np.ndarray
    Nw: np.ndarray
    Nv: np.ndarray
    B1: np.ndarray
    P: control.StateSpace
    n_delta: int
    nmeas: int
    ncon: int
    sensor: str

    def plant_without_d22(self) -> control.StateSpace:
        """``P`` with ``D22 = 0`` (loop shifting), for syntheses that require it.

        Accelerometers with a flap feed-through give ``D22 = Vf² α Hs df ≠ 0``.  Design a
        controller K̃ on the shifted measurement ``z̃m = zm − D22 v`` with this plant, then
        use :meth:`physical_controller` to get the K that acts on the real ``zm``.

        Returns
        -------
        control.StateSpace
            ``P`` with its control-to-measurement block ``D22`` set to zero.
        """
        D = np.array(self.P.D, dtype=float)
        D[-self.nmeas:, -self.ncon:] = 0.0
        return control.ss(self.P.A, self.P.B, self.P.C, D, inputs=self.P.input_labels,
                          outputs=self.P.output_labels, name="Sigma_AE_LFT_shifted")

    def physical_controller(self, K_shifted) -> control.StateSpace:
        """Controller on the real sensors from one designed on :meth:`plant_without_d22`.

        With ``v = K̃ (zm − D22 v)``: ``K = (I + K̃ D22)⁻¹ K̃`` (a positive-feedback
        interconnection, exact including the algebraic loop).

        Parameters
        ----------
        K_shifted : control.StateSpace
            ``K̃``, designed on :meth:`plant_without_d22`.

        Returns
        -------
        control.StateSpace
            ``K`` from the real ``zm`` to ``v``.
        """
        Kt = control.ss(K_shifted)
        if np.allclose(self.D22, 0.0):
            return Kt
        D22 = np.asarray(self.D22, dtype=float).reshape(self.nmeas, self.ncon)
        return control.feedback(Kt, control.ss([], [], [], D22), sign=-1)

    def close(self, dV: float) -> control.StateSpace:
        """Close the internal feedback ``wf = −ΔV zf`` (eq. 15).

        Returns ΣAE at ``V² = Vf² + dV`` as a ``control.StateSpace`` with inputs
        ``[w, v]`` and outputs ``zm`` (compare :meth:`AeroelasticLoop.statespace`).

        Parameters
        ----------
        dV : float
            ``ΔV = V² − Vf²``.

        Returns
        -------
        control.StateSpace
            ΣAE at ``V² = Vf² + dV``.
        """
        N = self.n_delta
        Bf_, Bw = self.B1bar[:, :N], np.hstack([self.B1bar[:, N:], self.B2])
        Dff, Dfw = self.D11[:, :N], np.hstack([self.D11[:, N:], self.D12])
        Dmf, Dmw = self.D21[:, :N], np.hstack([self.D21[:, N:], self.D22])
        # zf = C1 x + Dff wf + Dfw [w; v],  wf = -dV zf  ->  zf = S (C1 x + Dfw [w; v])
        S = np.linalg.inv(np.eye(N) + dV * Dff)
        A = self.A - dV * Bf_ @ S @ self.C1
        B = Bw - dV * Bf_ @ S @ Dfw
        C = self.C2 - dV * Dmf @ S @ self.C1
        D = Dmw - dV * Dmf @ S @ Dfw
        return control.ss(A, B, C, D)


def build_lft(system: AeroelasticSystem, Vf: float) -> AeroelasticLFT:
    """Build the LFT of eq. 14 (Lemmas 1-2) around the nominal speed index ``Vf``.

    Parameters
    ----------
    system : AeroelasticSystem
        Σf and Σs.  A system whose ROM is scaled in time (``convective_V0``) is first frozen
        at ``Vf`` (:meth:`AeroelasticSystem.frozen_at`): the nominal loop is exact, and the
        V² uncertainty of eq. 10 keeps the lags of ``Vf`` (its exact stable interval is then
        :func:`casflutter.verify.speed_family_interval`'s, not the LFT's).
    Vf : float
        Nominal flutter speed index (e.g. ``find_flutter(system, ...).Vf``).

    Returns
    -------
    AeroelasticLFT

    See Also
    --------
    synthesize : the controller designed on the LFT's plant.
    verify_controller : the small-gain and exact speed ranges on it.

    Examples
    --------
    >>> import casflutter as cf
    >>> truth, rom = cf.load_problem("typical_section"), cf.example_rom()
    >>> system = cf.AeroelasticSystem.from_parts(cf.realize(rom).sigma_f, truth.modal_structure())
    >>> lft = cf.build_lft(system, cf.find_flutter(system, (0.5, 3.0)).Vf)
    >>> lft.nmeas, lft.ncon, lft.n_delta
    (2, 1, 2)
    """
    if Vf is None or not np.isfinite(Vf):
        raise ConfigError(f"Vf must be a finite speed index, got {Vf!r} (no flutter found?)")
    if getattr(system, "convective_V0", None) is not None:
        system = system.frozen_at(Vf)      # eq. 14 with the lags of Vf: exact at Vf
    s = system.structure
    N, nf = s.n_modes, system.n_f
    Vf2 = float(Vf) ** 2
    Bs, Cs = s.Bs, s.Cs
    A = system.state_matrix(Vf)
    Mx = np.vstack([-Bs, np.zeros((nf, N))])
    B1 = np.vstack([Bs, np.zeros((nf, N))])
    B2 = np.concatenate([Vf2 * Bs @ system.df, system.bf])[:, None]
    Nx = np.hstack([system.Df @ Cs, system.Cf])
    Nw = np.zeros((N, N))
    Nv = system.df[:, None].copy()
    B1bar = np.hstack([Mx, B1])
    C1 = Nx
    D11 = np.hstack([np.zeros((N, N)), Nw])
    D12 = Nv
    Hx, Hf = s.sensor_matrices()
    C2 = np.hstack([Hx, np.zeros((s.n_sensors, nf))]) + Vf2 * Hf @ Nx
    D21 = np.hstack([-Hf, Hf])
    D22 = Vf2 * Hf @ Nv
    P = control.ss(A, np.hstack([B1bar, B2]), np.vstack([C1, C2]),
                   np.block([[D11, D12], [D21, D22]]),
                   inputs=[f"wf[{i}]" for i in range(N)] + [f"w[{i}]" for i in range(N)] + ["v"],
                   outputs=[f"zf[{i}]" for i in range(N)] + [f"zm[{j}]" for j in range(s.n_sensors)],
                   name="Sigma_AE_LFT")
    return AeroelasticLFT(float(Vf), A, B1bar, B2, C1, D11, D12, C2, D21, D22, Mx, Nx, Nw, Nv,
                          B1, P, N, s.n_sensors, 1, s.sensor)
