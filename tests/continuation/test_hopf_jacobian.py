"""The Hopf system's structured Jacobian (hopf_system) against AD of its residual."""

import casadi as ca
import numpy as np
import pytest

from continuation._equilibria.systems import hopf_system
from continuation._equilibria.systems import ad_hopf_system
from continuation._casadi.vectorfield import VectorField

from .conftest import mass_model


def _mx(fun: ca.Function) -> ca.Function:
    x, p = ca.MX.sym("x", fun.size1_in(0)), ca.MX.sym("p", fun.size1_in(1))
    return ca.Function(fun.name(), [x, p], [fun(x, p)])


@pytest.mark.parametrize("symbolic", ["SX", "MX"])
def test_structured_hopf_jacobian_equals_ad_of_the_residual(symbolic):
    F, M = mass_model(with_q=True)
    if symbolic == "MX":
        F, M = _mx(F), _mx(M)
    vf = VectorField(F, M, ("p", "q"), expand=False)
    fast, ad = hopf_system(vf), ad_hopf_system(vf)
    rng = np.random.default_rng(3)
    for _ in range(5):
        Y, P, D = rng.standard_normal(7), rng.standard_normal(2), rng.standard_normal(2)
        assert np.array_equal(fast.residual(Y, P, D), ad.residual(Y, P, D))
        for free in ((0,), (1, 0)):
            a = fast.jacobian(Y, P, D, free).toarray()
            b = ad.jacobian(Y, P, D, free).toarray()
            assert np.allclose(a, b, rtol=1e-13, atol=1e-13 * np.abs(b).max())
