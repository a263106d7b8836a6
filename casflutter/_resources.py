"""Where the package finds its problem definitions (``problems/``).

In a source checkout and in an installed wheel alike, the problem definitions are reached
through ``casflutter/_problems`` (a link to the repository's ``problems/`` folder, copied into
the wheel as package data), so an installed package runs its default problems.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["problems_dir"]


def problems_dir() -> Path:
    """The folder holding one sub-folder per problem (TOML definitions and small data)."""
    here = Path(__file__).resolve().parent
    packaged = here / "_problems"
    if packaged.is_dir():
        return packaged
    source = here.parent / "problems"
    if source.is_dir():
        return source
    raise FileNotFoundError("casflutter's problem definitions are missing: reinstall the package")
