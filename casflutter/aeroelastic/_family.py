"""Plant families: a linear plant at every speed of a range, the one concept every analysis takes.

The paper's loop ΣAE(V) (eq. 8-9) is one plant per speed index, with the modal disturbances
``w`` and the flap ``v`` as inputs and the sensors ``zm`` as outputs.  An aircraft's
aeroservoelastic model is the same thing in another form: linear state-space models at a grid
of flight speeds, several control surfaces and sensors.  :class:`PlantFamily` is what both
are to the analyses (flutter, verification, design, exports):

* :meth:`PlantFamily.plant` — the plant at a speed, a ``control.StateSpace`` whose inputs and
  outputs are named (:class:`FamilySignals`);
* the roles of the signals: which inputs a controller drives (``controls``, the rest are
  disturbances) and which outputs it reads (``measurements``);
* the speed range, the units of speed and time, and the sign convention with which a
  controller is applied (``feedback``: ``"positive"``, ``u = +K y``, the paper's ``v = K zm``;
  ``"negative"``, ``u = −K y``, MATLAB's ``feedback(P, K)``);
* what the family offers an exact analysis: ``speed_degree``, the degree in V of the plant's
  matrices between the ``breakpoints`` (2 for strip theory's ΣAE(V), 1 between the grid
  speeds of a linearly interpolated grid, ``None`` when unknown).

A family is asked for what it offers, never for its class: the analyses read these
attributes and call :meth:`PlantFamily.plant`.
"""

from __future__ import annotations

import abc
import difflib
import math
from dataclasses import dataclass

import control
import numpy as np

from .._format import result_repr
from ..data import check_grid_speeds, check_stack, check_state_stack
from ..errors import ConfigError, DimensionError

__all__ = ["FEEDBACK_SIGNS", "FamilySignals", "PlantFamily", "MatrixFamily", "GriddedFamily",
           "RealisationGap"]

#: The sign ``s`` of ``u = s K y`` for each feedback convention.
FEEDBACK_SIGNS = {"positive": 1.0, "negative": -1.0}


def _names(what: str, names) -> tuple[str, ...]:
    out = tuple(str(n) for n in names)
    dup = sorted({n for n in out if out.count(n) > 1})
    if dup:
        raise ConfigError(f"{what}: the names {dup} appear more than once; every signal "
                          "needs its own name")
    if any(not n.strip() for n in out):
        raise ConfigError(f"{what}: an empty name; every signal needs a name")
    padded = [n for n in out if n != n.strip()]
    if padded:
        raise ConfigError(f"{what}: the names {padded} have blanks around them; names are "
                          f"matched exactly, so give them without: {[n.strip() for n in padded]} "
                          "(as a family file reads them)")
    return out


def _subset(what: str, names: tuple, pool: tuple, pool_what: str) -> None:
    unknown = [n for n in names if n not in pool]
    if unknown:
        hints = {n: difflib.get_close_matches(n, pool, 1) for n in unknown}
        hint = "; ".join(f"{n!r}: did you mean {h[0]!r}?" for n, h in hints.items() if h)
        raise ConfigError(f"{what}: {unknown} are not among the {pool_what} {list(pool)}"
                          + (f" ({hint})" if hint else ""))


def _positions(names, default: tuple, pool: tuple, pool_what: str) -> list[int]:
    """Positions in ``pool`` of ``names`` (``None``: ``default``), checked by :func:`_subset`."""
    names = default if names is None else tuple(names)
    _subset(f"{pool_what} asked for", names, pool, pool_what)
    return [pool.index(n) for n in names]


