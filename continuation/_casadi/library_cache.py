"""The on-disk cache of compiled libraries (``continuation.compilation``): where it is,
the key of a library, its record, and the checks before a library is loaded.

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
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import platform
import stat
import subprocess
import warnings
from pathlib import Path

import casadi as ca

__all__ = ["FORMAT", "default_cache_dir", "compiler_identity", "cache_key", "check_private",
           "digest", "record_path", "mismatch", "cache_directory", "holds"]

FORMAT = "continuation-compile-2"     # bump to invalidate all cache entries


def default_cache_dir() -> Path:
    """``$CONTINUATION_CACHE`` if set, else ``$XDG_CACHE_HOME/continuation`` or
    ``~/.cache/continuation``."""
    env = os.environ.get("CONTINUATION_CACHE")
    if env:
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME")
    return (Path(base).expanduser() if base else Path.home() / ".cache") / "continuation"


@functools.lru_cache(maxsize=None)
def compiler_identity(path: str) -> str:
    """``path`` and the first line of ``path --version``."""
    try:
        out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=30)
        return f"{path}|{out.stdout.splitlines()[0] if out.stdout else ''}"
    except (OSError, subprocess.SubprocessError) as exc:
        raise RuntimeError(f"C compiler {path} does not run: {exc}") from exc


def cpu_model() -> str:
    """The CPU model (part of the key of ``-march=native`` builds)."""
    try:
        with open("/proc/cpuinfo") as f:
            return next((line for line in f if line.startswith("model name")), "")
    except OSError:
        return platform.processor()


def cache_key(fn: ca.Function, compiler: str, flags: tuple, derivatives: bool) -> str:
    """sha256 of the format, CasADi version, platform, compiler, flags and ``fn``."""
    h = hashlib.sha256()
    parts = [FORMAT, ca.__version__, platform.system(), platform.machine(),
             compiler_identity(compiler), " ".join(flags), f"derivatives={bool(derivatives)}"]
    if any("native" in flag for flag in flags):
        parts.append(cpu_model())
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


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def record_path(target: Path) -> Path:
    """The record of the library ``target``."""
    return target.with_name(target.name + ".json")


def mismatch(target: Path, key: str) -> str | None:
    """None if the existing library ``target`` matches its record, else why not."""
    try:
        record = json.loads(record_path(target).read_text())
        size, sha256 = int(record["size"]), record["sha256"]
        if record["key"] != key:
            return "its record is that of another function"
    except FileNotFoundError:
        return "it has no record"
    except (OSError, ValueError, KeyError, TypeError) as exc:
        return f"its record is unreadable ({type(exc).__name__}: {exc})"
    actual = target.stat().st_size
    if actual != size:
        return f"it has {actual} bytes, its record {size} (truncated or altered)"
    if digest(target) != sha256:
        return "its sha256 differs from its record (altered)"
    return None


def cache_directory(cache: Path) -> Path:
    """``cache``, created with mode 0700 if missing, and checked private."""
    cache.mkdir(mode=0o700, parents=True, exist_ok=True)
    check_private(cache)
    return cache


def holds(target: Path, key: str) -> bool:
    """Whether ``target`` is a library that matches its record (its directory created
    private if missing; a mismatch is warned about: the library is then rebuilt)."""
    cache_directory(target.parent)
    if not target.exists():
        return False
    check_private(target)
    why = mismatch(target, key)
    if why is not None:
        warnings.warn(f"rebuilding the compiled library {target}: {why}", RuntimeWarning,
                      stacklevel=4)
    return why is None
