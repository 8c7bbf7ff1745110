"""LAPACK and BLAS for the compiled layer (``_jit``): SciPy's ``cython_lapack`` and
``cython_blas`` routines as external functions of numba, bound to process-wide symbols
by name (``continuation_dgetrf``, ...), so that numba's cached machine code, which
refers to the symbol, stays valid in a new process. Imported by ``_jit`` only."""

from __future__ import annotations

import llvmlite.binding as llvm
from numba import types
from numba.extending import get_cython_function_address


def _bound(module: str, name: str, nargs: int):
    """SciPy's ``module.name`` (all arguments pointers, Fortran convention) as an external
    function of numba, through a symbol of this process named after it."""
    symbol = f"continuation_{name}"
    llvm.add_symbol(symbol, get_cython_function_address(f"scipy.linalg.{module}", name))
    return types.ExternalFunction(symbol, types.void(*([types.voidptr] * nargs)))


dgetrf = _bound("cython_lapack", "dgetrf", 6)
dgetrs = _bound("cython_lapack", "dgetrs", 9)
dgeqrf = _bound("cython_lapack", "dgeqrf", 8)
dormqr = _bound("cython_lapack", "dormqr", 13)
dtrsm = _bound("cython_blas", "dtrsm", 11)
dgemm = _bound("cython_blas", "dgemm", 13)
dgbtrf = _bound("cython_lapack", "dgbtrf", 8)
