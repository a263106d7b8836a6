"""Plant families to and from gridded family files.

:func:`load_family` reads a problem file ``kind = "plant_family"`` (the layout is that of
:mod:`casflutter.data`'s :class:`~casflutter.data.FamilyFile`) into a
:class:`~casflutter.aeroelastic.GriddedFamily`; :func:`write_family` samples any
:class:`~casflutter.aeroelastic.PlantFamily` at a grid of speeds and writes the problem file
and its data file (``.npz`` or MATLAB ``.mat``), so that a model built here (a truth's
linearisation, a ROM loop, a strip-theory wing) can be handed to another tool, or come back
as a grid.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from .._resources import problems_dir
from ..data import FamilyFile, read_family_file
from ..errors import ConfigError, DataError
from ._family import FamilySignals, GriddedFamily, PlantFamily

__all__ = ["load_family", "write_family", "family_record"]

log = logging.getLogger(__name__)


def load_family(source) -> GriddedFamily:
    """The gridded plant family of a family file.

    Parameters
    ----------
    source : str, Path or casflutter.data.FamilyFile
        The problem file (TOML, ``kind = "plant_family"``), a folder holding it as
        ``problem.toml``, the name of such a folder of the package's ``problems/`` (e.g.
        ``"goland_4flaps"``), or a record already read.

    Returns
    -------
    GriddedFamily
        Signals named, roles and units as the file says; interpolated linearly between
        the grid speeds.  A warning is logged where the states seem to change meaning
        between grid speeds (:meth:`GriddedFamily.realisation_gaps`).  The file's
        rigid-body positions are left out: when the states that feed no output and no
        other state (:meth:`GriddedFamily.detached_states`) have, at every grid speed, a
        pole at the origin and no pole that grows, the family is returned without them
        (:meth:`GriddedFamily.without_states`; the input-output behaviour is unchanged and
        no controller moves them), says so at INFO level and names them in
        ``left_out_states`` (0-based indices of the file's states).  Detached states with a
        pole that grows are kept, for the design to refuse by name.

    Raises
    ------
    ConfigError
        A missing file or key, an unknown key, an unknown role name (with the closest
        signal name).
    DataError
        A data file that is missing or does not fit (the message names the file).

    Examples
    --------
    >>> from casflutter.aeroelastic import load_family
    >>> fam = load_family("goland_4flaps")
    >>> fam.n_states, len(fam.signals.controls), len(fam.signals.measurements)
    (50, 4, 8)
    """
    if isinstance(source, FamilyFile):
        rec = source
    else:
        path = Path(source)
        if not path.exists() and path.suffix != ".toml" and len(path.parts) == 1 and \
                (problems_dir() / path).is_dir():
            path = problems_dir() / path
        if path.is_dir():
            path = path / "problem.toml"
        rec = read_family_file(path)
    where = rec.path if rec.path is not None else rec.name
    try:
        signals = FamilySignals(rec.input_names, rec.output_names, controls=rec.controls,
                                measurements=rec.measurements, input_units=rec.input_units,
                                output_units=rec.output_units)
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    family = GriddedFamily(rec.speeds, rec.A, rec.B, rec.C, rec.D, signals,
                           speed_unit=rec.speed_unit, time_unit=rec.time_unit,
                           feedback=rec.feedback, name=rec.name)
    gaps = family.realisation_gaps()
    if gaps:
        g = gaps[0]
        log.warning(
            "%s: the states seem to change meaning between grid speeds in %d of %d intervals "
            "(first %g-%g %s: both ends have the same poles within 10 %%, but the plant "
            "interpolated halfway has a pole %.0f %% away from all of them).  The family is "
            "interpolated elementwise, which needs the same states at every speed: export it "
            "in one realisation (the same modal basis, normalisation and lag states at every "
            "speed)", where, len(gaps), family.speeds.size - 1, g.lo, g.hi, family.speed_unit,
            100 * g.pole_distance)
    return _leave_out_positions(family, where)


#: an eigenvalue of the detached block within this much of the imaginary axis or the origin,
#: relative to the family's scale (max |A| over the grid), is on it to rounding.  Rounding of
#: A's entries (eps · max |A|) moves a double pole at the origin (a yaw angle feeding a lateral
#: displacement, a Jordan block) by about sqrt(eps) · max |A| = 1.5e-8 · max |A|; an entry of
#: the block at the level of the detached-state tolerance is set to zero first.
_ORIGIN_REL = 1e-7

#: (file, states) whose leaving out was already said in this process
_ANNOUNCED: set = set()


def _leave_out_positions(family: GriddedFamily, where) -> GriddedFamily:
    """``family`` without its detached states when they are positions: every pole of
    their block at the origin or decaying at every grid speed, one at the origin at least."""
    detached = family.detached_states()
    if not detached or len(detached) == family.n_states:
        return family
    reduced = family.without_states(detached)
    lam = reduced.left_out_eigenvalues
    scale = float(np.max(np.abs(family.arrays[0])))
    tiny = _ORIGIN_REL * scale
    at_origin = np.abs(lam) <= tiny
    if np.max(lam.real) > tiny or not np.all(at_origin.any(axis=1)):
        log.debug("%s: states %s (0-based) feed no output and no other state, but their "
                  "poles are not at the origin (or one grows); they are kept", where,
                  list(detached))
        return family
    # said once per file and process (a run loads its family to check the configuration,
    # then for its stages)
    key = (str(where), tuple(detached))
    level = logging.DEBUG if key in _ANNOUNCED else logging.INFO
    _ANNOUNCED.add(key)
    log.log(
        level,
        "%s: %d of its %d states left out (0-based indices %s): poles at the origin that feed "
        "no output and no other state: rigid-body positions or integrators that no sensor "
        "sees; the loop's input-output behaviour does not depend on them (every closed loop "
        "keeps these %d poles, whatever the controller: %d at the origin, %s)", where,
        len(detached), family.n_states, list(detached), len(detached),
        int(np.min(at_origin.sum(axis=1))),
        "none other" if bool(np.all(at_origin)) else
        f"the others decaying, the slowest at Re λ = {np.max(lam[~at_origin].real):.4g} "
        f"per {family.time_unit}")
    return reduced


def family_record(family: PlantFamily, speeds, *, name: str | None = None,
                  description: str = "", source: str = "",
                  reference: dict | None = None) -> FamilyFile:
    """A family sampled at a grid of speeds, as a file record.

    Parameters
    ----------
    family : PlantFamily
        Any family (its plants must have the same number of states at every speed).
    speeds : array_like
        Grid speeds inside the family's range, strictly increasing (at least two).
    name, description, source : str, optional
        Written to the file's ``[problem]`` table (default name: the family's).
    reference : dict, optional
        Written to the file's ``[reference]`` table.

    Returns
    -------
    casflutter.data.FamilyFile

    Raises
    ------
    ConfigError
        A speed outside the family's range, speeds not increasing.
    DataError
        Plants whose sizes change along the grid.
    """
    if not isinstance(family, PlantFamily):
        raise ConfigError(f"family must be a casflutter.aeroelastic.PlantFamily, got "
                          f"{type(family).__name__}")
    v = np.asarray(speeds, dtype=float).ravel()
    v = np.array([family.check_speed(x, "speeds") for x in v])
    sig = family.signals
    mats: list[list[np.ndarray]] = [[], [], [], []]
    for x in v:
        P = family.plant(float(x))
        for store, M in zip(mats, (P.A, P.B, P.C, P.D)):
            store.append(np.atleast_2d(np.asarray(M, dtype=float)))
    shapes = {tuple(M.shape for M in (a, b, c, d)) for a, b, c, d in zip(*mats)}
    if len(shapes) != 1:
        raise DataError(f"{family.name}: the plant's sizes change along the speeds "
                        f"({sorted(shapes)}); a gridded family needs the same states at every "
                        "speed")
    return FamilyFile(v, *(np.stack(M) for M in mats), speed_unit=family.speed_unit,
                      feedback=family.feedback, time_unit=family.time_unit,
                      name=family.name if name is None else name, description=description,
                      source=source, input_names=sig.inputs, output_names=sig.outputs,
                      controls=sig.controls, measurements=sig.measurements,
                      input_units=sig.input_units, output_units=sig.output_units,
                      reference=reference or {})


def write_family(family: PlantFamily, path, speeds, format: str = "npz", *,
                 data_file: str | None = None, name: str | None = None,
                 description: str = "", source: str = "", reference: dict | None = None,
                 overwrite: bool = True) -> Path:
    """Sample a plant family at a grid of speeds and write a family file.

    Writes the problem file ``path`` (TOML, ``kind = "plant_family"``) and its data file
    beside it, each atomically (a failure leaves no half-written file); the result loads
    with :func:`load_family` and gives the family's plants at the grid speeds exactly.

    Parameters
    ----------
    family : PlantFamily
        Any family: a :class:`GriddedFamily`, a loop family, a strip-theory wing.
    path : str or Path
        The problem file (``.toml``).
    speeds : array_like
        Grid speeds inside the family's range.
    format, data_file, overwrite :
        The data file's format and name, and whether existing files are replaced: see
        :meth:`casflutter.data.FamilyFile.write`.
    name, description, source, reference :
        See :func:`family_record`.

    Returns
    -------
    pathlib.Path
        The problem file written (its data file beside it).

    Raises
    ------
    ConfigError, DataError, OutputError
        Bad speeds or format, plants of changing size, a path that cannot be written (all
        checked before the files are written).

    See Also
    --------
    load_family : the file back as a :class:`GriddedFamily`.
    """
    rec = family_record(family, speeds, name=name, description=description, source=source,
                        reference=reference)
    return rec.write(path, format=format, data_file=data_file, overwrite=overwrite)
