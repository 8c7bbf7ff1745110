"""Fast paths of the linear algebra and CasADi layers against the plain routes."""

import casadi as ca
import numpy as np
import pytest

from continuation._symbolic import BufferedFunction


def test_buffered_function_equals_plain_call_and_returns_copies():
    x, d = ca.SX.sym("x", 3), ca.SX.sym("d", 0)
    fun = ca.Function("f", [x, d], [ca.sin(x) * x[0], ca.vertcat(x[1] ** 2, x[2])])
    buffered = BufferedFunction(fun)
    a, b = np.array([0.3, -1.2, 2.0]), np.array([1.0, 2.0, 3.0])
    first = buffered(a, np.zeros(0))
    second = buffered(b, np.zeros(0))
    for got, arg in ((first, a), (second, b)):
        plain = [np.asarray(v.full()).ravel() for v in fun(arg, ca.DM.zeros(0, 1))]
        assert all(np.array_equal(g, p) for g, p in zip(got, plain))


def test_buffered_function_raises_like_a_call():
    x = ca.MX.sym("x")
    integ = ca.integrator("I", "cvodes", {"x": x, "ode": x ** 2}, 0, 10.0)
    fun = ca.Function("g", [x], [integ(x0=x)["xf"]])
    with pytest.raises(RuntimeError):
        BufferedFunction(fun)(np.array([1.0]))


def test_factorization_with_reused_ordering_matches_a_fresh_splu():
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from continuation._newton import factorize
    from continuation._problem import _det_sign

    rng = np.random.default_rng(0)
    A = (sp.random(300, 300, density=0.02, random_state=1) + 0.5 * sp.identity(300)).tocsc()
    first = factorize(A)
    B = A.copy()
    B.data = rng.standard_normal(B.nnz)             # same pattern: ordering reused
    reused = factorize(B)
    assert not np.array_equal(reused.q, np.arange(300))
    b = rng.standard_normal(300)
    for lu, M in ((first, A), (reused, B)):
        fresh = spla.splu(M, permc_spec="MMD_AT_PLUS_A")
        for trans in ("N", "T"):
            x, x0 = lu.solve(b, trans=trans), fresh.solve(b, trans=trans)
            assert np.max(np.abs(x - x0)) < 1e-12 * np.max(np.abs(x0))
        assert _det_sign(lu) == np.sign(np.linalg.det(M.toarray()))
