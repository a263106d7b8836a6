"""Output paths checked before any work: a command that computes for minutes must not fail
at the end because its output file or folder cannot be written.

:func:`check_output_path` is the one check the command line (``--out``, ``--figure``) and the
drivers use; it creates nothing that stays behind (a probe file in the nearest existing
folder is created and removed at once).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Iterable, Literal

from .errors import OutputError

__all__ = ["check_output_path", "check_figure_path"]


def _nearest_existing(path: Path) -> Path:
    p = path
    while not p.exists() and not p.is_symlink():
        if p.parent == p:
            break
        p = p.parent
    return p


def _probe(folder: Path, what: str, target: Path) -> None:
    """Create and remove a file in ``folder`` (``os.access`` is not enough: root, read-only
    mounts, network file systems)."""
    try:
        fd, name = tempfile.mkstemp(prefix=".casflutter-write-test-", dir=folder)
    except OSError as exc:
        raise OutputError(f"{what} {target}: cannot write in the folder {folder} "
                          f"({exc.strerror or exc}); choose a writable location") from None
    os.close(fd)
    try:
        os.unlink(name)
    except OSError:
        pass


def check_output_path(path: str | os.PathLike, *, what: str = "output",
                      kind: Literal["file", "dir"] = "file",
                      suffixes: Iterable[str] | None = None,
                      overwrite: bool = True) -> Path:
    """Check that ``path`` can be created and written, before any work starts.

    Parameters
    ----------
    path : str or path-like
        The output file (``kind="file"``) or folder (``kind="dir"``).
    what : str
        How the message names the input (``"--out"``, ``"--figure"``, ``"output folder"``).
    kind : {"file", "dir"}
        A file (its folder is created later by the writer) or a folder.
    suffixes : iterable of str, optional
        Allowed file suffixes (lower case, with the dot, e.g. ``(".png", ".pdf")``).
    overwrite : bool
        Whether an existing file (or a non-empty folder) may be replaced; ``False`` refuses
        it (the command's ``--overwrite`` sets it).

    Returns
    -------
    pathlib.Path
        ``path`` as a :class:`~pathlib.Path` (nothing is created).

    Raises
    ------
    OutputError
        The path or one of its parents is a file where a folder is needed (or a folder
        where a file is needed), the nearest existing folder is not writable, the suffix is
        not allowed, or the path exists and ``overwrite`` is false.  The message names
        ``what``, the path, the problem and the fix.
    """
    if kind not in ("file", "dir"):
        raise ValueError(f"kind must be 'file' or 'dir', got {kind!r}")
    if os.fspath(path) == "":
        raise OutputError(f"{what}: empty path; give a file or folder name")
    p = Path(os.fspath(path)).expanduser()
    if kind == "file" and suffixes is not None:
        allowed = tuple(s.lower() for s in suffixes)
        if p.suffix.lower() not in allowed:
            raise OutputError(f"{what} {p}: unsupported file type {p.suffix or '(none)'!r}; "
                              f"use one of {', '.join(allowed)}")
    if p.exists():
        if kind == "file":
            if p.is_dir():
                raise OutputError(f"{what} {p} is a folder; give a file name (e.g. "
                                  f"{p / ('out' + (p.suffix or ''))})")
            if not overwrite:
                raise OutputError(f"{what} {p} already exists; remove it, choose another "
                                  "name or pass --overwrite")
            if not os.access(p, os.W_OK):
                raise OutputError(f"{what} {p} exists and is not writable; choose another "
                                  "name or change its permissions")
            _probe(p.parent, what, p)
            return p
        if not p.is_dir():
            raise OutputError(f"{what} {p} is a file, not a folder; remove it or choose "
                              "another folder name")
        if not overwrite and any(p.iterdir()):
            raise OutputError(f"{what} {p} already exists and is not empty; choose another "
                              "folder or pass --overwrite")
        _probe(p, what, p)
        return p
    anc = _nearest_existing(p.parent if kind == "file" else p)
    if not anc.is_dir():
        raise OutputError(f"{what} {p}: {anc} is a file, not a folder, so {p} cannot be "
                          "created; choose another path")
    _probe(anc, what, p)
    return p


def check_figure_path(path: str | os.PathLike, *, what: str = "--figure",
                      overwrite: bool = True) -> Path:
    """:func:`check_output_path` for a matplotlib figure: the suffix must be a format
    matplotlib writes (``.png``, ``.pdf``, ``.svg`` ...).

    Raises
    ------
    OutputError
        As :func:`check_output_path`; the message lists the formats.
    """
    from matplotlib.backend_bases import FigureCanvasBase  # noqa: PLC0415 - heavy, optional

    formats = sorted("." + ext for ext in FigureCanvasBase.get_supported_filetypes())
    return check_output_path(path, what=what, kind="file", suffixes=formats,
                             overwrite=overwrite)
