"""Exact CasADi Jacobians against finite differences; bad input raises ValueError."""

import casadi as ca
import numpy as np
import pytest

import continuation as C
from continuation._casadi.symbolic import bound
from continuation._equilibria.systems import ad_hopf_system


def fd_jacobian(fun, X, h=1e-6):
    cols = []
    for i in range(X.size):
        e = np.zeros(X.size)
        e[i] = h
        cols.append((fun(X + e) - fun(X - e)) / (2 * h))
    return np.array(cols).T


def test_equilibrium_jacobian_matches_finite_differences(models):
    prob = C.EquilibriumProblem(models.brusselator(), [1.3, 2.1], {"A": 1.7, "B": 2.4}, "B")
    X = np.array([1.3, 2.1, 2.4])
    exact = prob.jacobian(X).toarray()
    assert exact.shape == (2, 3)
    assert np.max(np.abs(exact - fd_jacobian(prob.residual, X))) < 1e-8


def test_mass_and_hopf_system_jacobians(models):
    F, M = models.mass_model()
    vf = C.VectorField(F, M, ("p",))
    rng = np.random.default_rng(3)
    x, p = rng.standard_normal(2), np.array([0.3])
    assert np.max(np.abs(vf.jac_x(x, p).toarray() -
                         fd_jacobian(lambda y: vf.rhs(y, p), x))) < 1e-8
    hopf = bound(vf, "hopf", p, rng.standard_normal(2), ("p",), ad_hopf_system)
    X = rng.standard_normal(hopf.n_unknowns)
    assert hopf.n_unknowns == 3 * 2 + 2
    exact = hopf.jacobian(X).toarray()
    assert exact.shape == (8, 8)
    assert np.max(np.abs(exact - fd_jacobian(hopf.residual, X))) < 1e-7
    # mass matrix evaluated exactly
    assert np.allclose(vf.mass(x, p).toarray(),
                       [[1 + x[0] ** 2, x[1]], [0, 1 + x[1] ** 2]], atol=1e-15)


def test_multilinear_forms_match_finite_differences(models):
    F, M = models.mass_model()
    vf = C.VectorField(F, M, ("p",))
    rng = np.random.default_rng(4)
    x, p = rng.standard_normal(2), np.array([0.7])
    u, v = rng.standard_normal(2), rng.standard_normal(2)
    h = 1e-4
    fd = (vf.rhs(x + h * (u + v), p) - vf.rhs(x + h * (u - v), p)
          - vf.rhs(x - h * (u - v), p) + vf.rhs(x - h * (u + v), p)) / (4 * h * h)
    assert np.allclose(vf.form("F2", x, p, u, v).real, fd, atol=1e-6)
    y = rng.standard_normal(2)
    fdm = ((vf.mass(x + h * u, p) - vf.mass(x - h * u, p)) @ y) / (2 * h)
    assert np.allclose(vf.form("M1", x, p, u, y).real, fdm, atol=1e-7)
    z = u + 1j * v  # complex arguments by multilinearity
    assert np.allclose(vf.form("F2", x, p, z, z),
                       vf.form("F2", x, p, u, u) - vf.form("F2", x, p, v, v)
                       + 2j * vf.form("F2", x, p, u, v), atol=1e-13)


def test_mx_functions_are_accepted(models):
    x, p = ca.MX.sym("x", 2), ca.MX.sym("p", 2)
    F = ca.Function("F", [x, p], [models.brusselator()(x, p)])
    prob = C.EquilibriumProblem(F, [1.5, 1.0], {"A": 1.5, "B": 1.5}, "B")
    br = C.continuation(prob, settings=C.ContinuationSettings(max_steps=3))
    assert len(br) == 4 and br.status == "max_steps"


@pytest.mark.parametrize("kwargs, field", [
    (dict(ds=0.5, ds_max=0.1), "ds"),
    (dict(direction=0), "direction"),
    (dict(max_steps=0), "max_steps"),
    (dict(bounds={"mu": (1.0, 0.0)}), "bounds"),
    (dict(ds_min=-1.0), "ds_min"),
    (dict(step_shrink=1.5), "step_shrink"),
    (dict(max_turn=-0.1), "max_turn"),
    (dict(max_turn=4.0), "max_turn"),
])
def test_settings_validation(kwargs, field):
    with pytest.raises(ValueError, match=field):
        C.ContinuationSettings(**kwargs)


