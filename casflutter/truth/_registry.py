"""The registry of truth problems and their definitions in ``problems/``.

A problem is named by one of :data:`PROBLEMS` (a built-in truth class with published
defaults), by a TOML file describing a rig section (``kind = "pitch_plunge"``, see
:mod:`._pitch_plunge`) or a user's wing without a simulator (``kind = "wing"``: modal data and
records; ``kind = "gaf"``: modal data and ``Q(ik)``; see :mod:`._wing_file`), a gridded plant
family (``kind = "plant_family"``: state-space models at a grid of speeds, read into a
:class:`casflutter.data.FamilyFile`; :func:`casflutter.aeroelastic.load_family` makes it a
family), or by the name of a folder of ``problems/`` whose ``problem.toml`` is such a file (e.g.
``nata``, ``example_wing``, ``goland_gaf``, ``goland_4flaps``).
"""

from __future__ import annotations

import difflib

from pathlib import Path
from typing import Any, Iterable, Mapping

from .. import _resources
from .._resources import read_toml
from ..data import FAMILY_KIND, FamilyFile, read_family_file
from ..errors import ConfigError
from ._base import AeroelasticTruth
from ._goland import GolandWing
from ._pitch_plunge import PITCH_PLUNGE_KIND, PitchPlungeSection
from ._seed_wing import SeedWing
from ._typical_section import TypicalSection
from ._wing_file import GAF_KIND, WING_KIND, GAFProblem, WingProblem

__all__ = ["PROBLEMS", "FILE_KINDS", "WING_KINDS", "problem_names", "file_problem_names", "load_problem",
           "load_problem_file", "problem_definition", "problem_label"]

#: name -> truth class
PROBLEMS: dict[str, type[AeroelasticTruth]] = {
    "typical_section": TypicalSection,
    "goland": GolandWing,
    "seed_wing": SeedWing,
}

#: ``kind`` of a problem file -> truth class reading it
FILE_KINDS: dict[str, type] = {PITCH_PLUNGE_KIND: PitchPlungeSection}

#: ``kind`` of a wing file (no truth simulator) -> the class reading it
WING_KINDS: dict[str, type] = {WING_KIND: WingProblem, GAF_KIND: GAFProblem}


def problem_names() -> list[str]:
    """List the built-in problems that have a truth simulator.

    Returns
    -------
    list of str
        The names :func:`load_problem` accepts besides a problem file's path.

    See Also
    --------
    load_problem : a problem's truth, with parameter changes.

    Examples
    --------
    >>> import casflutter as cf
    >>> sorted(cf.problem_names())
    ['goland', 'seed_wing', 'typical_section']
    """
    return list(PROBLEMS)


def file_problem_names() -> list[str]:
    """Names of the folders of ``problems/`` holding a problem file (``kind = ...``)."""
    try:
        root = _resources.problems_dir()
    except FileNotFoundError:
        return []
    out = []
    for path in sorted(root.glob("*/problem.toml")):
        if path.parent.name in PROBLEMS:
            continue
        try:
            if read_toml(path, "problem definition").get("kind") in (*FILE_KINDS, *WING_KINDS,
                                                                     FAMILY_KIND):
                out.append(path.parent.name)
        except ConfigError:
            continue
    return out


def _file_of(name: str) -> Path | None:
    """The problem file meant by ``name`` (a TOML path, a folder holding ``problem.toml``, or
    a folder of ``problems/``), or None for a built-in or unknown name."""
    name = str(name)
    if name in PROBLEMS:
        return None
    path = Path(name)
    if path.suffix == ".toml" or path.is_file():
        if not path.is_file():
            raise ConfigError(f"problem file {path} not found: the file does not exist")
        return path
    if path.is_dir() and (path / "problem.toml").is_file():
        return path / "problem.toml"
    if name in file_problem_names():
        return _resources.problems_dir() / name / "problem.toml"
    return None


