"""Control of the BLAS/OpenMP thread pools used by numpy, scipy and CasADi.

Threaded BLAS reductions sum in an order that depends on the number of threads, so the last
bits of a result depend on how the process was launched (``OPENBLAS_NUM_THREADS``).  A
nonconvex optimiser whose accept/stop decisions compare such numbers can then end in another
local optimum.  :func:`single_threaded` pins every pool that threadpoolctl can see to one
thread for the duration of a ``with`` block (or a decorated function), so that the same
inputs give bit-identical outputs whatever the environment says.

CasADi bundles an OpenBLAS of its own (``libcasadi-tp-openblas``, the BLAS of Ipopt's linear
solver MUMPS) whose symbols threadpoolctl does not recognise; it takes its thread count from
the environment when it loads (two on a two-core machine), and the H∞ synthesis's QPs were
large enough on a 50-state family for that to change the last bits of γ between a bare shell
and ``OPENBLAS_NUM_THREADS=1``.  :func:`single_threaded` pins it too, through its own
``openblas_set_num_threads``.
"""

from __future__ import annotations

import ctypes
import functools
import glob
import importlib
import os
from contextlib import contextmanager
from typing import Callable, Iterator, TypeVar

from threadpoolctl import threadpool_limits

__all__ = ["single_threaded", "deterministic"]

#: Modules whose import loads a BLAS/OpenMP pool of its own (numpy, scipy and slycot, which
#: python-control loads, each bundle an OpenBLAS).
_POOL_MODULES = ("numpy", "scipy.linalg", "slycot")

F = TypeVar("F", bound=Callable)


def _load_pools() -> None:
    """Load every BLAS pool casflutter uses: threadpoolctl limits only the libraries loaded
    when the limit is set, and one loaded later inside the block (a command's import of
    scipy) would keep the thread count of the environment."""
    for name in _POOL_MODULES:
        try:
            importlib.import_module(name)
        except ImportError:  # slycot is optional
            pass


@functools.lru_cache(maxsize=None)
def casadi_openblas():
    """CasADi's bundled OpenBLAS as a ``ctypes`` library (the one the Ipopt plugin loads;
    loading it here first is the same library), or ``None`` where this CasADi has none."""
    try:
        casadi = importlib.import_module("casadi")
    except ImportError:  # pragma: no cover - casadi is a dependency
        return None
    for path in sorted(glob.glob(os.path.join(os.path.dirname(casadi.__file__),
                                              "libcasadi-tp-openblas*"))):
        try:
            lib = ctypes.CDLL(path)
            get, set_ = lib.openblas_get_num_threads, lib.openblas_set_num_threads
        except (OSError, AttributeError):
            continue
        get.restype, get.argtypes = ctypes.c_int, []
        set_.restype, set_.argtypes = None, [ctypes.c_int]
        return lib
    return None


@contextmanager
def single_threaded() -> Iterator[None]:
    """Limit every BLAS/OpenMP pool to one thread inside the block (restored afterwards),
    CasADi's own OpenBLAS included."""
    _load_pools()
    lib = casadi_openblas()
    before = lib.openblas_get_num_threads() if lib is not None else None
    with threadpool_limits(limits=1):
        if lib is not None:
            lib.openblas_set_num_threads(1)
        try:
            yield
        finally:
            if lib is not None:
                lib.openblas_set_num_threads(before)


def deterministic(fn: F) -> F:
    """Decorator: run ``fn`` inside :func:`single_threaded`."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with single_threaded():
            return fn(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
