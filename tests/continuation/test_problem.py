"""Exact CasADi Jacobians against finite differences; bad input raises ValueError."""

import casadi as ca
import numpy as np
import pytest

import continuation as C


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
    # the Hopf system, as a Hopf curve in (p, q) from its point p = 1/2, omega = 1/2 at q = 1
    curve = C.HopfCurveProblem(C.VectorField(*models.mass_model(with_q=True), ("p", "q")),
                               [1.0, 1.0], {"p": 0.5, "q": 1.0}, 0.5, ("p", "q"))
    X = curve.X0 + 0.1 * rng.standard_normal(curve.X0.size)
    assert X.size == 3 * 2 + 1 + 2
    exact = curve.jacobian(X).toarray()
    assert exact.shape == (8, 9)
    assert np.max(np.abs(exact - fd_jacobian(curve.residual, X))) < 1e-7
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


def test_system_that_cannot_be_evaluated_stops_the_branch_with_a_status():
    """A residual that raises LinAlgError beyond X = 2 (as an extended system's inner
    solve does away from its point): a continuation into that region shortens its steps
    up to the edge p = 1 and stops there with a status instead of raising (Newton's own
    report: ``test_internals_newton``)."""

    def residual(X):
        if X[0] > 2.0:
            raise np.linalg.LinAlgError("no root here")
        return np.array([X[0] ** 2 - 9.0])

    F = ca.Function("F", [x := ca.SX.sym("x"), p := ca.SX.sym("p")], [x - p])
    prob = C.EquilibriumProblem(F, [0.0], {"p": 0.0}, "p")
    plain = prob.residual
    prob.residual = lambda X: residual(X[-1:] + 1.0) if X[-1] > 1.0 else plain(X)
    branch = C.continuation(prob, settings=C.ContinuationSettings(ds=0.1, ds_max=0.5,
                                                                 max_steps=50))
    assert branch.status == "failed" and 0.999 < branch.par("p").max() <= 1.0
    assert "could not be evaluated" in branch.message
