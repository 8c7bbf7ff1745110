"""Compiled C code for CasADi functions, cached on disk by structure.

``compile_function(fn)`` generates C for ``fn`` (``casadi.CodeGenerator``), compiles it
into a shared library with the system C compiler and loads it with ``casadi.external``.
The library is stored under ``cache_dir`` (default: ``$FSICAS_CACHE`` or
``~/.cache/fsicas``) with a name keyed by the sha256 of ``fn.serialize()``, the compiler
flags, the compiler identity, the CasADi version and the platform; a later call, also in
a new process, only loads it. Libraries are built in a private temporary directory and
moved into place with ``os.replace``, so concurrent processes never see a partial file.

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
import functools
import hashlib
import os
import platform
import shlex
import shutil
import subprocess
import tempfile
from pathlib import Path

import casadi as ca

__all__ = ["compile_function", "compile_model", "default_cache_dir", "find_compiler",
           "default_flags"]

_FLAGS_SX = ("-O1",)
_FLAGS_OTHER = ("-O3",)
_COMMON = ("-fPIC", "-shared")
_FORMAT = "fsicas-codegen-2"     # bump to invalidate all cache entries

#: Number of compilations done by this process (cache misses); for tests and benchmarks.
compile_count = 0


def default_cache_dir() -> Path:
    """``$FSICAS_CACHE`` if set, else ``~/.cache/fsicas``."""
    env = os.environ.get("FSICAS_CACHE")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "fsicas"


def find_compiler() -> str:
    """Path of the C compiler: ``$CC``, else gcc, cc or clang; RuntimeError if none."""
    candidates = [os.environ["CC"]] if os.environ.get("CC") else ["gcc", "cc", "clang"]
    for name in candidates:
        path = shutil.which(shlex.split(name)[0]) if name.strip() else None
        if path:
            return path
    raise RuntimeError(
        f"no C compiler found (tried {', '.join(candidates)} on PATH; set CC to choose one): "
        "compiled CasADi functions are unavailable, use the plain CasADi functions instead")


@functools.lru_cache(maxsize=None)
def _compiler_identity(path: str) -> str:
    try:
        out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=30)
        return f"{path}|{out.stdout.splitlines()[0] if out.stdout else ''}"
    except (OSError, subprocess.SubprocessError) as exc:
        raise RuntimeError(f"C compiler {path} does not run: {exc}") from exc


def default_flags(fn: ca.Function) -> tuple[str, ...]:
    """-O1 for SX functions (straight-line code), -O3 otherwise (module docstring)."""
    return _FLAGS_SX if fn.is_a("SXFunction") else _FLAGS_OTHER


def _key(fn: ca.Function, compiler: str, flags, derivatives: bool) -> str:
    h = hashlib.sha256()
    for part in (_FORMAT, ca.__version__, platform.system(), platform.machine(),
                 _compiler_identity(compiler), " ".join(default_flags(fn) if flags is None else flags),
                 f"derivatives={bool(derivatives)}"):
        h.update(part.encode())
        h.update(b"\0")
    h.update(fn.serialize().encode())
    return h.hexdigest()


def compile_function(fn: ca.Function, cache_dir=None, flags=None,
                     timeout: float | None = None, derivatives: bool = False) -> ca.Function:
    """``fn`` as compiled C code (a ``casadi.external``), built once per structure.

    ``flags``: optimization flags (e.g. ``["-O2"]``); None: :func:`default_flags`. ``timeout``: seconds allowed to the compiler.
    ``derivatives``: also compile ``fn.jacobian()`` so the result can be differentiated.
    Raises RuntimeError when no C compiler is available or compilation fails.
    """
    global compile_count
    compiler = find_compiler()
    cache = Path(cache_dir).expanduser() if cache_dir is not None else default_cache_dir()
    key = _key(fn, compiler, flags, derivatives)
    target = cache / f"{fn.name()}_{key[:32]}.so"
    if not target.exists():
        cache.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=cache, prefix=".build-") as tmp:
            source = ca.CodeGenerator(f"{fn.name()}.c", {"with_header": False})
            source.add(fn)
            if derivatives:
                source.add(fn.jacobian())      # named jac_<name>: found by casadi.external
            c_file = source.generate(tmp + os.sep)
            opt = default_flags(fn) if flags is None else tuple(flags)
            so_tmp = os.path.join(tmp, "out.so")
            cmd = [compiler, *opt, *_COMMON, c_file, "-o", so_tmp, "-lm"]
            try:
                done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
            except subprocess.TimeoutExpired as exc:
                raise RuntimeError(f"compiling {fn.name()} took more than {timeout} s") from exc
            if done.returncode != 0:
                raise RuntimeError(f"compiling {fn.name()} failed ({' '.join(cmd)}):\n"
                                   f"{done.stderr[-2000:]}")
            os.replace(so_tmp, target)
            compile_count += 1
    return ca.external(fn.name(), str(target))


def compile_model(model, cache_dir=None, flags=None, timeout: float | None = None,
                  derivatives: bool = False):
    """Copy of ``model`` whose mass, rhs, jac_rhs and jac_rhs_p are compiled C code.

    ``derivatives=True`` makes the compiled rhs differentiable (needed where rhs is
    composed symbolically and differentiated, e.g. :func:`fsicas.steady.steady_state`).
    """
    compiled = {name: compile_function(getattr(model, name), cache_dir, flags, timeout,
                                       derivatives=derivatives and name == "rhs")
                for name in ("mass", "rhs", "jac_rhs", "jac_rhs_p")}
    return dataclasses.replace(model, **compiled)
