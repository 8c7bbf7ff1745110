"""The compiled-code cache loads only what it built: a planted, truncated or altered
library is rebuilt, a cache that others can write to is refused, a cache directory that
cannot be used is replaced by a temporary one (``continuation.compilation``). Libraries
are loaded in new processes: a bad one loaded by mistake would crash the process, not
fail an assertion."""

import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
import warnings

import casadi as ca
import pytest

from continuation import compilation

pytestmark = pytest.mark.skipif(not compilation.has_compiler(), reason="no C compiler")

#: In a new process (a library once loaded stays loaded under its path): compile
#: g(x) = x**power into ``cache`` and print g(2) and the number of compilations.
SCRIPT = textwrap.dedent("""
    import sys
    import casadi as ca
    from continuation import compilation
    cache, power = sys.argv[1], int(sys.argv[2])
    x = ca.SX.sym("x")
    g = compilation.compile_function(ca.Function("g", [x], [x ** power]), cache_dir=cache)
    print(float(g(2.0)), compilation.compile_count)
""")


def run_script(cache, power: int, env=None) -> subprocess.CompletedProcess:
    """:data:`SCRIPT` in a new process; fails the test unless it exits with 0."""
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(cache), str(power)],
                         capture_output=True, text=True, env={**os.environ, **(env or {})})
    assert out.returncode == 0, f"exit status {out.returncode}:\n{out.stderr}"
    return out


def compile_in_new_process(cache, power: int) -> tuple[float, int]:
    """(g(2), compilations) of :data:`SCRIPT`."""
    value, count = run_script(cache, power).stdout.split()
    return float(value), int(count)


def library_of(cache, power: int):
    x = ca.SX.sym("x")
    return compilation.library_path(ca.Function("g", [x], [x ** power]), cache_dir=cache)


def test_planted_library_without_record_is_rebuilt(tmp_path):
    """A library under the predictable name of g = x**2 that computes x**3 (an attacker's
    file, no sha256 record of ours) is not loaded: g is rebuilt and computes x**2."""
    cache, other = tmp_path / "cache", tmp_path / "other"
    assert compile_in_new_process(other, 3) == (8.0, 1)
    cache.mkdir(mode=0o700)
    shutil.copy(library_of(other, 3), library_of(cache, 2))
    assert compile_in_new_process(cache, 2) == (4.0, 1)
    assert compile_in_new_process(cache, 2) == (4.0, 0)       # now ours: loaded


def test_library_altered_after_the_build_is_rebuilt(tmp_path):
    """The record of g = x**2 kept, its bytes replaced by those of x**3: rebuilt."""
    cache, other = tmp_path / "cache", tmp_path / "other"
    assert compile_in_new_process(cache, 2) == (4.0, 1)
    compile_in_new_process(other, 3)
    target = library_of(cache, 2)
    target.write_bytes(library_of(other, 3).read_bytes())
    assert compile_in_new_process(cache, 2) == (4.0, 1)


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX permissions")
@pytest.mark.parametrize("what", ["directory", "library"])
def test_cache_writable_by_others_is_refused(tmp_path, what):
    """A cache directory or library that group or others may write is not loaded from:
    RuntimeError naming the path; ``compiled_or_none`` warns and returns None."""
    cache = tmp_path / "cache"
    compile_in_new_process(cache, 2)
    path = cache if what == "directory" else library_of(cache, 2)
    path.chmod(0o777)
    x = ca.SX.sym("x")
    g = ca.Function("g", [x], [x ** 2])
    with pytest.raises(RuntimeError, match="refusing to load compiled code from .*writable"):
        compilation.compile_function(g, cache_dir=cache)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert compilation.compiled_or_none(g, cache_dir=cache) is None
    assert any("refusing" in str(w.message) for w in caught)