def test_small_settings_validation():
    with pytest.raises(ValueError, match="tol"):
        C.NewtonSettings(tol=-1)
    with pytest.raises(ValueError, match="nev"):
        C.EigenSettings(nev=0)
    with pytest.raises(ValueError, match="tangent"):
        C.PALC(tangent="chord")


def test_problem_validation(models):
    F = models.brusselator()
    with pytest.raises(ValueError, match="par_names"):
        C.VectorField(F, None, ("A",))
    with pytest.raises(ValueError, match="params"):
        C.EquilibriumProblem(F, [1, 1], {"A": 1.0}, "A")
    with pytest.raises(ValueError, match="unknown parameter 'C'"):
        C.EquilibriumProblem(F, [1, 1], {"A": 1.0, "B": 2.0}, "C")
    with pytest.raises(ValueError, match="x0"):
        C.EquilibriumProblem(F, [1, 1, 1], {"A": 1.0, "B": 2.0}, "A")
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    with pytest.raises(ValueError, match="M output"):
        C.EquilibriumProblem(F, [1, 1], {"A": 1.0, "B": 2.0}, "A",
                             M=ca.Function("M", [x, p], [ca.SX.eye(3)]))
    prob = C.EquilibriumProblem(F, [1, 1], {"A": 1.0, "B": 2.0}, "A")
    with pytest.raises(ValueError, match="bounds"):
        C.continuation(prob, settings=C.ContinuationSettings(bounds={"Z": (0, 1)}))
    with pytest.raises(ValueError, match="settings"):
        C.continuation(prob, settings={"ds": 0.1})


def test_caller_arrays_not_mutated(models):
    x0 = np.array([1.5, 1.0])
    prob = C.EquilibriumProblem(models.brusselator(), x0, {"A": 1.5, "B": 1.5}, "B")
    C.continuation(prob, settings=C.ContinuationSettings(max_steps=5))
    assert np.array_equal(x0, [1.5, 1.0])


def test_non_expandable_mx_function():
    # F contains a linear solve, so it stays an MX function: x0 = a, x1 = b a.
    x, p = ca.MX.sym("x", 2), ca.MX.sym("p", 2)
    A = ca.vertcat(ca.horzcat(2 + x[0] ** 2, 0.1), ca.horzcat(0.2, 3))
    F = ca.Function("F", [x, p], [ca.solve(A, ca.vertcat(p[0] - x[0], p[1] * x[0] - x[1]),
                                           "lapackqr")])
    prob = C.EquilibriumProblem(F, [0.4, 0.3], {"a": 0.5, "b": 1.0}, "a")
    assert prob.vf.sym is ca.MX
    br = C.continuation(prob, settings=C.ContinuationSettings(max_steps=5))
    a = br.par("a")
    assert br.status == "max_steps" and a[-1] > 0.55
    assert np.allclose(br.x, np.column_stack([a, a]), atol=1e-12)


def test_permutation_parity_matches_determinant():
    from itertools import permutations
    from continuation._driver.problem import _parity
    for n in range(1, 6):
        for perm in permutations(range(n)):
            assert _parity(perm) == round(np.linalg.det(np.eye(n)[list(perm)]))


def test_round_off_floor_handled_by_step_criterion():
    """A residual with a noise floor 1e-6 >> tol and a stiff Jacobian 1e12: the
    updates reach round-off level, which the xtol criterion accepts (and reports
    the true residual); with xtol = 0 the solve fails with its residual."""
    import scipy.sparse as sp
    from continuation._driver.newton import newton

    def residual(X):
        return 1e12 * (X - 0.3) + 1e-6 * np.cos(1e20 * X)

    def jacobian(X):
        return sp.csc_matrix([[1e12]])

    ok = newton(residual, jacobian, np.array([1.0]), C.NewtonSettings())
    assert ok.converged and ok.residual > 1e-10 and "round-off" in ok.message
    assert abs(ok.X[0] - 0.3) < 1e-15
    bad = newton(residual, jacobian, np.array([1.0]), C.NewtonSettings(xtol=0.0))
    assert not bad.converged and bad.residual > 1e-10
    assert f"{bad.residual:.3e}" in bad.message


