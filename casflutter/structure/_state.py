"""The structural state of eq. 6, independent of where a model keeps it.

Every model of the package carries the modal displacements ``u`` and velocities ``u̇`` of
the ``N`` structural modes of eq. 6 in its state vector, but not in the same places: Σs of
eq. 7 keeps one block per mode, ``[u_1, u̇_1, u_2, u̇_2, ...]`` (its matrices are then block
diagonal, as in the paper), while the truth simulators keep ``[u, u', lag states]`` (the
natural layout of their second-order equations).  Two types keep the two apart:

- :class:`ModalState` is the state itself: ``u`` and ``u̇`` by name, no layout.  What
  :meth:`ModalStructure.modal_state` and :meth:`ModalStructure.displaced_state` (and the
  truths' methods of the same names) return, and what every simulation accepts as its
  initial state: each puts it where its own model keeps it.
- :class:`ModalLayout` is where one model keeps it: :meth:`ModalLayout.vector` writes a
  :class:`ModalState` into that model's state vector, :meth:`ModalLayout.state` reads it
  back, :attr:`ModalLayout.mode_states` gives the indices ``[u_i, u̇_i]`` of each mode.

A state built for one model is therefore right for every other one; a raw vector is
accepted only as the model's own full state (e.g. the last sample of its own simulation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import DimensionError

__all__ = ["ModalState", "ModalLayout", "ModalStates"]


def _modal_vector(values, n_modes: int, name: str) -> np.ndarray:
    v = np.zeros(n_modes) if values is None else np.asarray(values, dtype=float).ravel()
    if v.size != n_modes:
        raise DimensionError(f"{name} has {v.size} entries, the structure has {n_modes} modes")
    return v


@dataclass(frozen=True)
class ModalState:
    """Modal displacements and velocities of the ``N`` structural modes of eq. 6.

    Parameters
    ----------
    u, udot : array_like, shape (N,)
        Modal displacements ``u_i`` and velocities ``u̇_i``.

    Raises
    ------
    DimensionError
        ``u`` and ``udot`` of different lengths.

    Examples
    --------
    >>> from casflutter.structure import ModalLayout, ModalState
    >>> x = ModalState(u=[0.0, 0.5, 0.0], udot=[0.0, 0.0, 0.0])
    >>> ModalLayout(3, interleaved=True).vector(x).tolist()
    [0.0, 0.0, 0.5, 0.0, 0.0, 0.0]
    >>> ModalLayout(3, interleaved=False).vector(x).tolist()
    [0.0, 0.5, 0.0, 0.0, 0.0, 0.0]
    """

    u: np.ndarray
    udot: np.ndarray

    def __post_init__(self):
        u = np.atleast_1d(np.asarray(self.u, dtype=float)).ravel()
        object.__setattr__(self, "u", u)
        object.__setattr__(self, "udot", _modal_vector(self.udot, u.size, "udot"))

    @property
    def n_modes(self) -> int:
        """Number of modes ``N``."""
        return int(self.u.size)


@dataclass(frozen=True)
class ModalLayout:
    """Where a model keeps the modal displacements and velocities in its state vector.

    Parameters
    ----------
    n_modes : int
        Number of modes ``N``.
    interleaved : bool
        ``True``: one block per mode, ``[u_1, u̇_1, u_2, u̇_2, ...]`` (Σs, eq. 7);
        ``False``: ``[u, u̇]`` (the truth simulators, lag states after them).
    """

    n_modes: int
    interleaved: bool

    @property
    def displacements(self) -> np.ndarray:
        """Indices of ``u_1 .. u_N`` in the state vector."""
        i = np.arange(self.n_modes)
        return 2 * i if self.interleaved else i

    @property
    def velocities(self) -> np.ndarray:
        """Indices of ``u̇_1 .. u̇_N`` in the state vector."""
        i = np.arange(self.n_modes)
        return 2 * i + 1 if self.interleaved else self.n_modes + i

    @property
    def mode_states(self) -> list[np.ndarray]:
        """State indices ``[u_i, u̇_i]`` of each mode (for eigenvector participation)."""
        return [np.array([d, v]) for d, v in zip(self.displacements, self.velocities)]

    def vector(self, state: ModalState) -> np.ndarray:
        """The ``2N`` structural entries of the state vector holding ``state``.

        Parameters
        ----------
        state : ModalState

        Returns
        -------
        numpy.ndarray
            Shape ``(2N,)``.

        Raises
        ------
        DimensionError
            ``state`` is not a :class:`ModalState` of ``N`` modes.
        """
        if not isinstance(state, ModalState):
            raise DimensionError(f"expected a ModalState, got {type(state).__name__}; build "
                                 "one with modal_state(u, udot) or displaced_state(mode, d)")
        if state.n_modes != self.n_modes:
            raise DimensionError(f"the state has {state.n_modes} modes, the model has "
                                 f"{self.n_modes}")
        x = np.zeros(2 * self.n_modes)
        x[self.displacements] = state.u
        x[self.velocities] = state.udot
        return x

    def state(self, x) -> ModalState:
        """The :class:`ModalState` held by a state vector of this layout.

        Parameters
        ----------
        x : array_like
            The model's state vector (its first ``2N`` entries are the structure's).

        Returns
        -------
        ModalState
        """
        x = np.asarray(x, dtype=float).ravel()
        if x.size < 2 * self.n_modes:
            raise DimensionError(f"a state vector of {x.size} entries has no room for the "
                                 f"{2 * self.n_modes} structural states of {self.n_modes} modes")
        return ModalState(x[self.displacements], x[self.velocities])

    def initial(self, x0, size: int) -> np.ndarray:
        """An initial state of a model with ``size`` states in this layout.

        Parameters
        ----------
        x0 : ModalState or array_like or None
            A :class:`ModalState` (put where this layout keeps it, the rest zero), the
            model's own state vector (``size`` entries, or its first ``2N``: the rest zero),
            or ``None`` (zero).

        Returns
        -------
        numpy.ndarray
            Shape ``(size,)``.

        Raises
        ------
        DimensionError
            A vector of another length.
        """
        out = np.zeros(size)
        if x0 is None:
            return out
        if isinstance(x0, ModalState):
            out[:2 * self.n_modes] = self.vector(x0)
            return out
        x = np.asarray(x0, dtype=float).ravel()
        if x.size not in (2 * self.n_modes, size):
            raise DimensionError(f"x0 has {x.size} entries; give a ModalState, the "
                                 f"{2 * self.n_modes} structural states or all {size} states")
        out[:x.size] = x
        return out


class ModalStates:
    """``modal_state`` and ``displaced_state`` of a model of ``n_modes`` structural modes
    (Σs and the truths): each builds a :class:`ModalState`, which the model's simulation
    puts where its ``layout`` keeps it."""

    n_modes: int

    def modal_state(self, u=None, udot=None) -> ModalState:
        """The structural state of given modal displacements and velocities.

        Parameters
        ----------
        u, udot : array_like, shape (N,), optional
            Modal displacements and velocities (default zero).

        Returns
        -------
        ModalState
            Right for every model of these modes: each simulation puts it where its own
            model keeps it (``layout.vector(state)``).

        Raises
        ------
        DimensionError
            ``u`` or ``udot`` not of length ``N``.
        """
        return ModalState(_modal_vector(u, self.n_modes, "u"),
                          _modal_vector(udot, self.n_modes, "udot"))

    def displaced_state(self, mode: int, deflection: float) -> ModalState:
        """The structure at rest with mode ``mode`` displaced by ``deflection``.

        Parameters
        ----------
        mode : int
            0-based mode index.
        deflection : float
            Modal displacement ``u_mode``.

        Returns
        -------
        ModalState
            An initial state of any simulation of these modes (the flow at rest).

        Raises
        ------
        DimensionError
            ``mode`` is not one of the ``N`` modes.
        """
        if not 0 <= int(mode) < self.n_modes:
            raise DimensionError(f"mode {mode} is not one of the {self.n_modes} modes (0-based)")
        u = np.zeros(self.n_modes)
        u[int(mode)] = deflection
        return self.modal_state(u)
