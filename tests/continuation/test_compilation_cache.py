"""The compiled-code cache loads only what it built: a planted or altered library is
rebuilt, a cache that others can write to is refused (``continuation.compilation``)."""

import os
import shutil
import subprocess
import sys
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


def compile_in_new_process(cache, power: int) -> tuple[float, int]:
    """(g(2), compilations) of :data:`SCRIPT`."""
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(cache), str(power)],
                         capture_output=True, text=True, check=True)
    value, count = out.stdout.split()
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
