"""CasADi Functions compiled to C, cached on disk by structure (``continuation.compilation``).

``compile_function(fn)`` generates C for ``fn`` (``casadi.CodeGenerator``), compiles it
into a shared library with the system C compiler (``-fPIC -shared``) and loads it with
``casadi.external``. The library is stored under ``cache_dir`` (default
:func:`default_cache_dir`: ``$CONTINUATION_CACHE``, else ``$XDG_CACHE_HOME/continuation``
or ``~/.cache/continuation``) with a name keyed by the sha256 of ``fn.serialize()``, the
compiler flags, the compiler identity, the CasADi version and the platform; a later call,
also in a new process, only loads it (and a second call in the same process returns the
loaded function).

Each library has a record beside it and is loaded only if it matches it, from a private
cache (``continuation._casadi.library_cache``, where the rules are stated); a cache directory
that cannot be used is replaced, with one ``RuntimeWarning``, by a temporary directory of
the process (removed at exit). Files are written in a private temporary directory and
moved into place with ``os.replace``, the record before the library, so concurrent
builders of one key never expose a partial file (the builds are byte-identical).

Default flags: ``-O1`` for SX functions (straight-line code, where -O2/-O3 compile times
grow superlinearly with the size of one function body for no run-time gain) and ``-O3``
for MX functions (loops over dense matrix products: measured 1.2x faster than -O2 and
3x faster than -O1 on the collocation kernel of a modal model).

:func:`compiled_or_none` is the fallback form: ``None`` instead of an exception when no
compiler is found or compilation fails (the caller keeps the CasADi function).

:func:`compile_later` builds in the background: it returns a :class:`Deferred` (the
library loaded at once if the cache holds it); its ``poll()`` queues the build and gives
None until the library is loaded, then the function to call from then on, while the
caller goes on evaluating the CasADi function. The compiler is a subprocess, started and
collected by the polls (no threads: CasADi is only used by the caller's thread), at most
:func:`background_slots` at once (the cores but one), the latest request first. A
compiler still running when the process ends is killed and its temporary directory
removed; :func:`compile_function` waits for the same build.
"""

from __future__ import annotations

import atexit
import json
import os
import shlex
import shutil
import subprocess
import tempfile
import time
import warnings
from pathlib import Path

import casadi as ca

from ._casadi.library_cache import (FORMAT, cache_key, check_private, compiler_identity,
                             default_cache_dir, digest, holds, record_path)

__all__ = ["compile_function", "compile_later", "compiled_or_none", "Deferred",
           "default_cache_dir", "default_flags", "find_compiler", "has_compiler",
           "library_path", "check_private", "background_slots"]

_FLAGS_SX = ("-O1",)
_FLAGS_OTHER = ("-O3",)
_COMMON = ("-fPIC", "-shared")

#: Number of compilations done by this process (cache misses); for tests and benchmarks.
compile_count = 0
_SCRATCH: dict = {}          # process id -> its temporary cache directory
_WARNED: set = set()         # unusable cache directories already warned about


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


def default_flags(fn: ca.Function) -> tuple:
    """``-O1`` for SX functions, ``-O3`` otherwise (module docstring)."""
    return _FLAGS_SX if fn.is_a("SXFunction") else _FLAGS_OTHER


def _scratch() -> Path:
    """This process's temporary cache directory (mode 0700, removed at exit)."""
    pid = os.getpid()
    if pid not in _SCRATCH:
        _SCRATCH[pid] = Path(tempfile.mkdtemp(prefix="continuation-cache-"))   # see _at_exit
    return _SCRATCH[pid]


