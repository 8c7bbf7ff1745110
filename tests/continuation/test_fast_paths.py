"""Fast paths of the linear algebra and CasADi layers against the plain routes."""

import casadi as ca
import numpy as np
import pytest
import scipy.sparse as sp

from continuation._casadi.symbolic import BufferedFunction


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

    from continuation._driver.newton import factorize
    from continuation._driver.problem import _det_sign

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


def _random_system(seed, n=200):
    import scipy.sparse as sp
    rng = np.random.default_rng(seed)
    A = (sp.random(n, n, density=0.03, random_state=seed) + 2.0 * sp.identity(n)).tocsc()
    return A, rng.standard_normal(n)


def _cubic_system(n=30, seed=5):
    """``H(x) = A x + x^3 / 10 - b`` with the root ``x*`` built in, its Jacobian sparse."""
    A, _ = _random_system(seed, n)
    x_star = np.random.default_rng(seed + 1).standard_normal(n)
    b = A @ x_star + 0.1 * x_star ** 3
    H = lambda x: A @ x + 0.1 * x ** 3 - b                              # noqa: E731
    J = lambda x: (A + sp.diags(0.3 * x ** 2)).tocsc()                   # noqa: E731
    return H, J, x_star


@pytest.mark.parametrize("start", [1e-3, 1.0])
def test_chord_steps_reach_the_root_as_accurately_as_newton(start):
    """Near the root (1e-3) the first step's factors serve all later steps (one
    Jacobian); far from it (1.0) the steps are Newton's until one contracts by 1e-3,
    then chord steps. Either way the root the system was built from is met to
    round-off, as by Newton's method (contraction 0), with no more Jacobians; for step
    control the run of chord steps counts as one Newton iteration (``effort``)."""
    from continuation._driver.newton import newton
    from continuation._driver.settings import NewtonSettings

    H, J, x_star = _cubic_system()
    x0 = x_star + start * np.random.default_rng(7).standard_normal(x_star.size)
    chord = newton(H, J, x0, NewtonSettings(tol=1e-10))
    plain = newton(H, J, x0, NewtonSettings(tol=1e-10, contraction=0.0))
    assert chord.converged and plain.converged
    assert plain.jacobians == plain.iterations == plain.effort
    scale = np.max(np.abs(x_star))
    for res in (chord, plain):
        assert np.max(np.abs(res.X - x_star)) < 1e-13 * scale
    assert chord.jacobians < plain.jacobians and chord.iterations <= plain.iterations + 1
    assert chord.effort == chord.jacobians + 1            # the chord run counts once
    if start < 0.01:
        assert chord.jacobians == 1 < chord.iterations


def test_contraction_setting_is_validated():
    from continuation._driver.settings import NewtonSettings
    for bad in (-0.1, 1.0, float("nan")):
        with pytest.raises(ValueError, match="NewtonSettings.contraction"):
            NewtonSettings(contraction=bad)


def _brusselator_cycles():
    import continuation as C
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    F = ca.Function("F", [x, p], [ca.vertcat(p[0] - (p[1] + 1) * x[0] + x[0] ** 2 * x[1],
                                             p[1] * x[0] - x[0] ** 2 * x[1])])
    eq = C.EquilibriumProblem(F, [1, 2.5], {"A": 1.0, "B": 2.5}, "B")
    (hopf,) = C.continuation(eq, settings=C.ContinuationSettings(
        ds=0.05, bounds={"B": (1.5, 2.5)}, direction=-1)).special("hopf")
    cyc = C.cycle_from_hopf(eq, hopf, dp=1e-2, settings=C.CollocationSettings(ntst=20, ncol=4))
    it = C.ContinuationIterator(cyc, C.PALC(), C.ContinuationSettings(
        ds=0.1, max_steps=4, direction=cyc.hopf_direction))
    return cyc, it


