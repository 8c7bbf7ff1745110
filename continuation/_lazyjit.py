"""Compiled leaves, and numba imported only when one is first called.

``import continuation`` does not import numba (0.25 s) and a problem that never calls
compiled code (an equilibrium branch, a Hopf curve) never pays numba's start (about
0.4 s in a new process, even with the compiled code cached): :func:`jit` compiles a
function, with numba's ``njit(cache=True, nogil=True)``, at its first call. Only for
leaves, which call nothing compiled: a compiled caller must see a numba function, and
lives with its callees in ``continuation._jit``.
"""

from __future__ import annotations

from functools import wraps

#: blocks of at most this many rows are handled by loops, larger ones by LAPACK/BLAS
SMALL = 32

#: the ``kl`` of the band arguments of ``_jit.condensed_solve`` for interval factors side
#: by side (``_jit.side_interval_factors``; a band has ``kl >= 0``, dense factors -1)
SIDE_BY_SIDE = -2

#: the ``kl`` of those band arguments for dense interval factors with kinematic rows
#: eliminated by block (``_dense.kinematic_factor``; ``ku``: their number)
KINEMATIC = -3

#: the relative rounding allowed between a kinematic row's entries on its own position
#: and ``c Dm`` (``_intervals.kinematic_rows``, ``_dense.kinematic_factor``)
SCALE_TOL = 1e-15


def jit(fun):
    """``fun`` compiled by numba (cached on disk) at its first call."""
    compiled = None

    @wraps(fun)
    def call(*args):
        nonlocal compiled
        if compiled is None:
            from numba import njit
            compiled = njit(cache=True, nogil=True)(fun)
        return compiled(*args)

    return call