class _Build:
    """One library being made in a private temporary directory beside the target: its C
    source generated and the compiler started as a subprocess (:meth:`start`); once the
    compiler has ended, :meth:`finish` checks it and moves the record and the library to
    ``target`` (each atomically, the record first)."""

    def __init__(self, fn: ca.Function, compiler: str, flags: tuple, derivatives: bool,
                 target: Path, key: str, timeout):
        self.fn, self.compiler, self.flags, self.derivatives = fn, compiler, flags, derivatives
        self.target, self.key, self.timeout = target, key, timeout
        self.proc, self.tmp, self.timed_out = None, None, False
        # OSError here when the cache directory cannot take a build (the caller falls back)
        os.rmdir(tempfile.mkdtemp(dir=target.parent, prefix=".build-"))

    def start(self) -> None:
        """Generate the C source and start the compiler (RuntimeError when it does not
        run; OSError when the cache directory cannot take a build)."""
        self.tmp = Path(tempfile.mkdtemp(dir=self.target.parent, prefix=".build-"))
        try:
            source = ca.CodeGenerator(f"{self.fn.name()}.c", {"with_header": False})
            source.add(self.fn)
            if self.derivatives:
                source.add(self.fn.jacobian())  # named jac_<name>: found by casadi.external
            c_file = source.generate(str(self.tmp) + os.sep)
            self.cmd = [self.compiler, *self.flags, *_COMMON, c_file, "-o",
                        str(self.tmp / "out.so"), "-lm"]
            with open(self.tmp / "stderr.txt", "w") as err:
                self.proc = subprocess.Popen(self.cmd, stdin=subprocess.DEVNULL,
                                             stdout=subprocess.DEVNULL, stderr=err)
        except OSError as exc:
            self.discard()
            raise RuntimeError(f"cannot compile with {self.compiler}: {exc}") from exc
        self.started, self.pid = time.monotonic(), os.getpid()

    def ended(self, wait: bool = False) -> bool:
        """Whether the compiler has ended (``wait``: wait for it); one that runs longer
        than ``timeout`` is killed."""
        left = None if self.timeout is None else self.started + self.timeout - time.monotonic()
        try:
            if wait:
                self.proc.wait(timeout=left)
            elif self.proc.poll() is None:
                if left is None or left > 0:
                    return False
                raise subprocess.TimeoutExpired(self.cmd, self.timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            self.timed_out = True
        return True

    def finish(self) -> None:
        """After the compiler ended: RuntimeError if it failed, else the record and the
        library moved into place."""
        global compile_count
        try:
            if self.timed_out:
                raise RuntimeError(f"compiling {self.fn.name()} took over {self.timeout} s")
            if self.proc.returncode != 0:
                stderr = (self.tmp / "stderr.txt").read_text(errors="replace")
                raise RuntimeError(f"compiling {self.fn.name()} failed "
                                   f"({' '.join(self.cmd)}):\n{stderr[-2000:]}")
            so_tmp = self.tmp / "out.so"
            os.chmod(so_tmp, 0o700)
            record = {"format": FORMAT, "key": self.key, "size": so_tmp.stat().st_size,
                      "sha256": digest(so_tmp), "compiler": compiler_identity(self.compiler),
                      "flags": [*self.flags, *_COMMON]}
            record_tmp = self.tmp / "out.json"
            record_tmp.write_text(json.dumps(record, indent=1) + "\n")
            os.replace(record_tmp, record_path(self.target))
            os.replace(so_tmp, self.target)
            compile_count += 1
        finally:
            self.discard()

    def discard(self) -> None:
        """Kill the compiler if it still runs (in this process) and remove the temporary
        directory."""
        if self.proc is not None and self.pid == os.getpid() and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        if self.tmp is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)


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


class Deferred:
    """A CasADi Function and its compiled library (:func:`compile_later`): loaded at once
    when the cache holds it, else built when asked for: :meth:`poll` builds it in the
    background and gives the function to call meanwhile, :meth:`wait` builds it now."""

    def __init__(self, fn: ca.Function, target: Path | None = None, build=None):
        self.fn, self.target, self.build = fn, target, build
        #: the compiled function once loaded; the reason it could not be, an exception
        self.compiled, self.error = None, None
        self._warned = False

    @property
    def done(self) -> bool:
        """Whether nothing is left to build (the library loaded, or it cannot be)."""
        return self.build is None

    def poll(self) -> ca.Function | None:
        """None while the library is being built (its build queued at the first poll);
        then the function to call from now on: the compiled one or, if it could not be
        built, ``fn`` (with one RuntimeWarning)."""
        if self.build is not None:
            if self not in _RUNNING and self not in _QUEUED:
                _QUEUED.append(self)
            _pump()
            if self.build is not None:
                return None
        if self.error is not None and not self._warned:
            self._warned = True
            warnings.warn(f"falling back to the CasADi function: {self.error}",
                          RuntimeWarning, stacklevel=2)
        return self.fn if self.compiled is None else self.compiled

    def wait(self) -> ca.Function:
        """The compiled function, built now if it is still waiting for a compiler;
        RuntimeError (or OSError) if it cannot be built."""
        _own()
        if self.build is not None and self not in _RUNNING:
            if self in _QUEUED:
                _QUEUED.remove(self)
            self._start()
        if self in _RUNNING:
            _RUNNING.remove(self)
            self.build.ended(wait=True)
            self._complete()
        if self.error is not None:
            raise self.error
        if self.compiled is None:
            raise RuntimeError(f"{self.fn.name()} is not compiled (no compiler; a parent's)")
        return self.compiled

    def _start(self) -> None:
        try:
            self.build.start()
        except (RuntimeError, OSError) as exc:
            self._fail(exc)
        else:
            _RUNNING.append(self)

    def _complete(self) -> None:
        """Finish the build whose compiler ended and load the library."""
        try:
            self.build.finish()
            self.compiled = ca.external(self.fn.name(), str(self.target))
        except (RuntimeError, OSError) as exc:
            self._fail(exc)
        self.build = None

    def _fail(self, exc: Exception) -> None:
        self.build, self.error = None, exc
        _REQUESTS.pop((str(self.target), self.fn.name()), None)     # a later request retries


