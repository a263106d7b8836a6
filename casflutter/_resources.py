"""Where the package finds its problem definitions (``problems/``), and how it reads the
TOML files of problems, run configurations and studies.

In a source checkout and in an installed wheel alike, the problem definitions are reached
through ``casflutter/_problems`` (a link to the repository's ``problems/`` folder, copied into
the wheel as package data), so an installed package runs its default problems.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from .errors import ConfigError

__all__ = ["problems_dir", "read_toml"]


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


def read_toml(path, what: str = "file") -> dict:
    """The tables of the TOML file ``path``.

    Raises
    ------
    ConfigError
        If the file does not exist, is a folder, is not UTF-8 text or not valid TOML;
        ``what`` names it in the message (``"study file"``, ``"configuration file"`` ...).
    """
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{what} {path} is a folder; give the TOML file inside it")
    if not path.is_file():
        raise ConfigError(f"{what} {path} not found: the file does not exist")
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{what} {path} is not valid TOML ({exc})") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{what} {path} is not a UTF-8 text file ({exc.reason} at byte "
                          f"{exc.start}); give a TOML text file") from None
    except OSError as exc:
        raise ConfigError(f"{what} {path} cannot be read ({exc.strerror or exc})") from None
