"""White-box on purpose (the kernel of ``continuation._cycles.blocks`` and what it calls):
its batched lifted matrices against AD of the field; compiled collocation kernels
(``CollocationSettings(backend='compiled')``) against the CasADi virtual machine ('mx'):
residuals, Jacobians and Floquet multipliers agree to 1e-12 relative; the on-disk cache,
the environment switch and the fallback without a compiler."""

import os
import pathlib
import subprocess
import sys
import textwrap

import casadi as ca
import numpy as np
import pytest

import continuation as C
from continuation import compilation
from continuation._casadi.lifted import LiftedBatch

from .conftest import galerkin

RTOL = 1e-12

needs_compiler = pytest.mark.skipif(not compilation.has_compiler(),
                                    reason="no C compiler found (gcc, cc, clang or $CC)")


def _rel(a, b) -> float:
    """max |a - b| / max |a|."""
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))


def _mx_field(models):
    """The two-parameter mass model kept MX (``expand=False``)."""
    F, M = models.mass_model(with_q=True)
    x, p = ca.MX.sym("x", 2), ca.MX.sym("p", 2)
    Fm, Mm = ca.Function("F", [x, p], [F(x, p)]), ca.Function("M", [x, p], [M(x, p)])
    return C.VectorField(Fm, Mm, ("p", "q"), expand=False)


def _mx_van_der_pol(models):
    """Van der Pol kept MX."""
    F = models.van_der_pol()
    x, p = ca.MX.sym("x", 2), ca.MX.sym("p", 1)
    return C.VectorField(ca.Function("F", [x, p], [F(x, p)]), None, ("mu",), expand=False)


def _cases(models):
    """``name -> (F, M, params, active, guess, period)``."""
    F_m, M_m = models.mass_model(with_q=True)
    ring = lambda t: 1.0 + 0.3 * models.van_der_pol_guess(t)
    return {
        "van_der_pol": (models.van_der_pol(), None, {"mu": 1.0}, "mu",
                        models.van_der_pol_guess, 6.6),
        "brusselator": (models.brusselator(), None, {"A": 1.0, "B": 3.0}, "B",
                        lambda t: np.array([1.0, 3.0]) + 0.5 * models.van_der_pol_guess(t),
                        7.0),
        "van_der_pol_mx": (_mx_van_der_pol(models), None, {"mu": 1.0}, "mu",
                           models.van_der_pol_guess, 6.6),
        "mass_model": (F_m, M_m, {"p": 0.6, "q": 1.0}, "q", ring, 12.0),
        "mass_model_mx": (_mx_field(models), None, {"p": 0.6, "q": 1.0}, "p", ring, 12.0),
    }


def _problem(case, backend, ntst=7, ncol=3):
    F, M, params, active, guess, period = case
    settings = C.CollocationSettings(ntst=ntst, ncol=ncol, backend=backend)
    return C.CycleProblem(F, guess, period, params, active, M=M, settings=settings)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CONTINUATION_CACHE", str(tmp_path))
    return tmp_path


@needs_compiler
@pytest.mark.parametrize("name", ["van_der_pol", "brusselator", "mass_model",
                                  "mass_model_mx", "van_der_pol_mx"])
def test_compiled_kernel_equals_mx(models, cache, name):
    case = _cases(models)[name]
    mx, fast = _problem(case, "mx"), _problem(case, "compiled")
    assert fast.system.compiled.kernel.backend == "compiled"
    assert mx.system.compiled.kernel.backend == "mx"
    X = mx.X0 + 0.05 * np.random.default_rng(0).standard_normal(mx.X0.size)
    fast.system.D = mx.system.D.copy()
    assert _rel(mx.residual(X), fast.residual(X)) < RTOL
    Y, p, D = X[:-1], mx.params(X), mx.system.D
    for cols in [(0,), (1,), (1, 0), ()]:
        if max(cols, default=0) < len(p):
            Jm = mx.system.compiled.jacobian(Y, p, D, cols).toarray()
            Jc = fast.system.compiled.jacobian(Y, p, D, cols).toarray()
            assert _rel(Jm, Jc) < RTOL
    assert list(cache.glob("*.so"))


@needs_compiler
@pytest.mark.parametrize("name", ["van_der_pol", "van_der_pol_mx"])
def test_compiled_multipliers_equal_mx(models, cache, name):
    case = _cases(models)[name]
    mx, fast = _problem(case, "mx", ntst=12, ncol=4), _problem(case, "compiled", ntst=12, ncol=4)
    X = models.corrected(mx)
    fast.system.D = mx.system.D.copy()
    mu_m, mu_c = mx.multipliers(X), fast.multipliers(X)
    assert np.max(np.abs(mu_m - mu_c)) < RTOL * max(1.0, np.max(np.abs(mu_m)))