def test_cycle_step_factorizes_at_the_predictor_and_for_the_tangent(monkeypatch):
    """On a smooth cycle branch a step costs two factorizations: the corrector's at the
    predictor (the next Newton iterations are chord steps on it) and the tangent's at
    the new point, whose factors are those of ``[G_X(X); tau_k^T]`` there (checked by
    solving with the matrix assembled independently, sparse) and give ``G_X tau = 0``."""
    import continuation._driver.newton as newton_module
    import continuation._driver.palc as palc_module
    from continuation._driver.problem import Problem

    cyc, it = _brusselator_cycles()
    step = it.start()
    calls = []
    fresh_factors = newton_module.factorize
    for module in (newton_module, palc_module):
        monkeypatch.setattr(module, "factorize", lambda A: calls.append(1) or fresh_factors(A))
    for k in range(4):
        D = cyc.system.D.copy()                        # phase reference of the step
        calls.clear()
        new = it.advance(step)
        assert len(calls) == 2 and new.iterations >= 2    # chord steps in the corrector
        D_new, cyc.system.D = cyc.system.D, D
        A = Problem.bordered_jacobian(cyc, new.X, step.tau)          # sparse, assembled
        v = np.random.default_rng(k).standard_normal(new.X.size)
        assert np.max(np.abs(new.lu.solve(A @ v) - v)) < 1e-10 * np.max(np.abs(v))
        assert np.max(np.abs(cyc.jacobian(new.X) @ new.tau)) < 1e-12
        cyc.system.D, step = D_new, new


def test_multipliers_from_the_kept_jacobian_equal_fresh_ones():
    cyc, it = _brusselator_cycles()
    X = it.advance(it.start()).X
    kept = cyc.multipliers(X)                          # Jacobian kept from the tangent
    cyc._last_jacobian = None
    fresh = cyc.multipliers(X)
    assert np.array_equal(kept, fresh)
    assert abs(kept[np.argmin(np.abs(kept - 1))] - 1) < 1e-8


def _mass_spring_field(with_jacobians: bool, scale: float = 1.0):
    """``M(x) xdot = F(x)``: two coupled Duffing-Van der Pol oscillators, M depending on x."""
    import continuation as C
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
    from continuation._cycles.blocks import BlockCollocationSystem, point_kernel
    plain, given, wrong = _mass_spring_field(False), _mass_spring_field(True), \
        _mass_spring_field(True, scale=2.0)
    rng = np.random.default_rng(2)
    x, p = rng.normal(size=4), np.array([0.7, 0.3])
    assert np.allclose(given.jac_x(x, p).toarray(), plain.jac_x(x, p).toarray(), rtol=0, atol=1e-15)
    ntst, ncol = 5, 3
    U = rng.normal(size=4 * ntst * ncol + 1)
    D = np.concatenate([np.full(ntst, 1 / ntst), rng.normal(size=4 * ntst * ncol)])
    J = [BlockCollocationSystem(point_kernel(vf, ntst * ncol), ntst, ncol).jacobian(U, p, D, [0])
         for vf in (plain, given, wrong)]
    assert abs(J[0] - J[1]).max() <= 1e-14 * abs(J[0]).max()
    assert abs(J[0] - J[2]).max() > 0.1 * abs(J[0]).max()
    assert np.allclose(wrong.jac_x(x, p).toarray(), 2 * plain.jac_x(x, p).toarray())


def test_supplied_jacobians_of_the_wrong_shape_are_refused():
    import continuation as C
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
    import continuation as C
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


def test_nested_single_threaded_contexts_limit_once_and_restore_once():
    """An inner ``single_threaded`` (a Floquet routine inside a run) leaves the outer
    limit in place on exit; the outer one restores the caller's pools."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from continuation._linalg.threads import single_threaded

    def counts():
        return [pool["num_threads"] for pool in threadpool_info()]
    with threadpool_limits(2):
        before = counts()
        with single_threaded():
            with single_threaded():
                assert all(n == 1 for n in counts())
            assert all(n == 1 for n in counts())
        assert counts() == before


def test_single_threaded_sets_no_limit_where_every_pool_has_one_thread(monkeypatch):
    """Pools at one thread already (``OPENBLAS_NUM_THREADS=1``): nothing is limited or
    restored (a limit costs more than a point's small eigenproblem); with two threads
    the limit is set."""
    from threadpoolctl import threadpool_limits

    from continuation._linalg import threads as _threads
    calls = []
    real = type(_threads._controller()).limit
    monkeypatch.setattr(type(_threads._controller()), "limit",
                        lambda self, **kw: calls.append(kw) or real(self, **kw))
    with threadpool_limits(1):
        with _threads.single_threaded():
            pass
    assert calls == []
    with threadpool_limits(2):
        with _threads.single_threaded():
            pass
    assert calls == [{"limits": 1}]