def test_system_that_cannot_be_evaluated_is_a_failed_newton():
    """A residual that raises LinAlgError beyond X = 2 (as an extended system's inner
    solve does away from its point): Newton reports a failure naming it, and a
    continuation into that region shortens its steps up to the edge p = 1 and stops
    there with a status instead of raising."""
    import scipy.sparse as sp
    from continuation._driver.newton import newton

    def residual(X):
        if X[0] > 2.0:
            raise np.linalg.LinAlgError("no root here")
        return np.array([X[0] ** 2 - 9.0])

    bad = newton(residual, lambda X: sp.csc_matrix([[2 * X[0]]]), np.array([1.0]),
                 C.NewtonSettings())
    assert not bad.converged and "could not be evaluated: no root here" in bad.message
    F = ca.Function("F", [x := ca.SX.sym("x"), p := ca.SX.sym("p")], [x - p])
    prob = C.EquilibriumProblem(F, [0.0], {"p": 0.0}, "p")
    plain = prob.residual
    prob.residual = lambda X: residual(X[-1:] + 1.0) if X[-1] > 1.0 else plain(X)
    branch = C.continuation(prob, settings=C.ContinuationSettings(ds=0.1, ds_max=0.5,
                                                                 max_steps=50))
    assert branch.status == "failed" and 0.999 < branch.par("p").max() <= 1.0
    assert "could not be evaluated" in branch.message


def test_sparse_bordering_helpers_match_dense():
    import scipy.sparse as sp
    from continuation._linalg.sparse import append_columns, append_row
    rng = np.random.default_rng(0)
    for seed in range(20):
        m, n = rng.integers(1, 30), rng.integers(1, 30)
        A = sp.random(m, n, density=rng.uniform(0, 0.5), format="csc", random_state=seed)
        row = rng.standard_normal(n)
        cols = rng.standard_normal((m, 3))
        cols[rng.random((m, 3)) < 0.3] = 0.0
        assert np.array_equal(append_row(A, row).toarray(), np.vstack([A.toarray(), row]))
        assert np.array_equal(append_columns(A, cols).toarray(), np.hstack([A.toarray(), cols]))


def test_pattern_cache_matches_patterns_and_keys_and_keeps_the_newest():
    """A value is found again for the same pattern (any values) and key only; a
    pattern of equal nonzero count but other places, or another key, is a miss; the
    oldest entry goes when more than ``kept`` are stored."""
    import scipy.sparse as sp
    from continuation._linalg.sparse import PatternCache
    cache = PatternCache(kept=2)
    A = sp.csc_matrix(np.array([[1.0, 0.0], [2.0, 3.0]]))
    moved = sp.csc_matrix(np.array([[1.0, 4.0], [0.0, 3.0]]))
    assert A.nnz == moved.nnz
    assert cache.put(A, "a") == "a"
    assert cache.get(sp.csc_matrix(A * 7.0)) == "a"
    assert cache.get(moved) is None and cache.get(A, key=(1,)) is None
    cache.put(A, "a1", key=(1,))
    cache.put(moved, "m")
    assert cache.get(moved) == "m" and cache.get(A, key=(1,)) == "a1"
    assert cache.get(A) is None                          # the oldest of three, dropped


def test_solves_of_many_columns_equal_dense_lapack():
    """``LU.solve`` of many columns, on unsymmetric matrices that need row pivoting (a
    zero diagonal), at the first factorization of a pattern and on its kept ordering,
    equals LAPACK's dense solve and the column-by-column solve."""
    import scipy.sparse as sp
    from continuation._driver.newton import factorize
    rng = np.random.default_rng(3)
    for seed in range(6):
        m = int(rng.integers(5, 120))
        A = sp.random(m, m, density=0.1, random_state=seed) + sp.eye(m, k=1) + \
            sp.diags(rng.choice([0.0, 2.0], m))
        A = sp.csc_matrix(A)
        dense = A.toarray()
        if np.linalg.cond(dense) > 1e8:
            continue
        B = rng.standard_normal((m, 8 + seed))
        for lu in (factorize(A), factorize(A)):          # new pattern, kept ordering
            x = lu.solve(B)
            by_columns = np.column_stack([lu.solve(B[:, j]) for j in range(B.shape[1])])
            scale = np.abs(x).max()
            assert np.abs(x - np.linalg.solve(dense, B)).max() < 1e-11 * scale
            assert np.abs(x - by_columns).max() < 1e-12 * scale