def test_new_cache_directory_is_private(tmp_path):
    cache = tmp_path / "new" / "cache"
    compile_in_new_process(cache, 2)
    assert cache.stat().st_mode & 0o777 == 0o700
    assert library_of(cache, 2).stat().st_mode & 0o022 == 0


def truncate(lib):
    with open(lib, "r+b") as f:
        f.truncate(lib.stat().st_size // 3)


def flip_a_byte(lib):
    data = bytearray(lib.read_bytes())
    data[len(data) // 2] ^= 0xFF
    with open(lib, "r+b") as f:          # in place: same file, same size
        f.write(data)


def delete_record(lib):
    lib.with_name(lib.name + ".json").unlink()


def garble_record(lib):
    lib.with_name(lib.name + ".json").write_text('{"size": 12')


@pytest.mark.parametrize("damage, reason", [
    (truncate, "bytes, its record"), (flip_a_byte, "sha256 differs"),
    (delete_record, "no record"), (garble_record, "record is unreadable")],
    ids=["truncated", "byte-flipped", "record-deleted", "record-garbled"])
def test_damaged_entry_is_rebuilt_with_a_warning(tmp_path, damage, reason):
    """A damaged library or record: the next process rebuilds the library (warning that
    names it and why), never loads the damaged one, and the process after loads it."""
    cache = tmp_path / "cache"
    assert compile_in_new_process(cache, 2) == (4.0, 1)
    lib = library_of(cache, 2)
    damage(lib)
    out = run_script(cache, 2)
    assert out.stdout.split() == ["4.0", "1"]
    assert f"rebuilding the compiled library {lib}" in out.stderr and reason in out.stderr
    out = run_script(cache, 2)
    assert out.stdout.split() == ["4.0", "0"] and "Warning" not in out.stderr
    assert sorted(p.name for p in cache.iterdir()) == [lib.name, lib.name + ".json"]


def test_record_describes_its_library(tmp_path):
    cache = tmp_path / "cache"
    compile_in_new_process(cache, 2)
    lib = library_of(cache, 2)
    record = json.loads(lib.with_name(lib.name + ".json").read_text())
    assert record["size"] == lib.stat().st_size
    assert record["sha256"] == hashlib.sha256(lib.read_bytes()).hexdigest()
    assert record["key"].startswith(lib.stem.split("_")[-1]) and "-O1" in record["flags"]


@pytest.mark.parametrize("where", ["file", "under-a-file"])
def test_cache_path_that_is_a_file_falls_back_to_a_temporary_directory(tmp_path, where):
    """The cache path is a file (or below one): the function is compiled in a temporary
    directory of the process (one warning naming the path), the file is left alone and
    the temporary directory is removed at exit."""
    (tmp_path / "tmp").mkdir()
    blocker = tmp_path / "cache"
    blocker.write_text("not a directory")
    cache = blocker if where == "file" else blocker / "sub"
    out = run_script(cache, 2, env={"TMPDIR": str(tmp_path / "tmp")})
    assert out.stdout.split() == ["4.0", "1"]
    assert out.stderr.count(f"cannot use the compiled-code cache {cache}") == 1
    assert blocker.read_text() == "not a directory"
    assert list((tmp_path / "tmp").iterdir()) == []


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0,
                    reason="root ignores directory permissions")
def test_read_only_cache_loads_what_it_holds_and_compiles_the_rest_elsewhere(tmp_path):
    """A cache directory without write permission: its libraries that match their
    records are loaded; a missing one is compiled in a temporary directory (one warning)."""
    (tmp_path / "tmp").mkdir()
    cache = tmp_path / "cache"
    compile_in_new_process(cache, 2)
    cache.chmod(0o500)
    try:
        assert compile_in_new_process(cache, 2) == (4.0, 0)
        out = run_script(cache, 3, env={"TMPDIR": str(tmp_path / "tmp")})
        assert out.stdout.split() == ["8.0", "1"]
        assert f"cannot use the compiled-code cache {cache}" in out.stderr
        assert not library_of(cache, 3).exists()
    finally:
        cache.chmod(0o700)


def test_fallback_warns_once_per_cache_directory(tmp_path, monkeypatch):
    """Several functions and repeated calls in one process: one warning, one build each."""
    monkeypatch.setattr(compilation, "_SCRATCH", {})
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    blocker = tmp_path / "cache"
    blocker.touch()
    x = ca.SX.sym("x")
    before = compilation.compile_count
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(2):
            for k in (2, 3):
                g = compilation.compile_function(ca.Function(f"h{k}", [x], [x ** k]),
                                                 cache_dir=blocker)
                assert float(g(2.0)) == 2.0 ** k
    assert [str(w.message).split(" (")[0] for w in caught] == \
        [f"cannot use the compiled-code cache {blocker}"]
    assert compilation.compile_count == before + 2


#: Waits for ``go`` to exist, then compiles g(x) = x**k for k = 2..6 into ``cache``.
RACE = textwrap.dedent("""
    import os, sys, time
    import casadi as ca
    from continuation import compilation
    cache, go = sys.argv[1], sys.argv[2]
    while not os.path.exists(go):
        time.sleep(0.005)
    x = ca.SX.sym("x")
    for k in range(2, 7):
        g = compilation.compile_function(ca.Function(f"g{k}", [x], [x ** k + ca.sin(x)]),
                                         cache_dir=cache)
        assert abs(float(g(2.0)) - (2.0 ** k + 0.9092974268256817)) < 1e-12
""")


def test_processes_building_the_same_entries_at_once(tmp_path):
    """Two processes released together compile the same five functions: both succeed
    without a warning, and the cache holds each library once with a matching record."""
    cache, go = tmp_path / "cache", tmp_path / "go"
    procs = [subprocess.Popen([sys.executable, "-c", RACE, str(cache), str(go)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    go.touch()
    for proc in procs:
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 0 and "Warning" not in err, err
    libraries = sorted(cache.glob("*.so"))
    assert len(libraries) == 5
    assert sorted(p.name for p in cache.iterdir()) == \
        sorted([p.name for p in libraries] + [p.name + ".json" for p in libraries])
    for lib in libraries:
        record = json.loads(lib.with_name(lib.name + ".json").read_text())
        assert record["sha256"] == hashlib.sha256(lib.read_bytes()).hexdigest()


def _can_mount_read_only() -> bool:
    """Whether this process may bind-mount read-only in a private mount namespace."""
    if not shutil.which("unshare") or os.geteuid() != 0:
        return False
    probe = subprocess.run(["unshare", "-m", "sh", "-c", "mount --bind -o ro / / 2>/dev/null"],
                           capture_output=True)
    return probe.returncode == 0


@pytest.mark.skipif(not hasattr(os, "geteuid") or not _can_mount_read_only(),
                    reason="needs root and mount namespaces (unshare -m)")
def test_cache_on_a_read_only_file_system(tmp_path):
    """The cache directory bind-mounted read-only (in a private mount namespace, so only
    the test's process sees it): a library it holds is loaded, a missing one is compiled
    in a temporary directory with one warning."""
    (tmp_path / "tmp").mkdir()
    cache = tmp_path / "cache"
    compile_in_new_process(cache, 2)
    script = (f"mount --bind -o ro {cache} {cache} && "
              f"{sys.executable} -c \"$SCRIPT\" {cache} 2 && "
              f"{sys.executable} -c \"$SCRIPT\" {cache} 3")
    out = subprocess.run(["unshare", "-m", "sh", "-c", script], capture_output=True,
                         text=True, env={**os.environ, "SCRIPT": SCRIPT,
                                         "TMPDIR": str(tmp_path / "tmp")})
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["4.0", "0", "8.0", "1"]
    assert out.stderr.count(f"cannot use the compiled-code cache {cache} (Read-only") == 1
    assert not library_of(cache, 3).exists()
