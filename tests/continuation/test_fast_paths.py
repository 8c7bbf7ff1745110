"""Fast paths of the CasADi layer and of a run against the plain routes (the linear
algebra's and Newton's: ``test_internals_linalg``, ``test_internals_newton``)."""

import casadi as ca
import numpy as np
import pytest

import continuation as C
from continuation import BufferedFunction

from .conftest import brusselator_cycles


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


def test_contraction_setting_is_validated():
    for bad in (-0.1, 1.0, float("nan")):
        with pytest.raises(ValueError, match="NewtonSettings.contraction"):
            C.NewtonSettings(contraction=bad)


def test_multipliers_from_the_kept_jacobian_equal_fresh_ones():
    """The multipliers from the Jacobian the tangent left at a point equal those of the
    same cycle on a new problem (same field, mesh and settings), which has none kept."""
    cyc, it = brusselator_cycles()
    X = it.advance(it.start()).X
    kept = cyc.multipliers(X)                          # Jacobian kept from the tangent
    new = C.CycleProblem(cyc.vf, lambda t: cyc.evaluate(X, t), cyc.period(X), cyc.par_dict(X),
                         cyc.free, settings=cyc.settings, mesh=cyc.mesh)
    fresh = new.multipliers(X)
    assert np.array_equal(kept, fresh)
    assert abs(kept[np.argmin(np.abs(kept - 1))] - 1) < 1e-8


def _mass_spring_field(with_jacobians: bool, scale: float = 1.0):
    """``M(x) xdot = F(x)``: two coupled Duffing-Van der Pol oscillators, M depending on x."""
    x, p, v = ca.MX.sym("x", 4), ca.MX.sym("p", 2), ca.MX.sym("v", 4)
    F = ca.vertcat(x[1], p[0] * (1 - x[0] ** 2) * x[1] - x[0] - p[1] * (x[0] - x[2]),
                   x[3], p[0] * (1 - x[2] ** 2) * x[3] - x[2] + p[1] * (x[0] - x[2]) - x[2] ** 3)
    M = ca.diag(ca.vertcat(1, 1 + 0.1 * x[0] ** 2, 1, 1 + 0.2 * ca.sin(x[2])))
    Mv = ca.mtimes(M, v)
    fun = lambda name, args, out: ca.Function(name, args, [out])
    extra = dict(jacobian=fun("J", [x, p], scale * ca.jacobian(F, x)),
                 mass_action_jacobian=fun("Mvx", [x, p, v], scale * ca.jacobian(Mv, x))) \
        if with_jacobians else {}
    return C.VectorField(fun("F", [x, p], F), fun("M", [x, p], M), ("mu", "k"), expand=False,
                         mass_action=fun("Mv", [x, p, v], Mv), **extra)


def test_supplied_jacobians_are_what_the_collocation_kernel_and_jac_x_use():
    """A VectorField given ``jacobian`` and ``mass_action_jacobian`` evaluates them (here a
    deliberately wrong pair changes the result) and, when they are right, give the same
    dF/dx and collocation Jacobian as AD of F and M v."""
    plain, given, wrong = _mass_spring_field(False), _mass_spring_field(True), \
        _mass_spring_field(True, scale=2.0)
    rng = np.random.default_rng(2)
    x, p = rng.normal(size=4), np.array([0.7, 0.3])
    assert np.allclose(given.jac_x(x, p).toarray(), plain.jac_x(x, p).toarray(), rtol=0, atol=1e-15)
    orbit = rng.normal(size=(8, 4))
    X = np.concatenate([rng.normal(size=4 * 5 * 3 + 1), [0.7]])
    J = [C.CycleProblem(vf, orbit, 6.0, {"mu": 0.7, "k": 0.3}, "mu",
                        settings=C.CollocationSettings(ntst=5, ncol=3, backend="mx")).jacobian(X)
         for vf in (plain, given, wrong)]
    assert abs(J[0] - J[1]).max() <= 1e-14 * abs(J[0]).max()
    assert abs(J[0] - J[2]).max() > 0.1 * abs(J[0]).max()
    assert np.allclose(wrong.jac_x(x, p).toarray(), 2 * plain.jac_x(x, p).toarray())


def test_supplied_jacobians_of_the_wrong_shape_are_refused():
    x, p, v = ca.MX.sym("x", 2), ca.MX.sym("p", 1), ca.MX.sym("v", 2)
    F = ca.Function("F", [x, p], [ca.vertcat(x[1], -p * x[0])])
    with pytest.raises(ValueError, match="jacobian must map x"):
        C.VectorField(F, None, ("k",), jacobian=ca.Function("J", [x, p], [x]))
    with pytest.raises(ValueError, match="needs mass_action"):
        C.VectorField(F, None, ("k",),
                      mass_action_jacobian=ca.Function("J", [x, p, v], [ca.MX(2, 2)]))


def test_a_run_uses_one_blas_thread_and_restores_the_callers_pools():
    """Inside ``continuation`` the BLAS pools have one thread; afterwards they are as the
    caller left them (no lasting effect on the session)."""
    from threadpoolctl import threadpool_info, threadpool_limits
    x, p = ca.SX.sym("x"), ca.SX.sym("p")
    F = ca.Function("F", [x, p], [p * ca.exp(x) - x])
    inside = []
    record = lambda problem, X: inside.append(
        [pool["num_threads"] for pool in threadpool_info()]) or {}
    with threadpool_limits(2):
        before = [pool["num_threads"] for pool in threadpool_info()]
        C.continuation(C.EquilibriumProblem(F, [0.0], {"mu": 0.0}, "mu"),
                       settings=C.ContinuationSettings(max_steps=3), record=record)
        after = [pool["num_threads"] for pool in threadpool_info()]
    assert inside and all(all(n == 1 for n in counts) for counts in inside)
    assert after == before
