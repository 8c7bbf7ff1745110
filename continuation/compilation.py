"""CasADi Functions compiled to C, cached on disk by structure (``continuation.compilation``).

``compile_function(fn)`` generates C for ``fn`` (``casadi.CodeGenerator``), compiles it
into a shared library with the system C compiler (``-fPIC -shared``) and loads it with
``casadi.external``. The library is stored under ``cache_dir`` (default
:func:`default_cache_dir`: ``$CONTINUATION_CACHE``, else ``$XDG_CACHE_HOME/continuation``
or ``~/.cache/continuation``) with a name keyed by the sha256 of ``fn.serialize()``, the
compiler flags, the compiler identity, the CasADi version and the platform; a later call,
also in a new process, only loads it (and a second call in the same process returns the
loaded function).

Each library has a record beside it (``<library>.json``: its key, size and sha256, the
compiler and the flags). A library is loaded only if it matches its record: one without
a record, or whose size or sha256 differs (planted, truncated, altered), is rebuilt with
a ``RuntimeWarning`` naming it, never loaded (loading a truncated library can crash the
process). Files are written in a private temporary directory and moved into place with
``os.replace``, the record before the library, so concurrent builders of one key never
expose a partial file, and a reader that finds the record but not yet the library just
builds it too (the builds are byte-identical).

Loading a library runs its code, so the cache is trusted only as far as it is private:
the cache directory is created with mode 0700 and refused (``RuntimeError``) when it or
a library in it belongs to another user or is writable by group or others. A cache
directory that cannot be used (the path is a file, not writable, on a read-only file
system) is replaced, with one ``RuntimeWarning``, by a temporary directory of the process
(removed at exit): the function is still compiled, but not kept for later processes.

Default flags: ``-O1`` for SX functions (straight-line code, where -O2/-O3 compile times
grow superlinearly with the size of one function body for no run-time gain) and ``-O3``
for MX functions (loops over dense matrix products: measured 1.2x faster than -O2 and
3x faster than -O1 on the collocation kernel of a modal model).

:func:`compiled_or_none` is the fallback form: ``None`` instead of an exception when no
compiler is found or compilation fails (the caller keeps the CasADi function).
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import json
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
_FORMAT = "continuation-compile-2"     # bump to invalidate all cache entries

#: Number of compilations done by this process (cache misses); for tests and benchmarks.
compile_count = 0
_LOADED: dict = {}
_SCRATCH: dict = {}          # process id -> its temporary cache directory
_WARNED: set = set()         # unusable cache directories already warned about


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
    """The record of the library ``target``."""
    return target.with_name(target.name + ".json")


def _mismatch(target: Path, key: str) -> str | None:
    """None if the existing library ``target`` matches its record, else why not."""
    try:
        record = json.loads(_record(target).read_text())
        size, digest = int(record["size"]), record["sha256"]
        if record["key"] != key:
            return "its record is that of another function"
    except FileNotFoundError:
        return "it has no record"
    except (OSError, ValueError, KeyError, TypeError) as exc:
        return f"its record is unreadable ({type(exc).__name__}: {exc})"
    actual = target.stat().st_size
    if actual != size:
        return f"it has {actual} bytes, its record {size} (truncated or altered)"
    if _digest(target) != digest:
        return "its sha256 differs from its record (altered)"
    return None


def _cache_directory(cache: Path) -> Path:
    """``cache``, created with mode 0700 if missing, and checked private."""
    cache.mkdir(mode=0o700, parents=True, exist_ok=True)
    check_private(cache)
    return cache


def _scratch() -> Path:
    """This process's temporary cache directory (mode 0700, removed at exit)."""
    pid = os.getpid()
    if pid not in _SCRATCH:
        _SCRATCH[pid] = Path(tempfile.mkdtemp(prefix="continuation-cache-"))
        atexit.register(shutil.rmtree, _SCRATCH[pid], True)
    return _SCRATCH[pid]


