"""CasADi Functions compiled to C, cached on disk by structure (``continuation.compilation``).

``compile_function(fn)`` generates C for ``fn`` (``casadi.CodeGenerator``), compiles it
into a shared library with the system C compiler (``-fPIC -shared``) and loads it with
``casadi.external``. The library is stored under ``cache_dir`` (default
:func:`default_cache_dir`: ``$CONTINUATION_CACHE``, else ``$XDG_CACHE_HOME/continuation``
or ``~/.cache/continuation``) with a name keyed by the sha256 of ``fn.serialize()``, the
compiler flags, the compiler identity, the CasADi version and the platform; a later call,
also in a new process, only loads it (and a second call in the same process returns the
loaded function). Libraries are built in a private temporary directory and moved into
place with ``os.replace``, so concurrent processes never see a partial file.

Loading a library runs its code, so the cache is trusted only as far as it is private:
the cache directory is created with mode 0700 and refused (``RuntimeError``) when it or
a library in it belongs to another user or is writable by group or others; every
library has the sha256 of its bytes recorded beside it (``<library>.sha256``) when it
is built, and a library whose bytes do not match its record (planted, truncated or
altered after the build) is rebuilt instead of loaded.

Default flags: ``-O1`` for SX functions (straight-line code, where -O2/-O3 compile times
grow superlinearly with the size of one function body for no run-time gain) and ``-O3``
for MX functions (loops over dense matrix products: measured 1.2x faster than -O2 and
3x faster than -O1 on the collocation kernel of a modal model).

:func:`compiled_or_none` is the fallback form: ``None`` instead of an exception when no
compiler is found or compilation fails (the caller keeps the CasADi function).
"""

from __future__ import annotations

import functools
import hashlib
import os
import platform
import shlex
import shutil
import stat
import subprocess
import tempfile
import warnings
from pathlib import Path

import casadi as ca

__all__ = ["compile_function", "compiled_or_none", "default_cache_dir", "default_flags",
           "find_compiler", "has_compiler", "library_path", "check_private"]

_FLAGS_SX = ("-O1",)
_FLAGS_OTHER = ("-O3",)
_COMMON = ("-fPIC", "-shared")
_FORMAT = "continuation-compile-1"     # bump to invalidate all cache entries

#: Number of compilations done by this process (cache misses); for tests and benchmarks.
compile_count = 0
_LOADED: dict = {}


def default_cache_dir() -> Path:
    """``$CONTINUATION_CACHE`` if set, else ``$XDG_CACHE_HOME/continuation`` or
    ``~/.cache/continuation``."""
    env = os.environ.get("CONTINUATION_CACHE")
    if env:
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME")
    return (Path(base).expanduser() if base else Path.home() / ".cache") / "continuation"


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


def has_compiler() -> bool:
    """Whether :func:`find_compiler` finds a compiler."""
    try:
        find_compiler()
    except RuntimeError:
        return False
    return True


@functools.lru_cache(maxsize=None)
def _compiler_identity(path: str) -> str:
    """``path`` and the first line of ``path --version``."""
    try:
        out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=30)
        return f"{path}|{out.stdout.splitlines()[0] if out.stdout else ''}"
    except (OSError, subprocess.SubprocessError) as exc:
        raise RuntimeError(f"C compiler {path} does not run: {exc}") from exc


def default_flags(fn: ca.Function) -> tuple:
    """``-O1`` for SX functions, ``-O3`` otherwise (module docstring)."""
    return _FLAGS_SX if fn.is_a("SXFunction") else _FLAGS_OTHER


def _cpu() -> str:
    """The CPU model (part of the key of ``-march=native`` builds)."""
    try:
        with open("/proc/cpuinfo") as f:
            return next((line for line in f if line.startswith("model name")), "")
    except OSError:
        return platform.processor()


def cache_key(fn: ca.Function, compiler: str, flags: tuple, derivatives: bool) -> str:
    """sha256 of the format, CasADi version, platform, compiler, flags and ``fn``."""
    h = hashlib.sha256()
    parts = [_FORMAT, ca.__version__, platform.system(), platform.machine(),
             _compiler_identity(compiler), " ".join(flags), f"derivatives={bool(derivatives)}"]
    if any("native" in flag for flag in flags):
        parts.append(_cpu())
    for part in parts:
        h.update(part.encode())
        h.update(b"\0")
    h.update(fn.serialize().encode())
    return h.hexdigest()


