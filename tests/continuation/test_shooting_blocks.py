"""The block-wise shooting Jacobian (per-segment sensitivities in the directions
(x_i, T, p_free)) against CasADi's Jacobian of the whole graph, finite differences
and known cycles; ``ShootingProblem.sample``."""

import casadi as ca
import numpy as np
import pytest

import continuation as C


def _pair(make):
    """The same shooting problem with jacobian='blocks' and 'graph' (1e-12 tolerances)."""
    return [make(C.ShootingSettings(segments=5, abstol=1e-12, reltol=1e-12, jacobian=j))
            for j in ("blocks", "graph")]


def _vdp(models):
    return lambda s: C.ShootingProblem(models.van_der_pol(), models.van_der_pol_guess, 6.6,
                                       {"mu": 1.0}, "mu", settings=s)


def _mass_circle(active):
    """F = (b (1 - r^2) x - y, b (1 - r^2) y + x), M = (a + x) I: the unit circle is a
    cycle for all b > 0, a > 1, of period int (a + cos) = 2 pi a."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    b, a = p[0], p[1]
    r2 = x[0] ** 2 + x[1] ** 2
    F = ca.Function("F", [x, p], [ca.vertcat(b * (1 - r2) * x[0] - x[1],
                                             b * (1 - r2) * x[1] + x[0])])
    M = ca.Function("M", [x, p], [(a + x[0]) * ca.SX.eye(2)])
    circle = lambda t: np.c_[np.cos(2 * np.pi * np.atleast_1d(t)),
                             np.sin(2 * np.pi * np.atleast_1d(t))]
    return lambda s: C.ShootingProblem(F, circle, 15.0, {"b": 0.7, "a": 2.5}, active, M=M,
                                       settings=s)


def _agree(blocks, graph, X):
    graph.accept(X)
    Jb, Jg = blocks.jacobian(X).toarray(), graph.jacobian(X).toarray()
    return np.max(np.abs(Jb - Jg)) / np.max(np.abs(Jg))


def _fd_error(problem, X, h=1e-4):
    """Max error of the Jacobian against central differences of the residual,
    relative to its largest entry (h = 1e-4 balances the h^2 truncation against the
    1e-12 integrator noise amplified by 1/h; measured errors about 1e-7)."""
    J = problem.jacobian(X).toarray()
    E = np.eye(X.size)
    fd = np.column_stack([(problem.residual(X + h * e) - problem.residual(X - h * e)) / (2 * h)
                          for e in E])
    return np.max(np.abs(J - fd)) / np.max(np.abs(J))


def test_van_der_pol_blocks_equal_graph_and_finite_differences(models):
    blocks, graph = _pair(_vdp(models))
    X = models.corrected(blocks)
    assert _agree(blocks, graph, X) < 1e-8
    assert _fd_error(blocks, X) < 1e-6
    mb, mg = blocks.multipliers(X), graph.multipliers(X)
    assert np.max(np.abs(mb - mg)) < 1e-8 and abs(mb[0] - 1) < 1e-9


@pytest.mark.parametrize("active", ["a", "b"])
def test_state_dependent_mass_two_parameters(active):
    """The free parameter enters through M ('a') or F ('b'); the other one is a
    non-differentiated input of the segment integrator."""
    blocks, graph = _pair(_mass_circle(active))
    step = C.ContinuationIterator(blocks, C.PALC(), C.ContinuationSettings()).start()
    X = step.X
    assert abs(blocks.period(X) - 2 * np.pi * 2.5) < 1e-9
    assert _agree(blocks, graph, X) < 1e-8
    assert _fd_error(blocks, X) < 1e-6
    mb, mg = blocks.multipliers(X), graph.multipliers(X)
    assert np.max(np.abs(mb - mg)) < 1e-8


def test_branches_by_both_jacobians_end_at_the_same_cycle(models):
    ends = []
    for problem in _pair(_vdp(models)):
        br = C.continuation(problem, settings=C.ContinuationSettings(ds=0.1, ds_max=0.3,
                                                                     max_steps=4))
        assert br.status == "max_steps"
        ends.append((br.par("mu")[-1], br.columns["period"][-1], br.n_unstable[-1]))
    (mu_b, T_b, u_b), (mu_g, T_g, u_g) = ends
    assert abs(T_b - T_g) < 1e-8 and abs(mu_b - mu_g) < 1e-8 and u_b == u_g


def test_multipliers_reuse_the_last_jacobian(models):
    blocks, graph = _pair(_vdp(models))
    X = models.corrected(blocks)
    first = blocks.blocks(X)
    blocks.multipliers(X)
    assert blocks.blocks(X) is first
    J = graph.jacobian(X)
    graph.multipliers(X)
    assert graph._last[1] is J


def test_sample_gives_the_cycle_at_k_points_per_segment():
    (problem, _) = _pair(_mass_circle("a"))
    X = C.ContinuationIterator(problem, C.PALC(), C.ContinuationSettings()).start().X
    t, x = problem.sample(X, 7)
    assert t.shape == (35,) and x.shape == (35, 2)
    assert np.all(np.diff(t) > 0) and t[0] == 0 and t[-1] < 1
    assert np.array_equal(x[::7], problem.points(X))
    assert np.max(np.abs(np.linalg.norm(x, axis=1) - 1)) < 1e-9
    with pytest.raises(ValueError, match="k must"):
        problem.sample(X, 0)


def test_jacobian_setting_is_validated():
    with pytest.raises(ValueError, match="jacobian"):
        C.ShootingSettings(jacobian="dense")