def _build(fn: ca.Function, compiler: str, flags: tuple, derivatives: bool,
           target: Path, key: str, timeout) -> None:
    """Generate and compile the library of ``fn``, then move its record and the library
    to ``target`` (each atomically, the record first)."""
    global compile_count
    with tempfile.TemporaryDirectory(dir=target.parent, prefix=".build-") as tmp:
        source = ca.CodeGenerator(f"{fn.name()}.c", {"with_header": False})
        source.add(fn)
        if derivatives:
            source.add(fn.jacobian())      # named jac_<name>: found by casadi.external
        c_file = source.generate(tmp + os.sep)
        so_tmp = Path(tmp) / "out.so"
        cmd = [compiler, *flags, *_COMMON, c_file, "-o", str(so_tmp), "-lm"]
        try:
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired as exc:
            raise RuntimeError(f"compiling {fn.name()} took more than {timeout} s") from exc
        except OSError as exc:
            raise RuntimeError(f"C compiler {compiler} does not run: {exc}") from exc
        if done.returncode != 0:
            raise RuntimeError(f"compiling {fn.name()} failed ({' '.join(cmd)}):\n"
                               f"{done.stderr[-2000:]}")
        os.chmod(so_tmp, 0o700)
        record = {"format": _FORMAT, "key": key, "size": so_tmp.stat().st_size,
                  "sha256": _digest(so_tmp), "compiler": _compiler_identity(compiler),
                  "flags": [*flags, *_COMMON]}
        record_tmp = Path(tmp) / "out.json"
        record_tmp.write_text(json.dumps(record, indent=1) + "\n")
        os.replace(record_tmp, _record(target))
        os.replace(so_tmp, target)
        compile_count += 1


def _locate(fn: ca.Function, cache_dir, flags, derivatives: bool):
    """``(library path, key, compiler, flags)`` of ``fn``."""
    compiler = find_compiler()
    opt = default_flags(fn) if flags is None else tuple(flags)
    key = cache_key(fn, compiler, opt, derivatives)
    cache = Path(cache_dir).expanduser() if cache_dir is not None else default_cache_dir()
    return cache / f"{fn.name()}_{key[:32]}.so", key, compiler, opt


def library_path(fn: ca.Function, cache_dir=None, flags=None,
                 derivatives: bool = False) -> Path:
    """Where the compiled library of ``fn`` is (or would be) cached."""
    return _locate(fn, cache_dir, flags, derivatives)[0]


def _load_or_build(fn: ca.Function, target: Path, key: str, compiler: str, flags: tuple,
                   derivatives: bool, timeout) -> None:
    """Make ``target`` a library of ``fn`` that matches its record."""
    _cache_directory(target.parent)
    if target.exists():
        check_private(target)
        why = _mismatch(target, key)
        if why is None:
            return
        warnings.warn(f"rebuilding the compiled library {target}: {why}", RuntimeWarning,
                      stacklevel=3)
    _build(fn, compiler, flags, derivatives, target, key, timeout)


def compile_function(fn: ca.Function, cache_dir=None, flags=None,
                     timeout: float | None = None, derivatives: bool = False) -> ca.Function:
    """``fn`` as compiled C code (a ``casadi.external``), built once per structure.

    ``flags``: optimization flags (e.g. ``["-O2"]``); None: :func:`default_flags`.
    ``timeout``: seconds allowed to the compiler. ``derivatives``: also compile
    ``fn.jacobian()`` so the result can be differentiated (first derivatives only).
    Raises RuntimeError when no C compiler is available, compilation fails or the
    cache is not private; an unusable cache directory is replaced by a temporary one
    with a warning (module docstring).
    """
    target, key, compiler, opt = _locate(fn, cache_dir, flags, derivatives)
    if (str(target), fn.name()) in _LOADED:
        return _LOADED[str(target), fn.name()]
    try:
        _load_or_build(fn, target, key, compiler, opt, derivatives, timeout)
    except OSError as exc:
        cache, target = target.parent, _scratch() / target.name
        if cache not in _WARNED:
            _WARNED.add(cache)
            why = "not a directory" if cache.is_file() else exc.strerror or str(exc)
            warnings.warn(
                f"cannot use the compiled-code cache {cache} ({why}): "
                f"compiling into {target.parent} for this process only", RuntimeWarning,
                stacklevel=2)
        if (str(target), fn.name()) in _LOADED:
            return _LOADED[str(target), fn.name()]
        _load_or_build(fn, target, key, compiler, opt, derivatives, timeout)
    _LOADED[str(target), fn.name()] = ca.external(fn.name(), str(target))
    return _LOADED[str(target), fn.name()]


def compiled_or_none(fn: ca.Function, cache_dir=None, flags=None) -> ca.Function | None:
    """:func:`compile_function`, or None (with a RuntimeWarning when a compiler exists
    but fails) when ``fn`` cannot be compiled."""
    if not has_compiler():
        return None
    try:
        return compile_function(fn, cache_dir, flags)
    except (RuntimeError, OSError) as exc:
        warnings.warn(f"falling back to the CasADi function: {exc}", RuntimeWarning,
                      stacklevel=2)
        return None