@needs_compiler
def test_kernel_library_is_shared_by_meshes_and_processes(models, cache):
    """An MX field's point functions are compiled once and serve every number of points;
    an SX field's map is compiled whole, once per number of points ``K``; a new process
    loads what is cached and compiles nothing."""
    def problem(name, ntst, ncol):
        pr = _problem(_cases(models)[name], "compiled", ntst=ntst, ncol=ncol)
        pr.jacobian(pr.X0)
        return pr
    problem("van_der_pol_mx", 6, 4)
    before = compilation.compile_count
    problem("van_der_pol_mx", 9, 3)                 # another K: the same libraries
    assert compilation.compile_count == before
    problem("van_der_pol", 6, 4)
    before = compilation.compile_count
    problem("van_der_pol", 8, 3)                    # K = 24 again: the same libraries
    assert compilation.compile_count == before
    problem("van_der_pol", 5, 4)                    # K = 20: its own map (values, Jacobians)
    assert compilation.compile_count == before + 2
    libraries = {p: p.stat().st_mtime_ns for p in cache.glob("*.so")}
    script = textwrap.dedent(f"""
        import sys; sys.path.insert(0, {str(pathlib.Path(__file__).parent)!r})
        import conftest, continuation as C
        from continuation import compilation
        pr = C.CycleProblem(conftest.van_der_pol(), conftest.van_der_pol_guess, 6.6,
                            {{"mu": 1.0}}, "mu", settings=C.CollocationSettings(ntst=5))
        pr.jacobian(pr.X0)
        print(compilation.compile_count, pr.system.compiled.kernel.backend)
    """)
    env = {"CONTINUATION_CACHE": str(cache), "CONTINUATION_BACKEND": "compiled"}
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True, env={**os.environ, **env})
    assert out.stdout.split() == ["0", "compiled"]
    assert {p: p.stat().st_mtime_ns for p in cache.glob("*.so")} == libraries
    assert sorted(p.name for p in cache.iterdir() if p.suffix != ".so") == \
        sorted(p.name + ".json" for p in libraries)        # their records, no build dirs


