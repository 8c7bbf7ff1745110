"""One BLAS thread for the many small and mid-size dense problems of a continuation run.

A continuation step solves many dense systems of size 10-1000 (the Floquet condensation
of every mesh interval, bordered solves, small eigenproblems). Multithreaded OpenBLAS is
slower on them than one thread, and pathologically so on a shared machine: 20 dense
solves of size 328 with 82 right-hand sides took 4.3 s with two threads on a loaded
2-core machine and 0.13 s with one. The driver and the Floquet routines therefore run in
:func:`single_threaded`, which limits the BLAS and OpenMP pools to one thread through
``threadpoolctl`` and restores them on exit, so the caller's session is left as it was.
"""

from __future__ import annotations

from contextlib import contextmanager
from functools import lru_cache

from threadpoolctl import ThreadpoolController

#: how many :func:`single_threaded` contexts are open (only the outermost one limits)
_depth = 0


@lru_cache(maxsize=1)
def _controller() -> ThreadpoolController:
    """The thread pools of the loaded libraries (found once, at first use: NumPy and
    SciPy are imported by then)."""
    return ThreadpoolController()


@contextmanager
def single_threaded():
    """Context manager: BLAS/OpenMP pools limited to one thread inside, restored after.
    Inside another one (the driver's, around a whole run), or when every pool has one
    thread already (``OPENBLAS_NUM_THREADS=1``), it does nothing: a limit costs 10-40
    us, more than the small eigenproblem of a point it guards; the check costs 1 us."""
    global _depth
    pools = _controller()
    if _depth or all(pool.num_threads == 1 for pool in pools.lib_controllers):
        yield
        return
    with pools.limit(limits=1):
        _depth += 1
        try:
            yield
        finally:
            _depth -= 1
