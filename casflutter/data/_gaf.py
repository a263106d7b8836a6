"""Generalised aerodynamic forces in the frequency domain, ``Q(ik)``, and their files.

What a doublet-lattice code, NASTRAN SOL145/146, ZAERO or strip theory gives: the complex
matrices ``Q(ik)`` at a set of reduced frequencies ``k = omega b / U`` (``b`` the reference
semichord).  casflutter keeps them in the normalisation of the paper's eq. (6):

    u'' + 2 zeta omega u' + omega^2 u = alpha V^2 y,    y = Q(ik) [u; v],

for harmonic modal motion ``u`` and flap ``v`` (radians) at ``k``, with ``V = U / U_ref`` the
speed index and ``alpha`` the flow constant of the modal data.  ``Q`` is dimensionless in the
sense of eq. (6) and depends on ``k`` only.  Columns ``1..N`` are the modes, column ``N + 1``
(optional) the flap.

From NASTRAN's convention ``M u'' + C u' + K u = q_dyn Q_N(ik) [u; v]`` with
``q_dyn = rho U^2 / 2`` and generalised masses ``M``, :meth:`GAFTable.from_dynamic_pressure`
converts: ``Q = (rho U_ref^2 / (2 alpha)) M^-1 Q_N``.

File layouts (all three round-trip through :meth:`GAFTable.save` / :func:`load_gaf`):

NPZ (``numpy.savez``, read with ``allow_pickle=False``)
    ``k`` ``(nk,)`` float, strictly increasing, ``>= 0``; ``Q`` ``(nk, N, M)`` complex,
    ``M = N`` or ``N + 1``; ``b`` scalar [m]; optional ``U_ref`` [m/s], ``rho`` [kg/m^3],
    ``mode_names`` ``(N,)`` unicode strings, ``source`` unicode string.
CSV (long format, one matrix element per line)
    ``#`` comment lines ``# key = value`` with JSON values carry the scalars
    (``# b = 0.9144``, ``# U_ref = 79.6``, ``# rho = 1.225``,
    ``# mode_names = ["bending 1", "torsion 1"]``, ``# source = "..."``), then the header
    ``k,row,col,real,imag`` and one line per ``(k, row, col)``; ``row`` and ``col`` are
    1-based, ``col = N + 1`` is the flap; every element at every ``k`` exactly once.
MATLAB ``.mat`` (``scipy.io``)
    ``k`` (vector), ``Q`` complex ``N x M x nk`` (the MATLAB habit ``Q(:, :, n)`` per
    frequency), ``b`` scalar; optional ``U_ref``, ``rho``, ``mode_names`` (cell array of
    strings or char matrix), ``source``.

Bad files and arrays raise :class:`casflutter.errors.DataError` naming the array and the fix.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
from scipy.interpolate import make_interp_spline
from scipy.io import savemat

from .._format import result_repr
from ..errors import DataError
from ._matfile import mat_strings, read_mat

__all__ = ["GAFTable", "load_gaf"]

_CSV_HEADER = ("k", "row", "col", "real", "imag")
_CSV_KEYS = ("b", "U_ref", "rho", "mode_names", "source")


def _positive_scalar(name: str, value, *, optional: bool) -> float | None:
    if value is None:
        if optional:
            return None
        raise DataError(f"{name} is missing: give the reference {name} (a positive number)")
    arr = np.asarray(value)
    if arr.size != 1:
        raise DataError(f"{name} must be a scalar, got an array of shape {arr.shape}")
    try:
        x = float(np.real_if_close(arr.ravel()[0]))
    except (TypeError, ValueError):
        raise DataError(f"{name} = {value!r} is not a number") from None
    if not np.isfinite(x) or x <= 0:
        raise DataError(f"{name} = {x} must be a positive finite number")
    return x


@dataclass(frozen=True)
class GAFTable:
    """A table of generalised aerodynamic forces ``Q(ik)`` (module docstring).

    Parameters
    ----------
    k : array_like, shape (nk,)
        Reduced frequencies ``omega b / U``, strictly increasing, ``>= 0``.
    Q : array_like, shape (nk, N, M)
        Complex ``Q(ik)`` in the eq. (6) normalisation; ``M = N`` (modes only) or ``N + 1``
        (last column the flap, per radian).
    b : float
        Reference semichord [m] of ``k``.
    U_ref : float, optional
        Airspeed per unit speed index [m/s] (``V = U / U_ref``); needed to put the
        aeroelastic system in m/s.
    rho : float, optional
        Air density [kg/m^3] the table belongs to (for the record; ``Q`` itself does not
        depend on it in this normalisation).
    mode_names : tuple of str, optional
        One name per mode (default ``"mode 1"``, ...).
    source : str, optional
        Free-text provenance.

    Raises
    ------
    DataError
        Non-increasing, negative or non-finite ``k``; real, non-finite or mis-shaped ``Q``;
        non-positive ``b``; ``mode_names`` of the wrong length.
    """

    __repr__ = result_repr

    k: np.ndarray
    Q: np.ndarray
    b: float
    U_ref: float | None = None
    rho: float | None = None
    mode_names: tuple[str, ...] = ()
    source: str = field(default="", compare=False)

    def __post_init__(self):
        k = np.asarray(self.k)
        if k.ndim == 2 and 1 in k.shape:
            k = k.ravel()
        if k.ndim != 1 or k.size < 1:
            raise DataError(f"k must be a 1-D array of reduced frequencies, got shape {k.shape}")
        if np.iscomplexobj(k):
            raise DataError("k must be real (reduced frequencies omega b / U), got complex values")
        try:
            k = k.astype(float)
        except (TypeError, ValueError):
            raise DataError(f"k must be numeric, got dtype {k.dtype}") from None
        bad = ~np.isfinite(k)
        if bad.any():
            raise DataError(f"k has NaN/inf at index {int(np.argmax(bad))}; remove that "
                            "frequency from the table")
        if np.any(k < 0):
            raise DataError(f"k has a negative value ({k.min():g}); reduced frequencies are "
                            ">= 0 (Q(-ik) is the complex conjugate of Q(ik))")
        dk = np.diff(k)
        if np.any(dk <= 0):
            i = int(np.argmax(dk <= 0)) + 1
            raise DataError(f"k must be strictly increasing: k[{i}] = {k[i]:g} follows "
                            f"k[{i - 1}] = {k[i - 1]:g}; sort the table by k and drop duplicates")
        Q = np.asarray(self.Q)
        if not np.iscomplexobj(Q):
            raise DataError(f"Q has real dtype {Q.dtype}; Q(ik) must be complex: store "
                            "Q = Q_real + 1j * Q_imag (complex128)")
        Q = Q.astype(complex)
        if Q.ndim == 2 and k.size == 1:
            Q = Q[None]
        if Q.ndim != 3:
            raise DataError(f"Q must have shape (nk, N, M) = ({k.size}, N, N or N+1), got "
                            f"{Q.shape}")
        nk, N, M = Q.shape
        if nk != k.size:
            raise DataError(f"Q has {nk} matrices but k has {k.size} values; give one "
                            "matrix Q[n] per reduced frequency k[n] (shape (nk, N, M))")
        if N < 1 or M not in (N, N + 1):
            raise DataError(f"each Q[n] is {N} x {M}; it must be N x N (modes) or N x (N+1) "
                            "(modes and the flap as the last column)")
        bad = ~np.isfinite(Q)
        if bad.any():
            n, i, j = (int(x) for x in np.argwhere(bad)[0])
            raise DataError(f"Q has {int(bad.sum())} NaN/inf entries, first Q[{n}] element "
                            f"({i + 1}, {j + 1}) at k = {k[n]:g}; recompute or drop that "
                            "frequency")
        object.__setattr__(self, "k", k)
        object.__setattr__(self, "Q", Q)
        object.__setattr__(self, "b", _positive_scalar("b", self.b, optional=False))
        object.__setattr__(self, "U_ref", _positive_scalar("U_ref", self.U_ref, optional=True))
        object.__setattr__(self, "rho", _positive_scalar("rho", self.rho, optional=True))
        names = tuple(str(s).strip() for s in self.mode_names)
        if not names:
            names = tuple(f"mode {i + 1}" for i in range(N))
        if len(names) != N:
            raise DataError(f"mode_names has {len(names)} names for N = {N} modes; give one "
                            "name per row of Q")
        object.__setattr__(self, "mode_names", names)
        object.__setattr__(self, "source", str(self.source))

    # -- shape --------------------------------------------------------------------------
    @property
    def n_modes(self) -> int:
        """Number of modes N (rows of Q)."""
        return int(self.Q.shape[1])

    @property
    def n_inputs(self) -> int:
        """Columns of Q: N, or N + 1 with the flap."""
        return int(self.Q.shape[2])

    @property
    def has_flap(self) -> bool:
        """True when the last column of Q is the flap."""
        return self.n_inputs == self.n_modes + 1

    @property
    def input_names(self) -> tuple[str, ...]:
        """Names of the columns of Q (the modes, then ``"flap"``)."""
        return self.mode_names + (("flap",) if self.has_flap else ())

    def without_flap(self) -> "GAFTable":
        """The same table without the flap column."""
        if not self.has_flap:
            return self
        return GAFTable(self.k, self.Q[:, :, :self.n_modes], self.b, self.U_ref, self.rho,
                        self.mode_names, self.source)

    # -- interpolation --------------------------------------------------------------------
    @cached_property
    def _spline(self):
        deg = min(3, self.k.size - 1)
        if deg < 1:
            raise DataError("interpolation in k needs at least two reduced frequencies")
        return make_interp_spline(self.k, self.Q, k=deg, axis=0)

    def interpolate(self, k, derivative: int = 0) -> np.ndarray:
        """``Q`` (or its ``derivative``-th k-derivative) at reduced frequencies inside the table.

        Cubic interpolating spline (not-a-knot) of every element in ``k``.

        Parameters
        ----------
        k : float or array_like
            Reduced frequencies in ``[k[0], k[-1]]``.
        derivative : int
            0 for ``Q``, 1 for ``dQ/dk``.

        Returns
        -------
        numpy.ndarray
            ``(N, M)`` for a scalar ``k``, else ``(nk, N, M)``.

        Raises
        ------
        DataError
            A ``k`` outside the table (no extrapolation).
        """
        kk = np.asarray(k, dtype=float)
        lo, hi = self.k[0], self.k[-1]
        tol = 1e-12 * max(hi, 1.0)
        if np.any(kk < lo - tol) or np.any(kk > hi + tol) or not np.all(np.isfinite(kk)):
            raise DataError(f"k = {kk.min():g}..{kk.max():g} lies outside the table "
                            f"[{lo:g}, {hi:g}]; extend the table's reduced frequencies")
        kk = np.clip(kk, lo, hi)
        spl = self._spline if derivative == 0 else self._spline.derivative(derivative)
        return spl(kk)

    # -- conversions ----------------------------------------------------------------------
    @classmethod
    def from_truth(cls, truth, k, *, theodorsen: str = "exact") -> "GAFTable":
        """The table of a truth simulator with ``generalized_aero_forces(k)`` (e.g. Goland).

        Parameters
        ----------
        truth : object
            Has ``generalized_aero_forces(k, theodorsen=...)``, ``params.b`` and
            ``modal_structure()`` (its mode names and speed convention: ``U_ref``, ``rho``).
        k : array_like
            Reduced frequencies.
        theodorsen : {"exact", "jones"}
            Passed to the truth.

        Returns
        -------
        GAFTable
        """
        Q = truth.generalized_aero_forces(k, theodorsen=theodorsen)
        structure = truth.modal_structure()
        return cls(np.asarray(k, float), Q, truth.params.b, U_ref=structure.speed.U_ref,
                   rho=structure.speed.rho, mode_names=structure.mode_names,
                   source=f"{type(truth).__name__} strip theory, {theodorsen} Theodorsen C(k)")

    @classmethod
    def from_dynamic_pressure(cls, k, Q_dyn, b: float, *, generalized_mass, alpha: float,
                              U_ref: float, rho: float, mode_names=(),
                              source: str = "") -> "GAFTable":
        """Convert NASTRAN-style ``M u'' + C u' + K u = q_dyn Q_N(ik) [u; v]`` to eq. (6).

        ``Q = (rho U_ref^2 / (2 alpha)) M^-1 Q_N`` so that ``alpha V^2 Q = q_dyn M^-1 Q_N``.

        Parameters
        ----------
        k, b, mode_names, source
            As in :class:`GAFTable`.
        Q_dyn : array_like, shape (nk, N, M)
            ``Q_N(ik)`` per unit dynamic pressure ``q_dyn = rho U^2 / 2``.
        generalized_mass : float or array_like
            ``M``: a scalar, the N diagonal generalised masses, or an ``N x N`` matrix
            (``1`` for mass-normalised modes).
        alpha : float
            Flow constant of the modal data (eq. 6).
        U_ref : float
            Airspeed per unit speed index [m/s].
        rho : float
            Air density [kg/m^3] of ``q_dyn``.

        Returns
        -------
        GAFTable
        """
        Qn = np.asarray(Q_dyn)
        if not np.iscomplexobj(Qn) or Qn.ndim != 3:
            raise DataError(f"Q_dyn must be a complex (nk, N, M) array, got dtype {Qn.dtype} "
                            f"and shape {Qn.shape}")
        N = Qn.shape[1]
        Mg = np.asarray(generalized_mass, dtype=float)
        Mg = Mg * np.eye(N) if Mg.ndim == 0 else (np.diag(Mg) if Mg.ndim == 1 else Mg)
        if Mg.shape != (N, N) or not np.all(np.isfinite(Mg)):
            raise DataError(f"generalized_mass must be a scalar, N = {N} values or an N x N "
                            f"matrix, got shape {Mg.shape}")
        a = _positive_scalar("alpha", alpha, optional=False)
        Ur = _positive_scalar("U_ref", U_ref, optional=False)
        r = _positive_scalar("rho", rho, optional=False)
        try:
            Minv = np.linalg.inv(Mg)
        except np.linalg.LinAlgError:
            raise DataError("generalized_mass is singular") from None
        Q = (r * Ur * Ur / (2.0 * a)) * np.einsum("ij,njm->nim", Minv, Qn)
        return cls(k, Q, b, U_ref=Ur, rho=r, mode_names=mode_names, source=source)

    # -- files ----------------------------------------------------------------------------
    def save(self, path) -> Path:
        """Write to ``.npz``, ``.csv`` or ``.mat`` (by the suffix; module docstring).

        Returns
        -------
        pathlib.Path
            The path written.
        """
        path = Path(path)
        writer = {".npz": self.to_npz, ".csv": self.to_csv, ".mat": self.to_mat}.get(
            path.suffix.lower())
        if writer is None:
            raise DataError(f"{path}: unknown suffix {path.suffix!r}; use .npz, .csv or .mat")
        writer(path)
        return path

    def _optional(self) -> dict:
        out = {}
        if self.U_ref is not None:
            out["U_ref"] = self.U_ref
        if self.rho is not None:
            out["rho"] = self.rho
        return out

    def to_npz(self, path) -> None:
        """Write the NPZ layout."""
        arrays = {"k": self.k, "Q": self.Q, "b": np.array(self.b),
                  "mode_names": np.array(self.mode_names, dtype=str),
                  "source": np.array(self.source, dtype=str)}
        arrays.update({key: np.array(v) for key, v in self._optional().items()})
        np.savez(path, **arrays)

    def to_csv(self, path) -> None:
        """Write the CSV layout (long format, ``repr`` precision)."""
        with open(path, "w", newline="") as fh:
            fh.write("# casflutter generalised aerodynamic forces Q(ik), eq. (6) normalisation\n")
            meta = {"b": self.b, **self._optional(), "mode_names": list(self.mode_names),
                    "source": self.source}
            for key, value in meta.items():
                fh.write(f"# {key} = {json.dumps(value)}\n")
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(_CSV_HEADER)
            nk, N, M = self.Q.shape
            for n in range(nk):
                for i in range(N):
                    for j in range(M):
                        q = self.Q[n, i, j]
                        w.writerow([repr(float(self.k[n])), i + 1, j + 1, repr(float(q.real)),
                                    repr(float(q.imag))])

    def to_mat(self, path) -> None:
        """Write the MATLAB layout (``Q`` as ``N x M x nk``)."""
        names = np.empty(self.n_modes, dtype=object)
        names[:] = list(self.mode_names)
        savemat(path, {"k": self.k[None, :], "Q": np.transpose(self.Q, (1, 2, 0)),
                       "b": self.b, "mode_names": names, "source": self.source,
                       **self._optional()})

    @classmethod
    def from_npz(cls, path) -> "GAFTable":
        """Read the NPZ layout (module docstring)."""
        path = Path(path)
        try:
            z = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise DataError(f"{path}: cannot read as .npz ({exc})") from None
        with z:
            keys = set(z.files)
            for name in ("k", "Q", "b"):
                if name not in keys:
                    raise DataError(f"{path}: no array {name!r} (arrays are {sorted(keys)}); "
                                    "the NPZ layout needs k (nk,), complex Q (nk, N, M) and b")
            opt = {key: z[key] for key in ("U_ref", "rho") if key in keys}
            names = tuple(str(s) for s in np.atleast_1d(z["mode_names"])) \
                if "mode_names" in keys else ()
            source = str(z["source"]) if "source" in keys else path.name
            return _from_file(path, z["k"], z["Q"], z["b"], names=names, source=source, **opt)

    @classmethod
    def from_csv(cls, path) -> "GAFTable":
        """Read the CSV layout (module docstring)."""
        path = Path(path)
        meta: dict = {}
        rows: list[tuple[int, list[str]]] = []
        header = None
        try:
            fh = open(path, newline="")
        except OSError as exc:
            raise DataError(f"{path}: cannot open ({exc})") from None
        with fh:
            for lineno, line in enumerate(fh, start=1):
                text = line.strip()
                if not text:
                    continue
                if text.startswith("#"):
                    body = text[1:].strip()
                    if "=" in body:
                        key, _, val = body.partition("=")
                        key = key.strip()
                        if key not in _CSV_KEYS:
                            raise DataError(f"{path}:{lineno}: unknown key {key!r}; the keys "
                                            f"are {list(_CSV_KEYS)}")
                        try:
                            meta[key] = json.loads(val)
                        except json.JSONDecodeError:
                            raise DataError(f"{path}:{lineno}: value of {key!r} is not JSON "
                                            f"({val.strip()!r}); write numbers plainly and "
                                            "strings in double quotes") from None
                    continue
                cells = next(csv.reader([text]))
                if header is None:
                    header = tuple(c.strip() for c in cells)
                    if header != _CSV_HEADER:
                        raise DataError(f"{path}:{lineno}: header {list(header)} must be "
                                        f"{list(_CSV_HEADER)}")
                    continue
                rows.append((lineno, cells))
        if header is None or not rows:
            raise DataError(f"{path}: no data lines; the CSV layout is '# b = ...' lines, the "
                            f"header {','.join(_CSV_HEADER)} and one line per element")
        if "b" not in meta:
            raise DataError(f"{path}: no '# b = <semichord>' line; b is required")
        entries = {}
        for lineno, cells in rows:
            if len(cells) != 5:
                raise DataError(f"{path}:{lineno}: {len(cells)} fields, expected 5 "
                                f"({','.join(_CSV_HEADER)})")
            try:
                kn, re_, im_ = float(cells[0]), float(cells[3]), float(cells[4])
                i, j = int(cells[1]), int(cells[2])
            except ValueError:
                raise DataError(f"{path}:{lineno}: non-numeric field in {cells}") from None
            if i < 1 or j < 1:
                raise DataError(f"{path}:{lineno}: row and col are 1-based, got ({i}, {j})")
            if (kn, i, j) in entries:
                raise DataError(f"{path}:{lineno}: element ({i}, {j}) at k = {kn:g} appears "
                                "twice; keep one line per element and frequency")
            entries[(kn, i, j)] = complex(re_, im_)
        ks = np.array(sorted({e[0] for e in entries}))
        N = max(e[1] for e in entries)
        M = max(e[2] for e in entries)
        Q = np.empty((ks.size, N, M), dtype=complex)
        for n, kn in enumerate(ks):
            for i in range(N):
                for j in range(M):
                    try:
                        Q[n, i, j] = entries[(kn, i + 1, j + 1)]
                    except KeyError:
                        raise DataError(f"{path}: element ({i + 1}, {j + 1}) missing at "
                                        f"k = {kn:g}; every element is needed at every k "
                                        f"(N = {N}, M = {M})") from None
        opt = {key: meta[key] for key in ("U_ref", "rho") if key in meta}
        return _from_file(path, ks, Q, meta["b"], names=tuple(meta.get("mode_names", ())),
                          source=str(meta.get("source", path.name)), **opt)

    @classmethod
    def from_mat(cls, path) -> "GAFTable":
        """Read the MATLAB layout (module docstring; ``Q`` is ``N x M x nk``)."""
        path = Path(path)
        mat = read_mat(path)
        keys = sorted(k for k in mat if not k.startswith("__"))
        for name in ("k", "Q", "b"):
            if name not in mat:
                raise DataError(f"{path}: no variable {name!r} (variables are {keys}); the "
                                ".mat layout needs k, complex Q (N x M x nk) and b")
        k = np.asarray(mat["k"]).ravel()
        Q = np.asarray(mat["Q"])
        if Q.ndim == 2:
            Q = Q[:, :, None]
        if Q.ndim != 3 or Q.shape[2] != k.size:
            raise DataError(f"{path}: Q has shape {Q.shape} but the .mat layout is N x M x nk "
                            f"with nk = {k.size} (one N x M page per k); permute Q in MATLAB "
                            "(permute(Q, [2 3 1]) for an nk x N x M array)")
        opt = {key: mat[key] for key in ("U_ref", "rho") if key in mat}
        names = mat_strings(mat["mode_names"], "mode_names") if "mode_names" in mat else ()
        source = " ".join(mat_strings(mat["source"], "source")) if "source" in mat else path.name
        return _from_file(path, k, np.transpose(Q, (2, 0, 1)), mat["b"], names=names,
                          source=source, **opt)


def _from_file(path: Path, k, Q, b, *, names, source, **opt) -> GAFTable:
    """Construct, prefixing any validation error with the file name."""
    try:
        return GAFTable(k, Q, b, mode_names=names, source=source, **opt)
    except DataError as exc:
        raise DataError(f"{path}: {exc}") from None


def load_gaf(path) -> GAFTable:
    """Read a ``Q(ik)`` table from ``.npz``, ``.csv`` or ``.mat`` (module docstring).

    Parameters
    ----------
    path : str or pathlib.Path

    Returns
    -------
    GAFTable

    Raises
    ------
    DataError
        Unknown suffix, unreadable file, missing or malformed arrays (the message names the
        array and the fix).
    """
    path = Path(path)
    reader = {".npz": GAFTable.from_npz, ".csv": GAFTable.from_csv,
              ".mat": GAFTable.from_mat}.get(path.suffix.lower())
    if reader is None:
        raise DataError(f"{path}: unknown suffix {path.suffix!r}; use .npz, .csv or .mat")
    if not path.is_file():
        raise DataError(f"{path}: no such file")
    return reader(path)