def test_missing_compiler_falls_back_to_mx(models, cache, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-continuation")
    prob = _problem(_cases(models)["van_der_pol"], "compiled", ntst=5, ncol=2)
    assert prob.system.compiled.kernel.backend == "mx"
    assert np.all(np.isfinite(prob.jacobian(prob.X0).data))
    assert not list(cache.glob("*.so"))


def test_backend_setting_and_environment_are_validated(monkeypatch):
    with pytest.raises(ValueError, match="CollocationSettings.backend"):
        C.CollocationSettings(backend="jit")
    from continuation._cycles.settings import kernel_backend
    monkeypatch.delenv("CONTINUATION_BACKEND", raising=False)
    assert kernel_backend(None) == "auto"
    monkeypatch.setenv("CONTINUATION_BACKEND", "compiled")
    assert kernel_backend(None) == "compiled" and kernel_backend("mx") == "mx"
    monkeypatch.setenv("CONTINUATION_BACKEND", "fast")
    with pytest.raises(ValueError, match="CONTINUATION_BACKEND"):
        kernel_backend(None)


def test_cache_dir_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("CONTINUATION_CACHE", str(tmp_path / "c"))
    assert compilation.default_cache_dir() == tmp_path / "c"
    monkeypatch.delenv("CONTINUATION_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert compilation.default_cache_dir() == tmp_path / "xdg" / "continuation"


def test_auto_backend_compiles_mx_and_small_sx_fields(cache):
    """'auto' (the default) compiles the kernel of an MX field and of a small SX field,
    and keeps an SX field of more than ``SX_COMPILE_MAX`` instructions in the virtual
    machine."""
    from continuation._cycles.blocks import SX_COMPILE_MAX, point_kernel
    x, p = ca.MX.sym("x", 2), ca.MX.sym("p", 1)
    F = ca.Function("F", [x, p], [ca.vertcat(x[1], p * (1 - x[0] ** 2) * x[1] - x[0])])
    kinds = {expand: point_kernel(C.VectorField(F, None, ("mu",), expand=expand), 6, "auto")
             for expand in (False, True)}
    xs, ps = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    terms = sum(ca.sin(xs[0] + k * ps) for k in range(SX_COMPILE_MAX))
    large = ca.Function("G", [xs, ps], [ca.vertcat(xs[1], terms - xs[0])])
    kinds["large"] = point_kernel(C.VectorField(large, None, ("mu",)), 6, "auto")
    compiled = "compiled" if compilation.has_compiler() else "mx"
    assert kinds[False].backend == kinds[True].backend == compiled
    assert kinds["large"].backend == "mx"


def _kernel_functions(problem) -> list:
    """The BufferedFunctions of a problem's kernel: values, Jacobians, lifted matrices."""
    kernel = problem.system.compiled.kernel
    return [kernel.values, *kernel._jacobians.values(),
            *(batch._D for batch in kernel.lifted.values())]


def _compiled(buffered) -> bool:
    """Whether a BufferedFunction calls a compiled library (itself or mapped)."""
    fun = buffered.fun
    return fun.is_a("External") or any(f.is_a("External") for f in fun.find_functions())


@needs_compiler
@pytest.mark.parametrize("name", ["mass_model_mx", "van_der_pol"])
def test_background_compilation_switches_mid_run_to_equal_results(models, cache, name,
                                                                  monkeypatch):
    """'auto' evaluates in the virtual machine while the compiler runs beside it and
    switches to the library once it is built: every evaluation on the way equals the
    virtual machine's."""
    from continuation._cycles import blocks
    monkeypatch.setattr(blocks, "COMPILE_AFTER", 0.0)        # worth a build at once
    case = _cases(models)[name]
    mx, auto = _problem(case, "mx"), _problem(case, "auto")
    auto.system.D = mx.system.D.copy()
    X = mx.X0 + 0.05 * np.random.default_rng(0).standard_normal(mx.X0.size)
    Y, p, D = X[:-1], mx.params(X), mx.system.D
    Jm = mx.system.compiled.jacobian(Y, p, D, (0,)).toarray()
    switched = False
    for _ in range(2000):
        assert _rel(mx.residual(X), auto.residual(X)) < RTOL
        assert _rel(Jm, auto.system.compiled.jacobian(Y, p, D, (0,)).toarray()) < RTOL
        switched = all(f.later is None for f in _kernel_functions(auto))
        if switched:
            break
    assert switched and all(map(_compiled, _kernel_functions(auto)))
    assert list(cache.glob("*.so"))


@needs_compiler
def test_auto_compiles_only_what_pays_and_loads_what_is_cached(models, cache):
    """'auto' compiles nothing for a few evaluations (less than ``COMPILE_AFTER``
    seconds); once 'compiled' has built the libraries, 'auto' calls them from the
    first evaluation."""
    case = _cases(models)["mass_model_mx"]
    before = compilation.compile_count
    auto = _problem(case, "auto")
    auto.residual(auto.X0), auto.jacobian(auto.X0)
    assert compilation.compile_count == before and not list(cache.glob("*.so"))
    assert not list(cache.glob(".build-*"))          # nothing started, nothing left
    assert not any(map(_compiled, _kernel_functions(auto)))
    _problem(case, "compiled").jacobian(auto.X0)
    assert compilation.compile_count > before
    compilation._REQUESTS.clear()          # as a new process: what is cached is loaded
    again = _problem(case, "auto")
    again.residual(again.X0), again.jacobian(again.X0)
    assert all(map(_compiled, _kernel_functions(again)))


@needs_compiler
def test_failing_compiler_in_the_background_falls_back_with_a_warning(models, cache,
                                                                       monkeypatch, tmp_path):
    from continuation._cycles import blocks
    monkeypatch.setattr(blocks, "COMPILE_AFTER", 0.0)
    failing = tmp_path / "failing-cc"
    failing.write_text("#!/bin/sh\necho 'cc: internal error' >&2\nexit 1\n")
    failing.chmod(0o755)
    monkeypatch.setenv("CC", str(failing))
    case = _cases(models)["mass_model_mx"]
    mx, auto = _problem(case, "mx"), _problem(case, "auto")
    with pytest.warns(RuntimeWarning, match="(?s)falling back.*internal error"):
        for _ in range(200):
            auto.residual(auto.X0)
            if auto.system.compiled.kernel.backend == "mx":
                break
    assert auto.system.compiled.kernel.backend == "mx"
    assert _rel(mx.residual(mx.X0), auto.residual(auto.X0)) < RTOL
    assert not list(cache.glob("*.so")) and not list(cache.glob(".build-*"))


@needs_compiler
def test_a_build_left_running_at_exit_is_killed_and_leaves_nothing(tmp_path):
    """A process that ends while its background compiler runs kills the compiler and
    keeps nothing half-built."""
    slow = tmp_path / "slow-cc"
    slow.write_text(f"#!/bin/sh\n[ \"$1\" = --version ] && exec {compilation.find_compiler()} "
                    "--version\nexec sleep 60\n")        # a compiler that never ends
    slow.chmod(0o755)
    script = textwrap.dedent("""
        import casadi as ca
        from continuation import compilation
        x = ca.SX.sym("x")
        deferred = compilation.compile_later(ca.Function("g", [x], [x ** 3]))
        assert deferred.poll() is None
        print(deferred.build.proc.pid)
    """)
    cache = tmp_path / "cache"
    env = {**os.environ, "CONTINUATION_CACHE": str(cache), "CC": str(slow)}
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         env=env, timeout=50)
    assert out.returncode == 0, out.stderr
    assert not pathlib.Path(f"/proc/{int(out.stdout)}").exists()
    assert not list(cache.iterdir())


def test_lifted_batch_equals_ad_of_the_field_at_every_point():
    """The kernel's batched lifted matrices (``continuation._casadi.lifted.LiftedBatch``)
    equal AD of the field at every point."""
    s = galerkin()                            # the lifted field of test_lifted
    K = 7
    X, p = np.random.default_rng(1).normal(size=(K, s["n"])), np.array([0.7, 0.4])
    for lifted, ref in s["by_ad"]:
        batch = LiftedBatch(lifted, K)(X, p)
        for k in range(K):
            exact = np.array(ref(X[k], p))
            assert np.max(np.abs(batch[k] - exact)) < 1e-13 * np.max(np.abs(exact))