@dataclass(frozen=True)
class FamilySignals:
    """Names, roles and units of a family's inputs and outputs.

    Parameters
    ----------
    inputs, outputs : sequence of str
        Every input and output of the plant, in the plant's order (unique names, without
        surrounding blanks).
    controls : sequence of str, optional
        The inputs a controller drives (control surfaces, or their servo commands); default
        all inputs.  The other inputs are disturbances.
    measurements : sequence of str, optional
        The outputs a controller reads (sensors); default all outputs.
    input_units, output_units : sequence of str, optional
        A unit per input and output (``""`` where unknown; default all unknown).

    Raises
    ------
    ConfigError
        Repeated or empty names, names with blanks around them, roles naming signals the
        plant does not have, units of the wrong length, or no control input or no
        measurement.
    """

    inputs: tuple
    outputs: tuple
    controls: tuple | None = None
    measurements: tuple | None = None
    input_units: tuple = ()
    output_units: tuple = ()

    def __post_init__(self):
        inputs, outputs = _names("inputs", self.inputs), _names("outputs", self.outputs)
        controls = inputs if self.controls is None else _names("controls", self.controls)
        measurements = (outputs if self.measurements is None
                        else _names("measurements", self.measurements))
        _subset("controls", controls, inputs, "inputs")
        _subset("measurements", measurements, outputs, "outputs")
        if not controls or not measurements:
            raise ConfigError("a plant family needs at least one control input and one "
                              f"measurement; got controls {list(controls)} and measurements "
                              f"{list(measurements)}")
        units = {}
        for what, given, names in (("input_units", self.input_units, inputs),
                                   ("output_units", self.output_units, outputs)):
            given = tuple(str(u) for u in given)
            if given and len(given) != len(names):
                raise ConfigError(f"{what} has {len(given)} entries for {len(names)} "
                                  "signals; give one unit per signal (\"\" where unknown)")
            units[what] = given or ("",) * len(names)
        for name, value in (("inputs", inputs), ("outputs", outputs), ("controls", controls),
                            ("measurements", measurements), *units.items()):
            object.__setattr__(self, name, value)

    def __repr__(self) -> str:
        return (f"FamilySignals(controls={list(self.controls)}, "
                f"disturbances={list(self.disturbances)}, "
                f"measurements={list(self.measurements)}, "
                f"other outputs={[o for o in self.outputs if o not in self.measurements]})")

    @property
    def disturbances(self) -> tuple[str, ...]:
        """The inputs that are not controls."""
        return tuple(n for n in self.inputs if n not in self.controls)

    def input_index(self, names=None) -> list[int]:
        """Positions of inputs in the plant (default: the controls).

        Parameters
        ----------
        names : sequence of str, optional
            Input names, in the order wanted.

        Returns
        -------
        list of int
            Column indices into the plant's ``B`` and ``D``.

        Raises
        ------
        ConfigError
            A name the plant does not have (with the closest one).
        """
        return _positions(names, self.controls, self.inputs, "inputs")

    def output_index(self, names=None) -> list[int]:
        """Positions of outputs in the plant (default: the measurements).

        Parameters
        ----------
        names : sequence of str, optional
            Output names, in the order wanted.

        Returns
        -------
        list of int
            Row indices into the plant's ``C`` and ``D``.

        Raises
        ------
        ConfigError
            As :meth:`input_index`, for an output name.
        """
        return _positions(names, self.measurements, self.outputs, "outputs")


