"""The registry of truth problems and their definitions in ``problems/``."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable, Mapping

from .. import _resources
from .._resources import read_toml
from ..errors import ConfigError
from ._base import AeroelasticTruth
from ._goland import GolandWing
from ._seed_wing import SeedWing
from ._typical_section import TypicalSection

__all__ = ["PROBLEMS", "problem_names", "load_problem", "problem_definition"]

#: name -> truth class
PROBLEMS: dict[str, type[AeroelasticTruth]] = {
    "typical_section": TypicalSection,
    "goland": GolandWing,
    "seed_wing": SeedWing,
}



def problem_names() -> list[str]:
    """Names of the problems that have a truth simulator.

    Returns
    -------
    list of str
    """
    return list(PROBLEMS)


def _cls(name: str) -> type[AeroelasticTruth]:
    try:
        return PROBLEMS[name]
    except KeyError:
        raise ConfigError(f"unknown problem {name!r}; available: {', '.join(PROBLEMS)}") from None


def load_problem(name: str, params: Mapping[str, Any] | Iterable[str] = ()) -> AeroelasticTruth:
    """The truth model of problem ``name`` with parameter changes: the one way from a problem
    name and parameters to a truth.

    Parameters
    ----------
    name : str
        A name from :func:`problem_names`.
    params : mapping or iterable of str
        ``{name: value}`` or ``--set``-style ``"name=value"`` items, applied to the
        published parameters (unknown names raise :class:`ConfigError` listing the valid
        ones).

    Returns
    -------
    AeroelasticTruth

    Raises
    ------
    ConfigError
        Unknown problem or parameter, or a non-physical value.
    """
    cls = _cls(name)
    return cls(cls.Params.from_sets(params))


def problem_definition(name: str, problems_dir: str | Path | None = None) -> dict:
    """The TOML definition ``problems/NAME/problem.toml`` (published reference values).

    Parameters
    ----------
    name : str
        Problem name.
    problems_dir : path, optional
        Folder of the problem definitions (default: the package's).

    Returns
    -------
    dict
        The tables of the file.

    Raises
    ------
    ConfigError
        Unknown problem, or the definition file is not found (e.g. an installed package
        without the repository's ``problems/`` folder: pass ``problems_dir``).
    """
    _cls(name)
    root = Path(problems_dir) if problems_dir is not None else _resources.problems_dir()
    path = root / name / "problem.toml"
    if not path.is_file():
        raise ConfigError(f"problem definition {path} not found; pass problems_dir= pointing "
                          "at the repository's problems/ folder")
    return read_toml(path, "problem definition")
