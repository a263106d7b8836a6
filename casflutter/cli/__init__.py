"""The ``casflutter`` command.

Each sub-command lives in its own module under :mod:`casflutter.cli.commands`
(``casflutter NAME ...``) or :mod:`casflutter.cli.bench` (``casflutter bench NAME ...``)
and exposes ``register(subparsers)``, which adds its parser and sets
``func(args) -> int`` as the handler.  Modules are discovered, so a stage adds its
command without editing this file.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys

from .._threads import single_threaded
from ..errors import CasflutterError

__all__ = ["main", "build_parser"]


def _register_package(package_name: str, subparsers) -> None:
    package = importlib.import_module(package_name)
    for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{package_name}.{info.name}")
        module.register(subparsers)


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser (all discovered sub-commands)."""
    parser = argparse.ArgumentParser(
        prog="casflutter",
        description="Nonlinear aerodynamic ROMs, flutter analysis and fixed-order robust "
                    "flutter suppression (after Lum et al., ACC 2016).")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    _register_package(f"{__name__}.commands", sub)
    bench = sub.add_parser("bench", help="benchmarks that write JSON")
    bench_sub = bench.add_subparsers(dest="bench", metavar="BENCHMARK")
    _register_package(f"{__name__}.bench", bench_sub)
    bench.set_defaults(func=lambda args: (bench.print_help(), 2)[1])
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``casflutter`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        # one BLAS thread: the same seed gives bit-identical numbers however the process was
        # launched (make demo pins the pools through the environment, a bare shell does not)
        with single_threaded():
            return int(args.func(args) or 0)
    except CasflutterError as exc:
        print(f"casflutter: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