def _cls(name: str) -> type[AeroelasticTruth]:
    try:
        return PROBLEMS[name]
    except KeyError:
        avail = list(PROBLEMS) + file_problem_names()
        close = difflib.get_close_matches(name, avail, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ConfigError(f"unknown problem {name!r}{hint}; available: {', '.join(avail)}, or "
                          "a problem TOML file (kind = \"pitch_plunge\")") from None


def load_problem_file(path, sets=()) -> AeroelasticTruth | WingProblem | GAFProblem | FamilyFile:
    """The truth described by a problem TOML file (``kind = "pitch_plunge"``), the wing of a
    wing file (``kind = "wing"`` or ``"gaf"``, no simulator), or the record of a gridded plant
    family (``kind = "plant_family"``).

    Parameters
    ----------
    path : str or Path
        The file.
    sets : iterable of str
        ``"name=value"`` items applied to the file's values.

    Returns
    -------
    AeroelasticTruth, WingProblem, GAFProblem or casflutter.data.FamilyFile

    Raises
    ------
    ConfigError
        Missing file, invalid TOML, unknown ``kind``, missing/unknown keys or non-physical
        values (the message names the key).
    DataError
        A wing file's record or ``Q(ik)`` file missing or unusable.
    """
    path = Path(path)
    data = read_toml(path, "problem file")
    kind = data.get("kind")
    if kind in WING_KINDS:
        return WING_KINDS[kind].from_mapping(data, sets=sets, path=path)
    if kind == FAMILY_KIND:
        if list(sets):
            raise ConfigError(f"problem file {path} is a gridded plant family: it has no "
                              "parameters to --set (edit the file or its arrays)")
        return read_family_file(path)
    if kind not in FILE_KINDS:
        raise ConfigError(f"problem file {path}: key 'kind' must be one of "
                          f"{', '.join(map(repr, (*FILE_KINDS, *WING_KINDS, FAMILY_KIND)))}, "
                          f"got {kind!r}")
    default = path.parent.name if path.name == "problem.toml" else path.stem
    problem = data.get("problem", {})
    name = dict(problem if isinstance(problem, dict) else {}).get("name", default)
    return FILE_KINDS[kind].from_mapping(data, name=name, source=f"problem file {path}",
                                         sets=sets)


def load_problem(name: str, params: Mapping[str, Any] | Iterable[str] = ()) -> AeroelasticTruth:
    """The truth model of problem ``name`` with parameter changes: the one way from a problem
    name and parameters to a truth.

    Parameters
    ----------
    name : str
        A name from :func:`problem_names` or :func:`file_problem_names`, or the path of a
        problem TOML file (see :func:`load_problem_file`).
    params : mapping or iterable of str
        ``{name: value}`` or ``--set``-style ``"name=value"`` items, applied to the
        published (or the file's) parameters (unknown names raise :class:`ConfigError`
        listing the valid ones).

    Returns
    -------
    AeroelasticTruth

    Raises
    ------
    ConfigError
        Unknown problem or parameter, or a non-physical value.

    See Also
    --------
    problem_names : the built-in problems.
    find_flutter : the flutter speed of the loaded truth.

    Examples
    --------
    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section", ["mu=25"])
    >>> truth.n_modes, truth.params.mu
    (2, 25.0)
    """
    path = _file_of(name)
    if path is not None:
        sets = ([f"{k}={v}" for k, v in params.items()] if isinstance(params, Mapping)
                else params)
        return load_problem_file(path, sets)
    cls = _cls(name)
    return cls(cls.Params.from_sets(params))


def problem_label(name: str) -> str:
    """A short name for output files and titles: the built-in name, or the ``[problem]``
    name of a problem file (else its folder or stem)."""
    path = _file_of(name)
    if path is None:
        return str(name)
    data = read_toml(path, "problem file")
    default = path.parent.name if path.name == "problem.toml" else path.stem
    return str(dict(data.get("problem", {})).get("name", default))


def problem_definition(name: str, problems_dir: str | Path | None = None) -> dict:
    """The TOML definition ``problems/NAME/problem.toml`` (published reference values).

    Raises
    ------
    ConfigError
        Unknown problem, or the definition file is not found (e.g. an installed package
        without the repository's ``problems/`` folder: pass ``problems_dir``).
    """
    path = _file_of(name)
    if path is not None:
        return read_toml(path, "problem definition")
    _cls(name)
    root = Path(problems_dir) if problems_dir is not None else _resources.problems_dir()
    path = root / name / "problem.toml"
    if not path.is_file():
        raise ConfigError(f"problem definition {path} not found; pass problems_dir= pointing "
                          "at the repository's problems/ folder")
    return read_toml(path, "problem definition")
