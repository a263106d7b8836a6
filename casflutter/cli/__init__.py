"""The ``casflutter`` command.

Each sub-command lives in its own module under :mod:`casflutter.cli.commands`
(``casflutter NAME ...``) or :mod:`casflutter.cli.bench` (``casflutter bench NAME ...``)
and exposes ``register(subparsers)``, which adds its parser and sets
``func(args) -> int`` as the handler.  Modules are discovered, so a stage adds its
command without editing this file.

One rule for failures: a handler raises a :class:`casflutter.errors.CasflutterError` whose
message names the input, the problem and the fix; :func:`main` prints it as one line
``casflutter: error: ...`` on stderr and returns 1.  Any other exception is a bug: one line
with its type and a hint to rerun with ``--debug`` (which shows the traceback), and exit
code 1.  Ctrl-C and SIGTERM give 130 and 143; a closed stdout (``casflutter problems |
head``) ends quietly with 141.

Messages go through :mod:`logging` (logger ``casflutter`` and its children,
:mod:`casflutter._logging`): progress on stderr by default, silenced by ``--quiet`` (the
results on stdout stay), DEBUG records with ``--verbose``; ``--debug`` adds tracebacks.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import pkgutil
import sys
import traceback

from .. import __version__
from .._interrupt import Terminated, sigterm_raises
from .._logging import (PACKAGE_LOGGER, configure_cli_logging, own_warnings_logged,
                        remove_cli_logging)
from .._threads import single_threaded
from ._help import plain_help
from ..errors import CasflutterError

__all__ = ["main", "build_parser", "EXIT_ERROR", "EXIT_INTERRUPTED", "EXIT_TERMINATED",
           "EXIT_BROKEN_PIPE"]

#: Exit codes besides 0 (success) and 2 (argparse: bad command line).
EXIT_ERROR = 1
EXIT_INTERRUPTED = 130     # 128 + SIGINT
EXIT_TERMINATED = 143      # 128 + SIGTERM
EXIT_BROKEN_PIPE = 141     # 128 + SIGPIPE

_log = logging.getLogger(__name__)

_GLOBAL_FLAGS = (
    (("--debug",), dict(dest="debug", action="store_true",
                        help="show DEBUG messages and the traceback of an error")),
    (("-v", "--verbose"), dict(dest="verbose", action="store_true",
                               help="show DEBUG messages on stderr")),
    (("-q", "--quiet"), dict(dest="log_quiet", action="store_true",
                             help="no progress messages on stderr (results still on stdout)")),
)


def _register_package(package_name: str, subparsers) -> None:
    package = importlib.import_module(package_name)
    for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{package_name}.{info.name}")
        module.register(subparsers)


def _add_global_flags(parser: argparse.ArgumentParser, *, top: bool) -> None:
    """``--debug``, ``--verbose``, ``--quiet`` before or after the sub-command (an option a
    sub-command defines itself is left to it)."""
    for flags, kw in _GLOBAL_FLAGS:
        flags = tuple(f for f in flags if f not in parser._option_string_actions)
        if not flags:
            continue
        kw = dict(kw)
        if not top:
            kw["default"] = argparse.SUPPRESS  # do not reset a flag given before the command
        parser.add_argument(*flags, **kw)


class _Parser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` that matches options only by their full name.

    With argparse's default prefix matching, an option a sub-command documents can be taken
    by another parser: ``identify --v v`` (the flap column) was read by the top-level parser
    as an ambiguous prefix of ``--version`` and ``--verbose``.  Sub-command parsers are made
    by this class too (``add_subparsers`` builds them with the class of their parent), so a
    new command gets the rule without asking for it.
    """

    def __init__(self, *args, **kwargs):
        kwargs["allow_abbrev"] = False
        super().__init__(*args, **kwargs)


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser (all discovered sub-commands).

    Every parser in it (top level, sub-commands, ``bench`` sub-commands) takes options only
    by their full name (no prefix abbreviations, :class:`_Parser`)."""
    parser = _Parser(
        prog="casflutter",
        description="Nonlinear aerodynamic ROMs, flutter analysis and fixed-order robust "
                    "flutter suppression (after Lum et al., ACC 2016).")
    parser.add_argument("--version", action="version", version=f"casflutter {__version__}")
    _add_global_flags(parser, top=True)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    _register_package(f"{__name__}.commands", sub)
    bench = sub.add_parser("bench", help="benchmarks that write JSON")
    bench_sub = bench.add_subparsers(dest="bench", metavar="BENCHMARK")
    _register_package(f"{__name__}.bench", bench_sub)
    bench.set_defaults(func=lambda args: (bench.print_help(), 2)[1])
    for p in [*sub.choices.values(), *bench_sub.choices.values()]:
        _add_global_flags(p, top=False)
    plain_help(parser)       # the docstrings' reST markup as plain text
    return parser


def _one_line(text: str) -> str:
    return " ".join(part.strip() for part in str(text).splitlines() if part.strip())


def _error(message: str) -> None:
    try:
        sys.stderr.write(message + "\n")
        sys.stderr.flush()
    except (BrokenPipeError, ValueError):
        pass


def _silence_stdout() -> None:
    """After a broken pipe: point stdout at /dev/null so that the interpreter's final flush
    does not raise again (Python's documented recipe)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass  # not a real file (captured stdout): nothing will be flushed to a pipe


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``casflutter`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    debug = bool(getattr(args, "debug", False))
    quiet = bool(getattr(args, "log_quiet", False)) or getattr(args, "quiet", None) is True
    logger = logging.getLogger(PACKAGE_LOGGER)
    old_level = logger.level
    handler = configure_cli_logging(quiet=quiet, verbose=bool(getattr(args, "verbose", False)),
                                    debug=debug)
    try:
        # one BLAS thread: the same seed gives bit-identical numbers however the process was
        # launched (make demo pins the pools through the environment, a bare shell does not)
        with sigterm_raises(), single_threaded(), own_warnings_logged(_log):
            code = int(args.func(args) or 0)
        sys.stdout.flush()  # a broken pipe shows here, not at interpreter exit
        return code
    except BrokenPipeError:
        _silence_stdout()
        return EXIT_BROKEN_PIPE
    except CasflutterError as exc:
        if debug:
            _error(traceback.format_exc().rstrip())
        _error(f"casflutter: error: {_one_line(exc)}")
        return EXIT_ERROR
    except Terminated:
        handler.close_line()
        _error("casflutter: terminated (SIGTERM)")
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        handler.close_line()
        _error("casflutter: interrupted")
        return EXIT_INTERRUPTED
    except Exception as exc:  # noqa: BLE001 - a bug: one line unless --debug
        if debug:
            _error(traceback.format_exc().rstrip())
            _error(f"casflutter: internal error: {type(exc).__name__}: {_one_line(exc)}")
        else:
            _error(f"casflutter: internal error: {type(exc).__name__}: {_one_line(exc)} "
                   "(a bug; rerun with --debug for the traceback and report it)")
        return EXIT_ERROR
    finally:
        remove_cli_logging(handler, old_level)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