_REQUESTS: dict = {}         # (library, name) -> its Deferred
_QUEUED: list = []           # Deferreds whose compiler has not started yet
_RUNNING: list = []          # Deferreds whose compiler runs
_OWNER = [os.getpid()]       # the process whose builds these are


def background_slots() -> int:
    """How many compilers run at once in the background: the cores this process may
    use but one (the computation's), at least one."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:
        cores = os.cpu_count() or 1
    return max(1, cores - 1)


def _own() -> None:
    """In a forked process, leave the parent's builds to the parent (their functions stay
    uncompiled here; waiting for a compiler that is not our child would see it end)."""
    if _OWNER[0] != os.getpid():
        _OWNER[0] = os.getpid()
        for deferred in _QUEUED + _RUNNING:
            deferred.build = None
            _REQUESTS.pop((str(deferred.target), deferred.fn.name()), None)
        _QUEUED.clear()
        _RUNNING.clear()


def _pump() -> None:
    """Complete the background builds whose compiler ended and start queued ones while
    fewer than :func:`background_slots` run, the latest request first (the one most
    likely still in use)."""
    _own()
    for deferred in [d for d in _RUNNING if d.build.ended()]:
        _RUNNING.remove(deferred)
        deferred._complete()
    while _QUEUED and len(_RUNNING) < background_slots():
        _QUEUED.pop()._start()


@atexit.register
def _at_exit() -> None:
    """Kill this process's compilers still running, drop the queued builds (nothing is
    kept half-built) and remove the temporary cache directory."""
    if _OWNER[0] == os.getpid():
        for deferred in _QUEUED + _RUNNING:
            deferred.build.discard()
    if os.getpid() in _SCRATCH:
        shutil.rmtree(_SCRATCH[os.getpid()], ignore_errors=True)


def _request(fn: ca.Function, cache_dir, flags, timeout, derivatives: bool) -> Deferred:
    """The Deferred of ``fn``'s library: loaded if the cache holds it, else to be built
    (one per library and process). RuntimeError without a compiler or when the
    cache is not private; an unusable cache directory is replaced by a temporary one."""
    target, key, compiler, opt = _locate(fn, cache_dir, flags, derivatives)
    try:
        return _deferred(fn, target, key, compiler, opt, derivatives, timeout)
    except OSError as exc:
        cache, target = target.parent, _scratch() / target.name
        if cache not in _WARNED:
            _WARNED.add(cache)
            why = "not a directory" if cache.is_file() else exc.strerror or str(exc)
            warnings.warn(
                f"cannot use the compiled-code cache {cache} ({why}): "
                f"compiling into {target.parent} for this process only", RuntimeWarning,
                stacklevel=3)
        return _deferred(fn, target, key, compiler, opt, derivatives, timeout)


def _deferred(fn, target, key, compiler, flags, derivatives, timeout) -> Deferred:
    ident = (str(target), fn.name())
    if ident not in _REQUESTS:
        if holds(target, key):
            deferred = Deferred(fn, target)
            deferred.compiled = ca.external(fn.name(), str(target))
        else:
            build = _Build(fn, compiler, flags, derivatives, target, key, timeout)
            deferred = Deferred(fn, target, build)
        _REQUESTS[ident] = deferred
    return _REQUESTS[ident]


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
    return _request(fn, cache_dir, flags, timeout, derivatives).wait()


def compile_later(fn: ca.Function, cache_dir=None, flags=None,
                  timeout: float | None = None) -> Deferred:
    """``fn``'s compiled library as a :class:`Deferred`: loaded at once if the cache
    holds it, else built when asked for, by ``wait()`` or in the background by
    ``poll()``: a compiler runs beside this process (started and collected whenever a
    Deferred is polled, :func:`background_slots` at once) while the caller goes on with
    ``fn``. Never raises: without a compiler, or when the cache is refused, ``poll()``
    gives ``fn`` at once (the latter with a RuntimeWarning)."""
    if not has_compiler():
        return Deferred(fn)
    try:
        return _request(fn, cache_dir, flags, timeout, False)
    except (RuntimeError, OSError) as exc:
        deferred = Deferred(fn)
        deferred.error = exc
        return deferred


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
