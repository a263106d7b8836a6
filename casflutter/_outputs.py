"""Outputs that are checked before any work and never left half-written.

A command that computes for minutes must not fail at the end because its output file or
folder cannot be written, nor leave a folder that mixes two runs:

- :func:`check_output_path` is the one check the command line (``--out``, ``--figure``) and
  the drivers use before any work; it creates nothing that stays behind (a probe file in the
  nearest existing folder is created and removed at once).  An existing non-empty folder is
  refused unless ``overwrite``.
- :func:`atomic_folder` writes a whole output folder beside its target, under a name that
  says it is incomplete (``NAME.incomplete-XXXXXX``), and moves it into place only when every
  file is written: a run that fails or is interrupted leaves the target as it was (a process
  killed outright leaves the ``.incomplete`` folder, never a half folder at the target).
  With ``overwrite`` the old folder is replaced as a whole (no stale file of the old run
  stays beside the new ones).
- :func:`atomic_file` does the same for one file (write to a temporary name, then rename);
  :func:`save_figure` writes a matplotlib figure through it (the commands' ``--figure``).
  Like :func:`atomic_folder`, they create the missing parent folders of their target: a
  path :func:`check_output_path` accepted (whose folder need not exist yet) is written.
  :func:`atomic_folder` and :func:`atomic_file` create their temporary folder or file with
  the ordinary modes (``0o777`` for a folder, ``0o666`` for a file, less the umask: 0755
  and 0644 under umask 022), not the private 0700/0600 of
  :func:`tempfile.mkdtemp`/:func:`tempfile.mkstemp`, so the outputs are readable by
  whoever may read the user's other files.
- :func:`provenance` and :func:`write_manifest` record what produced a folder: the package
  version, the configuration's hash, the seed, the thread settings (BLAS environment
  variables and the thread pools threadpoolctl sees), the completed stages, start and end
  time and a SHA-256 of every file (``manifest.json``).
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import secrets
import shutil
import sys
import tempfile
from contextlib import contextmanager
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Iterable, Iterator, Literal, Mapping

import numpy as np

from . import __version__
from .errors import OutputError

__all__ = ["check_output_path", "check_figure_path", "atomic_folder", "atomic_file",
           "save_figure", "check_output_folder", "provenance", "thread_settings",
           "config_hash", "write_manifest", "utc_now", "plain_json",
           "INCOMPLETE_TAG", "MANIFEST_NAME", "THREAD_ENV_VARS"]

#: Part of the name of a folder being written (``NAME.incomplete-XXXXXX``, beside NAME).
INCOMPLETE_TAG = ".incomplete-"
#: The file that records what produced an output folder.
MANIFEST_NAME = "manifest.json"
#: Environment variables that set the number of BLAS/OpenMP threads.
THREAD_ENV_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                   "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")


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
        A file (its missing folders are created later by the writer, :func:`atomic_file`
        or :func:`save_figure`) or a folder (:func:`atomic_folder`).
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


# ---------------------------------------------------------------------- atomic writing
def _create_unique(folder: Path, prefix: str, suffix: str, *, directory: bool) -> Path:
    """Create a new folder or empty file ``folder/PREFIX<random>SUFFIX`` and return its path.

    Like :func:`tempfile.mkdtemp`/:func:`tempfile.mkstemp` (a random name, created
    exclusively, retried on a clash), but with the modes any other folder or file gets:
    ``0o777``/``0o666`` less the process umask.
    """
    for _ in range(100):
        path = folder / f"{prefix}{secrets.token_hex(4)}{suffix}"
        try:
            if directory:
                os.mkdir(path, 0o777)
            else:
                os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            continue
        return path
    raise FileExistsError(f"no free name {prefix}XXXXXXXX{suffix} in {folder}")


def check_output_folder(path: str | os.PathLike, *, overwrite: bool = False,
                        what: str = "output folder") -> Path:
    """Check, before any work, that :func:`atomic_folder` can write ``path``.

    :func:`check_output_path` of the folder, and the folder that will hold it (where the
    incomplete folder is written) must be writable too.

    Parameters
    ----------
    path : str or path-like
        The output folder.
    overwrite : bool
        Whether an existing non-empty folder may be replaced.
    what : str
        How the message names the folder.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    OutputError
        As :func:`check_output_path`, or the parent folder is not writable.
    """
    target = check_output_path(path, what=what, kind="dir", overwrite=overwrite)
    anc = _nearest_existing(target.parent)
    if anc.is_dir():
        _probe(anc, what, target)
    return target


@contextmanager
def atomic_folder(target: str | os.PathLike, *, overwrite: bool = False,
                  what: str = "output folder") -> Iterator[Path]:
    """Write an output folder beside ``target`` and move it into place at the end.

    The block receives an empty folder ``TARGET.incomplete-XXXXXX`` in the target's parent
    folder (same file system, so the final move is a rename).  When the block ends normally
    the folder becomes ``target``; when it raises (an error, Ctrl-C, SIGTERM turned into an
    exception) the incomplete folder is removed and ``target`` is left as it was.  A process
    killed outright leaves only the folder whose name says it is incomplete.

    Parameters
    ----------
    target : str or path-like
        The output folder.  Its parent folders are created.
    overwrite : bool
        Whether an existing non-empty ``target`` may be replaced (as a whole: no file of the
        old folder stays).  Without it such a folder is refused before the block runs, and
        again at the move (if it appeared meanwhile; the finished outputs then stay in the
        incomplete folder, which the message names).
    what : str
        How messages name the folder (``"--out"``).

    Yields
    ------
    pathlib.Path
        The incomplete folder to write into.

    Raises
    ------
    OutputError
        ``target`` cannot be written (:func:`check_output_path`) or exists and is not empty
        without ``overwrite``.
    """
    target = check_output_folder(target, what=what, overwrite=overwrite)
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        tmp = _create_unique(target.parent, target.name + INCOMPLETE_TAG, "", directory=True)
    except OSError as exc:
        raise OutputError(f"{what} {target}: cannot create a folder in {target.parent} "
                          f"({exc.strerror or exc}); choose a writable location") from None
    try:
        yield tmp
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    _move_into_place(tmp, target, overwrite=overwrite, what=what)


def _move_into_place(tmp: Path, target: Path, *, overwrite: bool, what: str) -> None:
    """Rename the finished folder ``tmp`` to ``target`` (replacing it with ``overwrite``)."""
    old = None
    if target.is_symlink() or target.exists():
        if not target.is_dir() or target.is_symlink():
            raise OutputError(f"{what} {target} is no longer a folder; the outputs are in {tmp}")
        if any(target.iterdir()):
            if not overwrite:
                raise OutputError(f"{what} {target} appeared while the run was working and is "
                                  f"not empty; the outputs are in {tmp}: move them yourself "
                                  "or rerun with --overwrite")
            old = target.parent / (target.name + ".old-" + tmp.name.rsplit("-", 1)[-1])
            target.rename(old)
        else:
            target.rmdir()
    try:
        tmp.rename(target)
    except OSError as exc:
        if old is not None:
            old.rename(target)   # put the previous outputs back
        raise OutputError(f"{what} {target}: cannot move the finished outputs into place "
                          f"({exc.strerror or exc}); they are in {tmp}") from None
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


@contextmanager
def atomic_file(target: str | os.PathLike, *, what: str = "output file") -> Iterator[Path]:
    """Write one file under a temporary name beside ``target`` and rename it at the end.

    Parameters
    ----------
    target : str or path-like
        The file.  Its missing parent folders are created (as :func:`atomic_folder` does),
        so a path that :func:`check_output_path` accepted can be written.
    what : str
        How a message names the file (``"--out"``).

    Yields
    ------
    pathlib.Path
        The temporary path to write (``TARGET.incomplete-XXXXXX`` + the target's suffix, so
        that writers which choose the format by suffix still work).  Removed if the block
        raises.

    Raises
    ------
    OutputError
        The folder or the temporary file cannot be created (a parent is a file, no
        permission); the message names ``what``, the path and the fix.
    """
    target = Path(os.fspath(target)).expanduser()
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = _create_unique(target.parent, target.stem + INCOMPLETE_TAG, target.suffix,
                             directory=False)
    except OSError as exc:
        raise OutputError(f"{what} {target}: cannot create a file in {target.parent} "
                          f"({exc.strerror or exc}); choose a writable location") from None
    try:
        yield tmp
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    os.replace(tmp, target)


def save_figure(fig, path: str | os.PathLike, *, what: str = "--figure",
                **savefig_kw) -> Path:
    """Save a matplotlib figure to ``path`` through :func:`atomic_file`.

    The one writer of the commands' ``--figure PATH``: the missing parent folders are
    created (the path was checked by :func:`check_figure_path` before the work, and its
    folder need not exist yet), and the file appears only when it is complete.  The format
    is chosen by the suffix, as :meth:`matplotlib.figure.Figure.savefig` does.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (left open: the caller closes it).
    path : str or path-like
        The file to write.
    what : str
        How a message names the file.
    **savefig_kw
        Passed to :meth:`~matplotlib.figure.Figure.savefig` (``dpi``, ...).

    Returns
    -------
    pathlib.Path
        ``path`` as a :class:`~pathlib.Path`.

    Raises
    ------
    OutputError
        As :func:`atomic_file`.
    """
    target = Path(os.fspath(path)).expanduser()
    with atomic_file(target, what=what) as tmp:
        fig.savefig(tmp, **savefig_kw)
    return target


# ---------------------------------------------------------------------- provenance
def plain_json(x: Any):
    """Plain JSON values of nested dicts, lists, tuples, numpy scalars and arrays; a
    non-finite float becomes ``None`` (strict JSON: ``null``)."""
    if isinstance(x, dict):
        return {k: plain_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [plain_json(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return None if not np.isfinite(x) else float(x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, np.ndarray):
        return plain_json(x.tolist())
    return x


def print_json(doc: Any) -> None:
    """Print ``doc`` on stdout as strict JSON (:func:`plain_json`: a non-finite number is
    ``null``), the ``--json`` output of the commands."""
    sys.stdout.write(json.dumps(plain_json(doc), indent=2, allow_nan=False) + "\n")


def utc_now() -> str:
    """The current time, UTC, ISO 8601 to the second (``2026-01-31T12:00:00Z``)."""
    return datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def thread_settings() -> dict:
    """The thread settings that can change the last bits of a result.

    Returns
    -------
    dict
        ``env``: each of :data:`THREAD_ENV_VARS` (``None`` when unset); ``pools``: the
        BLAS/OpenMP thread pools loaded in this process as threadpoolctl reports them
        (``user_api``, ``internal_api``, ``prefix``, ``version``, ``num_threads``,
        ``threading_layer``; empty when threadpoolctl is not installed).
    """
    pools = []
    try:
        from threadpoolctl import threadpool_info  # noqa: PLC0415 - optional
    except ImportError:   # pragma: no cover - a dependency, but not needed here
        threadpool_info = None
    if threadpool_info is not None:
        keys = ("user_api", "internal_api", "prefix", "version", "num_threads",
                "threading_layer")
        pools = [{k: info.get(k) for k in keys} for info in threadpool_info()]
    return {"env": {k: os.environ.get(k) for k in THREAD_ENV_VARS}, "pools": pools}


def config_hash(config: Mapping[str, Any]) -> str:
    """SHA-256 of a configuration's canonical JSON (sorted keys, no spaces).

    Parameters
    ----------
    config : mapping
        Plain JSON values (non-finite floats as ``None``).

    Returns
    -------
    str
        ``"sha256:<64 hex digits>"``.
    """
    text = json.dumps(config, sort_keys=True, separators=(",", ":"), allow_nan=False,
                      default=str)
    return "sha256:" + hashlib.sha256(text.encode("utf-8")).hexdigest()


def provenance(*, seed: int | None = None) -> dict:
    """What produced a result: version, seed, thread settings, interpreter and libraries.

    Parameters
    ----------
    seed : int, optional
        The seed of the run.

    Returns
    -------
    dict
        ``casflutter_version``, ``seed``, ``threads`` (:func:`thread_settings`), ``python``,
        ``platform`` and ``libraries`` (versions of numpy, scipy, casadi, control).
    """
    libs = {}
    for name in ("numpy", "scipy", "casadi", "control"):
        mod = sys.modules.get(name)
        libs[name] = getattr(mod, "__version__", None) if mod is not None else None
    return {"casflutter_version": __version__, "seed": seed, "threads": thread_settings(),
            "python": platform.python_version(), "platform": platform.platform(),
            "libraries": libs}


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_manifest(folder: str | os.PathLike, *, config: Mapping[str, Any] | None,
                   started: str, stages: Iterable[str], info: Mapping[str, Any],
                   extra: Mapping[str, Any] | None = None) -> Path:
    """Write ``manifest.json`` into an output folder (the last file written).

    Parameters
    ----------
    folder : path
        The (incomplete) output folder; every file already in it is listed with its size
        and SHA-256.
    config : mapping or None
        The configuration as plain JSON values (hashed by :func:`config_hash`).
    started : str
        Start time (:func:`utc_now` when the run began).
    stages : iterable of str
        The stages that completed, in order.
    info : mapping
        :func:`provenance` taken when the run began.
    extra : mapping, optional
        More keys (e.g. flags raised by the run).

    Returns
    -------
    pathlib.Path
        The manifest's path.
    """
    folder = Path(folder)
    files = {p.relative_to(folder).as_posix(): {"bytes": p.stat().st_size, "sha256": _sha256(p)}
             for p in sorted(folder.rglob("*")) if p.is_file() and p.name != MANIFEST_NAME}
    doc = {"format": "casflutter-output-manifest/1", "complete": True,
           "casflutter_version": info.get("casflutter_version", __version__),
           "config_hash": None if config is None else config_hash(config),
           "seed": info.get("seed"), "threads": info.get("threads"),
           "python": info.get("python"), "platform": info.get("platform"),
           "libraries": info.get("libraries"), "completed_stages": list(stages),
           "started": started, "finished": utc_now(), "files": files, **dict(extra or {})}
    path = folder / MANIFEST_NAME
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=2, allow_nan=False)
    return path
