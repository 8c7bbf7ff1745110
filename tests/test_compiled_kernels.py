"""Compiled collocation kernels on the flutter model (N = 4, with and without contact):
residual, Jacobian and Floquet multipliers equal the CasADi ('mx') kernel to 1e-12."""

import numpy as np
import pytest

import continuation as C
from continuation import compilation
from fsicas import Scene, build_model
from fsicas.linear.hopf import critical_velocity, flutter_problem

pytestmark = pytest.mark.skipif(not compilation.has_compiler(),
                                reason="no C compiler found (gcc, cc, clang or $CC)")

RTOL = 1e-12
SCENES = {"straight": dict(modes=4),
          "contact": dict(modes=4, contact=True, contact_stiffness=1e8, contact_eps=1e-2,
                          contact_smoothing=0.1)}


def _rel(a, b) -> float:
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))


@pytest.fixture(scope="module", params=list(SCENES))
def pair(request, tmp_path_factory):
    """``(mx, compiled)`` cycle problems from the first Hopf point, on one field."""
    mp = pytest.MonkeyPatch()
    mp.setenv("CONTINUATION_CACHE", str(tmp_path_factory.mktemp("kernels")))
    scene = Scene(**SCENES[request.param])
    model = build_model(scene)
    hopf = critical_velocity(scene, model, ustar_max=20.0)
    eq = flutter_problem(scene, model, min(0.2, hopf.ustar / 2))
    make = lambda backend: C.cycle_from_hopf(eq, hopf.point, dp=1e-3, settings=C.CollocationSettings(
        ntst=8, ncol=4, floquet="product", backend=backend))
    yield make("mx"), make("compiled")
    mp.undo()


def test_kernel_backends(pair):
    mx, fast = pair
    assert mx.system.compiled.kernel.backend == "mx"
    assert fast.system.compiled.kernel.backend == "compiled"


def test_residual_and_jacobian_equal(pair):
    mx, fast = pair
    rng = np.random.default_rng(2)
    X = mx.X0 * (1 + 1e-3 * rng.standard_normal(mx.X0.size))
    fast.system.D = mx.system.D.copy()
    assert _rel(mx.residual(X), fast.residual(X)) < RTOL
    Y, p, D = X[:-1], mx.params(X), mx.system.D
    for cols in [(0,), (3,)]:                   # one library for any single column
        Jm = mx.system.compiled.jacobian(Y, p, D, cols).toarray()
        Jc = fast.system.compiled.jacobian(Y, p, D, cols).toarray()
        assert _rel(Jm, Jc) < RTOL


def test_multipliers_equal(pair):
    mx, fast = pair
    step = C.ContinuationIterator(mx, C.PALC(), C.ContinuationSettings()).start()
    assert step is not None
    fast.system.D = mx.system.D.copy()
    mu_m, mu_c = mx.multipliers(step.X), fast.multipliers(step.X)
    assert np.max(np.abs(mu_m - mu_c)) < RTOL * max(1.0, np.max(np.abs(mu_m)))
