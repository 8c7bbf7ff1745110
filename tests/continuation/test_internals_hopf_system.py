"""White-box on purpose: the Hopf system's structured Jacobian
(``continuation._equilibria.systems.hopf_system``) against CasADi AD of its residual
(``ad_hopf_system``), and that AD system against finite differences."""

import casadi as ca
import numpy as np
import pytest

import continuation as C
from continuation._casadi.symbolic import bound
from continuation._equilibria.systems import ad_hopf_system, hopf_system

from .conftest import mass_model


def _mx(fun: ca.Function) -> ca.Function:
    x, p = ca.MX.sym("x", fun.size1_in(0)), ca.MX.sym("p", fun.size1_in(1))
    return ca.Function(fun.name(), [x, p], [fun(x, p)])


@pytest.mark.parametrize("symbolic", ["SX", "MX"])
def test_structured_hopf_jacobian_equals_ad_of_the_residual(symbolic):
    F, M = mass_model(with_q=True)
    if symbolic == "MX":
        F, M = _mx(F), _mx(M)
    vf = C.VectorField(F, M, ("p", "q"), expand=False)
    fast, ad = hopf_system(vf), ad_hopf_system(vf)
    rng = np.random.default_rng(3)
    for _ in range(5):
        Y, P, D = rng.standard_normal(7), rng.standard_normal(2), rng.standard_normal(2)
        assert np.array_equal(fast.residual(Y, P, D), ad.residual(Y, P, D))
        for free in ((0,), (1, 0)):
            a = fast.jacobian(Y, P, D, free).toarray()
            b = ad.jacobian(Y, P, D, free).toarray()
            assert np.allclose(a, b, rtol=1e-13, atol=1e-13 * np.abs(b).max())


def test_ad_hopf_system_jacobian_matches_finite_differences(models):
    F, M = models.mass_model()
    vf = C.VectorField(F, M, ("p",))
    rng = np.random.default_rng(3)
    p = np.array([0.3])
    hopf = bound(vf, "hopf-ad", p, rng.standard_normal(2), ("p",), ad_hopf_system)
    X = rng.standard_normal(hopf.n_unknowns)
    assert hopf.n_unknowns == 3 * 2 + 2
    exact = hopf.jacobian(X).toarray()
    assert exact.shape == (8, 8)
    h = 1e-6
    fd = np.array([(hopf.residual(X + h * e) - hopf.residual(X - h * e)) / (2 * h)
                   for e in np.eye(X.size)]).T
    assert np.max(np.abs(exact - fd)) < 1e-7
