"""Compiled C code (fsicas.model.codegen): agreement with CasADi, on-disk cache, errors."""
import subprocess
import sys
import tempfile
import textwrap

import casadi as ca
import numpy as np
import pytest

from continuation import compilation
from fsicas import Profile, Scene, build_model, steady_state
from fsicas.model import codegen
from fsicas.model.codegen import compile_function, compile_model

pytestmark = pytest.mark.skipif(
    not any(__import__("shutil").which(c) for c in ("gcc", "cc", "clang")),
    reason="no C compiler")

FUNCTIONS = ("mass", "rhs", "jac_rhs", "jac_rhs_p")


def rough_scene(**kw):
    """Asymmetric, converging/diverging channels, contact on with a wide gap."""
    return Scene(modes=4, hstar=0.1, ustar=4.0, zeta=(0.01, 0.02, 0.0, 0.05),
                 channel1=Profile.linear(0.06, 0.035), channel2=Profile.linear(0.04, 0.07),
                 contact=True, contact_stiffness=1e4, contact_eps=0.6, k0=0.3, **kw)


def random_states(model, count=5, seed=1):
    """States with small modal velocities, deflections of a few % of the gap, Q > 0."""
    rng = np.random.default_rng(seed)
    n = model.n_modes
    for _ in range(count):
        r = 0.02 * rng.standard_normal(n)
        q = 0.02 * rng.standard_normal(n) / np.arange(1, n + 1)
        Q = 0.25 * (1 + 0.2 * rng.random(2))
        yield np.concatenate([r, q, Q])


def assert_same(plain, compiled, x, p):
    a = np.array(plain(x, p))
    b = np.array(compiled(x, p))
    assert compiled.sparsity_out(0) == plain.sparsity_out(0)
    scale = np.max(np.abs(a))
    assert scale > 0
    np.testing.assert_allclose(b, a, rtol=1e-13, atol=1e-13 * scale)


@pytest.mark.parametrize("symbolic", ["SX", "MX"])
@pytest.mark.parametrize("make_scene", [lambda: Scene(modes=4), lambda: rough_scene(quad_nodes=12)],
                         ids=["straight", "asymmetric-contact"])   # 12 nodes: 36 cells of the
                                                                   # impact rule, not 84 (gcc's time)
def test_compiled_model_agrees_with_casadi(tmp_path, make_scene, symbolic):
    scene = make_scene()
    model = build_model(scene, symbolic)
    fast = compile_model(model, cache_dir=tmp_path)
    assert getattr(model, "rhs").is_a(f"{symbolic}Function")
    assert fast.scene == model.scene and fast.parameter_names == model.parameter_names
    p = model.parameters(scene, pressure_drop=1.7)
    for x in random_states(model):
        for name in FUNCTIONS:
            assert_same(getattr(model, name), getattr(fast, name), x, p)


def test_contact_is_active_in_the_rough_scene():
    """Guard against a vacuous agreement test: contact changes F at the test states."""
    on, off = build_model(rough_scene()), build_model(rough_scene().replace(contact=False))
    x = next(random_states(on))
    p_on = on.parameters(pressure_drop=1.7)
    p_off = off.parameters(pressure_drop=1.7)
    diff = np.array(on.rhs(x, p_on)) - np.array(off.rhs(x, p_off))
    assert np.max(np.abs(diff)) > 1e-6


def test_default_flags_follow_the_function_kind():
    scene = Scene(modes=2)
    assert codegen.default_flags(build_model(scene, "SX").rhs) == ("-O1",)
    assert codegen.default_flags(build_model(scene, "MX").rhs) == ("-O3",)


def test_second_call_hits_the_cache(tmp_path):
    fn = build_model(Scene(modes=4)).rhs
    start = codegen.compile_count
    compile_function(fn, cache_dir=tmp_path)
    assert codegen.compile_count == start + 1
    (lib,) = tmp_path.glob("*.so")
    mtime = lib.stat().st_mtime_ns
    # a rebuilt model of the same structure has the same key
    again = compile_function(build_model(Scene(modes=4, ustar=9.0)).rhs, cache_dir=tmp_path)
    assert codegen.compile_count == start + 1
    assert lib.stat().st_mtime_ns == mtime
    assert sorted(p.name for p in tmp_path.iterdir()) == [lib.name, lib.name + ".json"]
    x, p = np.linspace(0.01, 0.3, 10), build_model(Scene(modes=4)).parameters()
    np.testing.assert_array_equal(np.array(again(x, p)), np.array(fn(x, p)))


