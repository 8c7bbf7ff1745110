"""Compiled C code for CasADi functions, cached on disk by structure.

The generic machinery lives in the continuation library (``continuation.compilation``:
code generation, the system C compiler, the on-disk cache keyed by ``fn.serialize()``
and the flags, atomic writes, each library checked against its record before it is
loaded, a temporary directory when the cache directory cannot be used); this module
sets fsicas' cache directory (``$FSICAS_CACHE`` or ``~/.cache/fsicas``) and compiles a
whole model.

``compile_function(fn)`` generates C for ``fn``, compiles it into a shared library and
loads it with ``casadi.external``; a later call, also in a new process, only loads it.

Flags (measured in ``docs/performance.md``): SX-built functions are straight-line code,
where gcc's -O2/-O3 cost grows superlinearly with the size of one function body (the SX
Jacobian of N = 20 is 11 MB of C: -O1 30 s, -O2 > 6 min) for no run-time gain, so the
default is ``-O1`` for SX functions; MX-built code has loops, where -O3 runs up to 3x
faster than -O1, so the default is ``-O3`` for everything else.

A compiled function can be called with numbers or symbols (it becomes one call node),
but it cannot be differentiated unless compiled with ``derivatives=True``, which also
compiles ``fn.jacobian()`` into the library (first derivatives only).
"""
from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import casadi as ca

from continuation import compilation
from continuation.compilation import default_flags, find_compiler

__all__ = ["compile_function", "compile_model", "default_cache_dir", "find_compiler",
           "default_flags"]

#: Number of compilations done by this process (cache misses); for tests and benchmarks.
compile_count = 0


def default_cache_dir() -> Path:
    """``$FSICAS_CACHE`` if set, else ``~/.cache/fsicas``."""
    env = os.environ.get("FSICAS_CACHE")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "fsicas"


def compile_function(fn: ca.Function, cache_dir=None, flags=None,
                     timeout: float | None = None, derivatives: bool = False) -> ca.Function:
    """``fn`` as compiled C code (a ``casadi.external``), built once per structure.

    ``flags``: optimization flags (e.g. ``["-O2"]``); None: :func:`default_flags`.
    ``timeout``: seconds allowed to the compiler. ``derivatives``: also compile
    ``fn.jacobian()`` so the result can be differentiated.
    Raises RuntimeError when no C compiler is available, compilation fails or the cache
    directory is not private; a cache directory that cannot be used (a file, not
    writable) is replaced by a temporary one with a RuntimeWarning.
    """
    global compile_count
    before = compilation.compile_count
    cache = default_cache_dir() if cache_dir is None else cache_dir
    try:
        return compilation.compile_function(fn, cache, flags, timeout, derivatives)
    finally:
        compile_count += compilation.compile_count - before


def compile_model(model, cache_dir=None, flags=None, timeout: float | None = None,
                  derivatives: bool = False):
    """Copy of ``model`` whose mass, rhs, jac_rhs and jac_rhs_p are compiled C code.

    ``derivatives=True`` makes the compiled rhs differentiable (needed where rhs is
    composed symbolically and differentiated, e.g. :func:`fsicas.linear.steady.steady_state`).
    """
    compiled = {name: compile_function(getattr(model, name), cache_dir, flags, timeout,
                                       derivatives=derivatives and name == "rhs")
                for name in ("mass", "rhs", "jac_rhs", "jac_rhs_p")}
    return dataclasses.replace(model, **compiled)