class PlantFamily(abc.ABC):
    """A linear plant ``P(V)`` at every speed ``V`` of a range (module docstring).

    A subclass defines :meth:`plant` and :attr:`signals`; it sets the class attributes below
    where the defaults do not hold (a frozen dataclass may make any of them a field).

    Attributes
    ----------
    speed_range : tuple of float
        ``(lo, hi)``: the speeds at which :meth:`plant` is defined (``hi`` may be ``inf``).
    speed_unit : str
        Unit of V (``"speed index"`` for a problem's nondimensional speed, ``"m/s"``, ...).
    time_unit : str
        Unit of time of the plant (its frequencies are in rad per this unit).
    feedback : str
        How a controller ``K`` of this family is applied: ``"positive"`` (``u = +K y``, the
        paper's ``v = K zm``) or ``"negative"`` (``u = −K y``).
    speed_degree : int or None
        The plant's matrices are polynomials of this degree in V on each piece between
        :attr:`breakpoints` (``None``: not known to be polynomial).
    breakpoints : tuple of float
        Interior speeds where the polynomial pieces meet (``()``: one piece).
    name : str
        A name for messages and reports.
    """

    speed_range: tuple = (0.0, math.inf)
    speed_unit: str = "speed index"
    time_unit: str = "s"
    feedback: str = "positive"
    speed_degree: int | None = None
    breakpoints: tuple = ()
    name: str = "plant family"

    @property
    @abc.abstractmethod
    def signals(self) -> FamilySignals:
        """Names, roles and units of the plant's inputs and outputs."""

    @abc.abstractmethod
    def plant(self, V: float) -> control.StateSpace:
        """The linear plant at speed V.

        Parameters
        ----------
        V : float
            Speed, in :attr:`speed_unit`, inside :attr:`speed_range`.

        Returns
        -------
        control.StateSpace
            Continuous, inputs and outputs in the order and with the names of
            :attr:`signals`; the same states at every speed.
        """

    # ----------------------------------------------------------------- derived from plant()
    @property
    def feedback_sign(self) -> float:
        """``+1`` or ``−1``: ``u = feedback_sign · K y``."""
        return FEEDBACK_SIGNS[self.feedback]

    def state_matrix(self, V: float) -> np.ndarray:
        """The open-loop state matrix at V (what flutter tracking follows).

        Parameters
        ----------
        V : float
            Speed.

        Returns
        -------
        ndarray
        """
        return np.asarray(self.plant(V).A, dtype=float)

    def control_plant(self, V: float, controls=None, measurements=None) -> control.StateSpace:
        """The plant at V from (some of) the controls to (some of) the measurements.

        Parameters
        ----------
        V : float
            Speed.
        controls, measurements : sequence of str, optional
            Names (default: all controls, all measurements), in the order wanted.

        Returns
        -------
        control.StateSpace
            Named inputs and outputs.
        """
        sig = self.signals
        controls = sig.controls if controls is None else tuple(controls)
        measurements = sig.measurements if measurements is None else tuple(measurements)
        i, o = sig.input_index(controls), sig.output_index(measurements)
        P = self.plant(V)
        A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (P.A, P.B, P.C, P.D))
        return control.ss(A, B[:, i], C[o, :], D[np.ix_(o, i)], inputs=list(controls),
                          outputs=list(measurements))

    def check_speed(self, V: float, what: str = "V") -> float:
        """``V`` as a float, or an error naming the range.

        Parameters
        ----------
        V : float
            A speed.
        what : str
            Its name in the message.

        Returns
        -------
        float

        Raises
        ------
        ConfigError
            ``V`` not a finite number inside :attr:`speed_range`.
        """
        lo, hi = self.speed_range
        try:
            v = float(V)
        except (TypeError, ValueError):
            raise ConfigError(f"{what} = {V!r} is not a number") from None
        tol = 1e-12 * max(1.0, abs(lo), abs(hi) if math.isfinite(hi) else 1.0)
        if not (math.isfinite(v) and lo - tol <= v <= hi + tol):
            raise ConfigError(f"{what} = {V!r} {self.speed_unit} is outside the range "
                              f"[{lo:g}, {hi:g}] of {self.name}")
        return min(max(v, lo), hi)

    def speed_grid(self, n: int, lo: float | None = None, hi: float | None = None
                   ) -> np.ndarray:
        """``n`` evenly spaced speeds of ``[lo, hi]`` (default the range), with the
        breakpoints inside it added.

        Parameters
        ----------
        n : int
            Number of evenly spaced speeds (>= 2).
        lo, hi : float, optional
            Ends (default :attr:`speed_range`; a finite ``hi`` is needed).

        Returns
        -------
        ndarray
            Sorted, unique.
        """
        lo = self.speed_range[0] if lo is None else self.check_speed(lo, "lo")
        hi = self.speed_range[1] if hi is None else self.check_speed(hi, "hi")
        if not (math.isfinite(hi) and hi > lo and int(n) >= 2):
            raise ConfigError(f"a speed grid needs lo < hi (finite) and n >= 2; got "
                              f"[{lo}, {hi}], n = {n}")
        inner = [b for b in self.breakpoints if lo < b < hi]
        return np.unique(np.concatenate([np.linspace(lo, hi, int(n)), inner]))

    @property
    def n_states(self) -> int:
        """Number of states (the same at every speed)."""
        lo, hi = self.speed_range
        return int(self.plant(0.5 * (lo + hi) if math.isfinite(hi) else max(lo, 1.0)).nstates)

    def describe(self) -> str:
        """One paragraph: the name, range, states and signals.

        Returns
        -------
        str
        """
        s, (lo, hi) = self.signals, self.speed_range
        gone = getattr(self, "left_out_states", ())
        states = (f"{self.n_states} states ({len(gone)} more left out, which feed no output: "
                  f"states {list(gone)})" if gone else f"{self.n_states} states")
        return (f"{self.name}: {states}, speeds [{lo:g}, {hi:g}] "
                f"{self.speed_unit}, time in {self.time_unit}, {self.feedback} feedback; "
                f"controls {list(s.controls)}, measurements {list(s.measurements)}"
                + (f", disturbances {list(s.disturbances)}" if s.disturbances else ""))