def check_private(path: Path) -> None:
    """RuntimeError unless ``path`` belongs to this user and is not writable by group or
    others (POSIX; nothing is checked where there are no user ids)."""
    if not hasattr(os, "getuid"):
        return
    st = path.stat()
    problems = []
    if st.st_uid != os.getuid():
        problems.append(f"owned by user id {st.st_uid}")
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        problems.append(f"writable by group or others (mode {oct(st.st_mode & 0o777)})")
    if problems:
        raise RuntimeError(
            f"refusing to load compiled code from {path}: it is {' and '.join(problems)}; "
            "use a private cache directory (CONTINUATION_CACHE or FSICAS_CACHE, or chmod go-w)")


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _record(target: Path) -> Path:
    """Where the sha256 of the library ``target`` is recorded."""
    return target.with_name(target.name + ".sha256")


def _trusted(target: Path) -> bool:
    """Whether ``target`` exists, is private and matches its recorded sha256."""
    if not target.exists():
        return False
    check_private(target)
    record = _record(target)
    try:
        return record.read_text().strip() == _digest(target)
    except OSError:
        return False


def _cache_directory(cache: Path) -> Path:
    """``cache``, created with mode 0700 if missing, and checked private."""
    cache.mkdir(mode=0o700, parents=True, exist_ok=True)
    check_private(cache)
    return cache


def _build(fn: ca.Function, compiler: str, flags: tuple, derivatives: bool,
           target: Path, timeout) -> None:
    """Generate, compile and atomically move the library of ``fn`` and its sha256
    record to ``target``."""
    global compile_count
    with tempfile.TemporaryDirectory(dir=target.parent, prefix=".build-") as tmp:
        source = ca.CodeGenerator(f"{fn.name()}.c", {"with_header": False})
        source.add(fn)
        if derivatives:
            source.add(fn.jacobian())      # named jac_<name>: found by casadi.external
        c_file = source.generate(tmp + os.sep)
        so_tmp = os.path.join(tmp, "out.so")
        cmd = [compiler, *flags, *_COMMON, c_file, "-o", so_tmp, "-lm"]
        try:
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired as exc:
            raise RuntimeError(f"compiling {fn.name()} took more than {timeout} s") from exc
        if done.returncode != 0:
            raise RuntimeError(f"compiling {fn.name()} failed ({' '.join(cmd)}):\n"
                               f"{done.stderr[-2000:]}")
        os.chmod(so_tmp, 0o700)
        record_tmp = Path(tmp) / "out.sha256"
        record_tmp.write_text(_digest(Path(so_tmp)) + "\n")
        os.replace(record_tmp, _record(target))
        os.replace(so_tmp, target)
        compile_count += 1


def library_path(fn: ca.Function, cache_dir=None, flags=None,
                 derivatives: bool = False) -> Path:
    """Where the compiled library of ``fn`` is (or would be) cached."""
    compiler = find_compiler()
    opt = default_flags(fn) if flags is None else tuple(flags)
    cache = Path(cache_dir).expanduser() if cache_dir is not None else default_cache_dir()
    return cache / f"{fn.name()}_{cache_key(fn, compiler, opt, derivatives)[:32]}.so"


def compile_function(fn: ca.Function, cache_dir=None, flags=None,
                     timeout: float | None = None, derivatives: bool = False) -> ca.Function:
    """``fn`` as compiled C code (a ``casadi.external``), built once per structure.

    ``flags``: optimization flags (e.g. ``["-O2"]``); None: :func:`default_flags`.
    ``timeout``: seconds allowed to the compiler. ``derivatives``: also compile
    ``fn.jacobian()`` so the result can be differentiated (first derivatives only).
    Raises RuntimeError when no C compiler is available, compilation fails or the
    cache is not private (module docstring).
    """
    target = library_path(fn, cache_dir, flags, derivatives)
    key = (str(target), fn.name())
    if key not in _LOADED:
        _cache_directory(target.parent)
        if not _trusted(target):
            opt = default_flags(fn) if flags is None else tuple(flags)
            _build(fn, find_compiler(), opt, derivatives, target, timeout)
        _LOADED[key] = ca.external(fn.name(), str(target))
    return _LOADED[key]


def compiled_or_none(fn: ca.Function, cache_dir=None, flags=None) -> ca.Function | None:
    """:func:`compile_function`, or None (with a RuntimeWarning when a compiler exists
    but fails) when ``fn`` cannot be compiled."""
    if not has_compiler():
        return None
    try:
        return compile_function(fn, cache_dir, flags)
    except RuntimeError as exc:
        warnings.warn(f"falling back to the CasADi function: {exc}", RuntimeWarning,
                      stacklevel=2)
        return None
