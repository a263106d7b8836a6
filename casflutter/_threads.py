"""Control of the BLAS/OpenMP thread pools used by numpy, scipy and CasADi.

Threaded BLAS reductions sum in an order that depends on the number of threads, so the last
bits of a result depend on how the process was launched (``OPENBLAS_NUM_THREADS``).  A
nonconvex optimiser whose accept/stop decisions compare such numbers can then end in another
local optimum.  :func:`single_threaded` pins every pool that threadpoolctl can see to one
thread for the duration of a ``with`` block (or a decorated function), so that the same
inputs give bit-identical outputs whatever the environment says.
"""

from __future__ import annotations

import functools
import importlib
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


@contextmanager
def single_threaded() -> Iterator[None]:
    """Limit every BLAS/OpenMP pool to one thread inside the block (restored afterwards)."""
    _load_pools()
    with threadpool_limits(limits=1):
        yield


def deterministic(fn: F) -> F:
    """Decorator: run ``fn`` inside :func:`single_threaded`."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with single_threaded():
            return fn(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