class MatrixFamily(PlantFamily):
    """A family that computes its plant's matrices at each speed (:meth:`matrices`): the
    named plant and the state matrix follow from them."""

    @abc.abstractmethod
    def matrices(self, V: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` at speed V.

        Parameters
        ----------
        V : float
            Speed inside :attr:`speed_range`.

        Returns
        -------
        tuple of ndarray
        """

    def plant(self, V: float) -> control.StateSpace:
        """The plant of :meth:`matrices` at speed V, inputs and outputs named by
        :attr:`signals`; see :meth:`PlantFamily.plant`."""
        s = self.signals
        return control.ss(*self.matrices(V), inputs=list(s.inputs), outputs=list(s.outputs))

    def state_matrix(self, V: float) -> np.ndarray:
        """``A`` of :meth:`matrices` at speed V; see :meth:`PlantFamily.state_matrix`."""
        return self.matrices(V)[0]


@dataclass(frozen=True)
class RealisationGap:
    """A grid interval of a :class:`GriddedFamily` across which the states seem to change
    meaning (:meth:`GriddedFamily.realisation_gaps`).

    Attributes
    ----------
    lo, hi : float
        The grid speeds at its ends.
    pole_distance : float
        How far (relative) the farthest pole of the plant interpolated halfway lies from
        every pole of both ends.
    """

    __repr__ = result_repr

    lo: float
    hi: float
    pole_distance: float


def _read_only(M: np.ndarray) -> np.ndarray:
    M.setflags(write=False)
    return M


def _tolerance(tol) -> float:
    try:
        t = float(tol)
    except (TypeError, ValueError):
        t = math.nan
    if not (math.isfinite(t) and t >= 0):
        raise ConfigError(f"tol = {tol!r}: give a finite relative tolerance >= 0 (e.g. 1e-10)")
    return t


def _state_indices(indices, n: int) -> list[int]:
    """Sorted unique state indices, each an integer in ``[0, n)``."""
    out = set()
    for i in indices:
        if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer)):
            raise ConfigError(f"state index {i!r} is not an integer; give 0-based indices "
                              f"of the {n} states")
        if not 0 <= int(i) < n:
            raise ConfigError(f"state index {int(i)} is out of range; the family has {n} "
                              f"states, indexed 0 to {n - 1}")
        out.add(int(i))
    return sorted(out)


class GriddedFamily(MatrixFamily):
    """A plant family given at a grid of speeds, linearly interpolated between them.

    The state-space matrices are interpolated elementwise between neighbouring grid speeds,
    so on each interval between grid speeds the plant is affine in V
    (``speed_degree = 1``, the grid speeds are the breakpoints): a closed loop's exact
    stable interval can be certified piece by piece.  The states must mean the same thing at
    every grid speed (the same realisation), as they do in a model exported on a grid of
    flight conditions; :meth:`realisation_gaps` names the intervals where they seem not to.

    Parameters
    ----------
    speeds : array_like, shape (k,)
        Grid speeds, strictly increasing, k >= 2.
    A, B, C, D : array_like
        Shapes ``(k, n, n)``, ``(k, n, m)``, ``(k, p, n)``, ``(k, p, m)``.
    signals : FamilySignals, optional
        Names, roles and units (default: inputs ``u1..um``, all controls; outputs
        ``y1..yp``, all measurements).
    speed_unit, time_unit, feedback, name : str
        As :class:`PlantFamily`.

    Attributes
    ----------
    left_out_states : tuple of int
        The states of the family this one was made from that :meth:`without_states` left
        out (0-based indices into the original family's states, sorted; ``()`` for a family
        built from its arrays).  :func:`~casflutter.aeroelastic.load_family` leaves out a
        family file's rigid-body positions (:meth:`detached_states`).
    left_out_eigenvalues : ndarray, shape (k, len(left_out_states))
        The eigenvalues of the left-out block of the state matrix at each grid speed (row
        ``j``: ``speeds[j]``), sorted by real part and then imaginary part within a row;
        every closed loop of the original family has them besides the eigenvalues of this
        family's loop.  Read-only; no columns when nothing was left out.

    Raises
    ------
    DimensionError
        Arrays that are ragged, not finite, or of inconsistent sizes (named); no states
        (``n = 0``: a static plant has no flutter).
    ConfigError
        Speeds not strictly increasing or not finite, an unknown feedback convention, or
        signals that do not match the sizes.
    """

    speed_degree = 1

    def __init__(self, speeds, A, B, C, D, signals: FamilySignals | None = None, *,
                 speed_unit: str = "m/s", time_unit: str = "s", feedback: str = "negative",
                 name: str = "gridded plant family"):
        v = check_grid_speeds(speeds)
        k = v.size
        A = check_state_stack(A, k)
        n = A.shape[1]
        B = check_stack("B", B, k, n, None)
        C = check_stack("C", C, k, None, n)
        D = check_stack("D", D, k, C.shape[1], B.shape[2])
        m, p = B.shape[2], C.shape[1]
        if signals is None:
            signals = FamilySignals([f"u{i + 1}" for i in range(m)],
                                    [f"y{j + 1}" for j in range(p)])
        if len(signals.inputs) != m or len(signals.outputs) != p:
            raise ConfigError(f"the signals name {len(signals.inputs)} inputs and "
                              f"{len(signals.outputs)} outputs, the arrays have {m} inputs "
                              f"(B, D) and {p} outputs (C, D)")
        if feedback not in FEEDBACK_SIGNS:
            raise ConfigError(f"feedback = {feedback!r}: 'negative' (u = -K y, MATLAB's "
                              "feedback()) or 'positive' (u = +K y, the paper's v = K zm)")
        self.speeds, self._mats, self._signals = v, (A, B, C, D), signals
        self.speed_unit, self.time_unit = str(speed_unit), str(time_unit)
        self.feedback, self.name = feedback, str(name)
        self.speed_range = (float(v[0]), float(v[-1]))
        self.breakpoints = tuple(float(x) for x in v[1:-1])
        self.left_out_states: tuple[int, ...] = ()
        self.left_out_eigenvalues = _read_only(np.empty((k, 0), dtype=complex))

    @property
    def signals(self) -> FamilySignals:
        """Names, roles and units of the plant's inputs and outputs."""
        return self._signals

    @property
    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` stacked over the grid (copies)."""
        return tuple(M.copy() for M in self._mats)

    def _weights(self, V: float) -> tuple[int, float]:
        v = self.check_speed(V)
        j = int(min(max(np.searchsorted(self.speeds, v, side="right") - 1, 0),
                    self.speeds.size - 2))
        return j, (v - self.speeds[j]) / (self.speeds[j + 1] - self.speeds[j])

    def matrices(self, V: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` at V, interpolated elementwise.

        Parameters
        ----------
        V : float
            Speed inside the grid's range.

        Returns
        -------
        tuple of ndarray
        """
        j, t = self._weights(V)
        return tuple((1.0 - t) * M[j] + t * M[j + 1] for M in self._mats)

    @property
    def n_states(self) -> int:
        """Number of states."""
        return int(self._mats[0].shape[1])

    def detached_states(self, tol: float = 1e-10) -> tuple[int, ...]:
        """The states that feed neither an output nor any state outside them, at every speed.

        An aircraft's rigid-body positions (plunge and lateral displacement, yaw angle,
        altitude) are such states: translation does not change the aerodynamics and no
        accelerometer or gyro measures position, so the state's column of ``C`` and its
        column of ``A`` outside the set are zero, and its eigenvalue is 0.  With ``R`` these
        states and ``K`` the others, ``A[K, R] = 0`` and ``C[:, R] = 0``: every transfer
        function from the inputs to the outputs is that of ``(A[K, K], B[K], C[:, K], D)``,
        and a closed loop's state matrix is block triangular, so its eigenvalues are those of
        the loop closed on the kept states and those of ``A[R, R]``, which no controller
        changes (:meth:`without_states` leaves them out).

        The set is the largest one, found as a fixed point: start from the states whose
        column of ``C`` is zero at every grid speed and remove, until none is left to
        remove, every state that feeds a state outside the set at some grid speed.  A state
        that feeds only detached states (a yaw angle that feeds only the lateral
        displacement) is detached too.

        Parameters
        ----------
        tol : float
            Relative tolerance: an entry counts as zero when ``|A[i, j]| <= tol · max |A|``
            and ``|C[i, j]| <= tol · max |C|``, each maximum taken over every entry at every
            grid speed (so a model's units of the states and outputs enter only through
            these two scales).

        Returns
        -------
        tuple of int
            0-based state indices (into ``A``'s rows and columns), sorted; ``()`` when
            every state feeds an output, directly or through other states.

        Raises
        ------
        ConfigError
            ``tol`` not a finite number >= 0.
        """
        tol = _tolerance(tol)
        A, _, C, _ = self._mats
        absA, absC = np.abs(A), np.abs(C)
        feeds = absA.max(axis=0) > tol * float(absA.max())      # [i, j]: x_j feeds x_i
        detached = ~(absC.max(axis=(0, 1)) > tol * float(absC.max()))
        while True:
            bad = detached & feeds[~detached].any(axis=0)
            if not bad.any():
                return tuple(int(j) for j in np.flatnonzero(detached))
            detached &= ~bad

    def without_states(self, indices, *, tol: float = 1e-10) -> GriddedFamily:
        """The same family with states that feed no output and no kept state left out.

        ``A`` loses their rows and columns, ``B`` their rows and ``C`` their columns; the
        signals, units, feedback convention, name and speeds stay.  Since the states left
        out feed no output and no kept state, every transfer function from the inputs to
        the outputs is unchanged, and every closed loop of this family has the eigenvalues
        of the new family's loop and those of the left-out block, which no controller moves
        (recorded in :attr:`left_out_eigenvalues`).

        Parameters
        ----------
        indices : sequence of int
            0-based indices of this family's states, e.g. :meth:`detached_states`.
        tol : float
            Relative tolerance of "feeds", as in :meth:`detached_states`.

        Returns
        -------
        GriddedFamily
            The family without these states (``self`` when ``indices`` is empty);
            :attr:`left_out_states` names them by their indices in the family this one
            was made from (those of the file, for a family of
            :func:`~casflutter.aeroelastic.load_family`).

        Raises
        ------
        ConfigError
            An index that is not an integer or out of range, every state asked for, or a
            state that feeds an output or a kept state (named, with the fix): leaving it
            out would change the plant.
        """
        tol = _tolerance(tol)
        n = self.n_states
        idx = _state_indices(indices, n)
        if not idx:
            return self
        if len(idx) == n:
            raise ConfigError(f"{self.name}: leaving out all {n} states leaves no plant; "
                              "name only the states that feed no output")
        gone = set(idx)
        keep = [j for j in range(n) if j not in gone]
        A, B, C, D = self._mats
        absA, absC = np.abs(A), np.abs(C)
        outputs = list(range(C.shape[1]))
        for M, key, rows in ((absA, "A", keep), (absC, "C", outputs)):
            sub = M[:, rows][:, :, idx]
            hit = np.argwhere(sub > tol * float(M.max()))
            if hit.size:
                s, r, c = (int(x) for x in hit[0])
                i, j = rows[r], idx[c]
                what = (f"state {i}, which is kept" if key == "A"
                        else f"the output {self.signals.outputs[i]!r}")
                raise ConfigError(
                    f"{self.name}: state {j} (0-based) feeds {what} (|{key}[{i}, {j}]| = "
                    f"{M[s, i, j]:.3g} at V = {self.speeds[s]:g} {self.speed_unit}); leaving "
                    "it out would change the plant.  Only states that feed no output and no "
                    "kept state can be left out: those of detached_states()")
        fam = GriddedFamily(self.speeds, A[:, keep][:, :, keep], B[:, keep], C[:, :, keep], D,
                            self.signals, speed_unit=self.speed_unit,
                            time_unit=self.time_unit, feedback=self.feedback, name=self.name)
        before = set(self.left_out_states)
        original = [i for i in range(n + len(before)) if i not in before]
        fam.left_out_states = tuple(sorted(before | {original[j] for j in idx}))
        block = A[:, idx][:, :, idx].copy()
        block[np.abs(block) <= tol * float(absA.max())] = 0.0      # rounding: exactly zero
        lam = np.linalg.eigvals(block).astype(complex)
        fam.left_out_eigenvalues = _read_only(       # lexicographic: real part, then imaginary
            np.sort(np.concatenate([self.left_out_eigenvalues, lam], axis=1), axis=1))
        return fam

    def realisation_gaps(self, *, ends_tol: float = 0.1, middle_tol: float = 0.3
                         ) -> tuple[RealisationGap, ...]:
        """Grid intervals across which the states seem to change meaning.

        Interpolating the matrices elementwise is meaningful only when the states are the
        same at every grid speed.  A family exported speed by speed in coordinates of its
        own (a modal basis re-normalised or re-ordered at each speed, a minimal realisation
        per speed) gives neighbouring plants with nearly the same poles whose matrices
        are unrelated: halfway between them the interpolated plant is a system that exists
        at neither speed, and the analyses would certify or design on it.  An interval is
        named when every pole of each end lies within ``ends_tol`` (relative) of a pole of
        the other end, yet the plant interpolated halfway has a pole farther than
        ``middle_tol`` from every pole of both ends.  In one realisation the poles move
        continuously with the matrices (by at most the matrices' change, for
        well-conditioned eigenvectors), so this does not happen; an interval whose ends'
        poles differ by more than ``ends_tol`` is not judged.

        Parameters
        ----------
        ends_tol, middle_tol : float
            Relative pole distances (to ``max(|λ|, 1e-3 max |λ|)``: poles near the origin,
            such as an aircraft's rigid-body modes, count in absolute terms).

        Returns
        -------
        tuple of RealisationGap
            One per named interval, in speed order (empty for a family in one
            realisation).
        """
        A = self._mats[0]
        ends = [np.linalg.eigvals(a) for a in A]
        size = max(float(np.max(np.abs(lam))) for lam in ends) if ends[0].size else 0.0
        floor = max(1e-3 * size, np.finfo(float).tiny)

        def far(lam, ref):
            # relative distance of each of lam to the nearest of ref
            d = np.min(np.abs(lam[:, None] - ref[None, :]), axis=1)
            return d / np.maximum(np.abs(lam), floor)

        gaps = []
        for j in range(self.speeds.size - 1):
            a, b = ends[j], ends[j + 1]
            if a.size == 0 or max(far(a, b).max(), far(b, a).max()) > ends_tol:
                continue
            mid = np.linalg.eigvals(0.5 * (A[j] + A[j + 1]))
            worst = float(far(mid, np.concatenate([a, b])).max())
            if worst > middle_tol:
                gaps.append(RealisationGap(float(self.speeds[j]), float(self.speeds[j + 1]),
                                           worst))
        return tuple(gaps)

    def __repr__(self) -> str:
        s = self.signals
        return (f"GriddedFamily({self.name!r}: {self.n_states} states, "
                f"{len(s.inputs)} inputs, {len(s.outputs)} outputs, {self.speeds.size} speeds "
                f"[{self.speed_range[0]:g}, {self.speed_range[1]:g}] {self.speed_unit})")