def test_cache_is_hit_by_a_new_process(tmp_path):
    compile_model(build_model(Scene(modes=3)), cache_dir=tmp_path)
    files = {p: p.stat().st_mtime_ns for p in tmp_path.glob("*.so")}
    assert len(files) == 4
    script = textwrap.dedent(f"""
        from fsicas import Scene, build_model
        from fsicas.model import codegen
        codegen.compile_model(build_model(Scene(modes=3)), cache_dir={str(tmp_path)!r})
        print(codegen.compile_count)
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "0"
    assert {p: p.stat().st_mtime_ns for p in tmp_path.glob("*.so")} == files


def test_env_var_sets_default_cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("FSICAS_CACHE", str(tmp_path / "env-cache"))
    assert codegen.default_cache_dir() == tmp_path / "env-cache"
    x = ca.SX.sym("x", 2)
    compile_function(ca.Function("tiny", [x], [ca.sin(x) * x[0]]))
    assert len(list((tmp_path / "env-cache").glob("tiny_*.so"))) == 1


def test_cache_path_that_is_a_file_still_compiles(tmp_path, monkeypatch):
    """``$FSICAS_CACHE`` names a file: the function is compiled in a temporary directory
    (a RuntimeWarning names the path) and the file is left alone."""
    monkeypatch.setattr(compilation, "_SCRATCH", {})
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setenv("FSICAS_CACHE", str(tmp_path / "cache"))
    (tmp_path / "cache").write_text("a file")
    x = ca.SX.sym("x")
    with pytest.warns(RuntimeWarning, match=f"cannot use the compiled-code cache "
                                            f"{tmp_path / 'cache'} .not a directory"):
        g = compile_function(ca.Function("tiny_file", [x], [x ** 2 + ca.sin(x)]))
    assert float(g(2.0)) == pytest.approx(4 + np.sin(2.0), rel=1e-15)
    assert (tmp_path / "cache").read_text() == "a file"


def test_different_structures_get_different_entries(tmp_path):
    for n in (2, 3, 4):
        compile_function(build_model(Scene(modes=n)).rhs, cache_dir=tmp_path)
    compile_function(build_model(Scene(modes=4, quad_nodes=30)).rhs, cache_dir=tmp_path)
    compile_function(build_model(Scene(modes=4)).rhs, cache_dir=tmp_path, flags=["-O1"])
    assert len(list(tmp_path.glob("F_*.so"))) == 5


def test_parallel_processes_share_one_entry(tmp_path):
    script = textwrap.dedent(f"""
        import numpy as np
        from fsicas import Scene, build_model
        from fsicas.model import codegen
        m = build_model(Scene(modes=5))
        f = codegen.compile_function(m.jac_rhs, cache_dir={str(tmp_path)!r})
        x = np.full(12, 0.2)
        assert np.array_equal(np.array(f(x, m.parameters())), np.array(m.jac_rhs(x, m.parameters())))
    """)
    procs = [subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.PIPE)
             for _ in range(3)]
    for proc in procs:
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 0, err.decode()
    assert len(list(tmp_path.glob("*.so"))) == 1
    assert len(list(tmp_path.iterdir())) == 2          # and its record; no build dirs left


def test_missing_compiler_raises_runtime_error(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-fsicas")
    x = ca.SX.sym("x")
    with pytest.raises(RuntimeError, match="no C compiler"):
        compile_function(ca.Function("g", [x], [x ** 2]), cache_dir=tmp_path)
    assert not list(tmp_path.glob("*.so"))


def test_failed_compilation_raises_and_leaves_no_entry(tmp_path):
    x = ca.SX.sym("x")
    with pytest.raises(RuntimeError, match="compiling g failed"):
        compile_function(ca.Function("g", [x], [x ** 2]), cache_dir=tmp_path,
                         flags=["--no-such-flag-fsicas"])
    assert list(tmp_path.iterdir()) == []


def test_derivatives_make_compiled_rhs_usable_in_steady_state(tmp_path):
    scene = Scene(modes=4, ustar=3.0, channel1=Profile.linear(0.05, 0.04),
                  channel2=Profile.linear(0.05, 0.06))
    model = build_model(scene)
    fast = compile_model(model, cache_dir=tmp_path, derivatives=True)
    ref = steady_state(scene, model)
    got = steady_state(scene, fast)
    np.testing.assert_allclose(got.x, ref.x, rtol=1e-10, atol=1e-12)
    assert got.pressure_drop == pytest.approx(ref.pressure_drop, rel=1e-10)
