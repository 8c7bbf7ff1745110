"""Cycles with one more equation: located folds / period doublings and curves of
grazing cycles, cycle folds (LPC) and period doublings, on systems with closed forms."""

import casadi as ca
import numpy as np
import pytest

import continuation as C

SETTINGS = C.CollocationSettings(ntst=20, ncol=4)


def _shifted_hopf():
    """x' = b X - y - X r^2, y' = X + b y - y r^2 with X = x - c: the circle of radius
    sqrt(b) about (c, 0), period 2 pi. Its least x is c - sqrt(b): it grazes the wall
    x = 0 on the curve c = sqrt(b). p = (b, c)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    X, y = x[0] - p[1], x[1]
    r2 = X ** 2 + y ** 2
    return ca.Function("F", [x, p], [ca.vertcat(p[0] * X - y - X * r2, X + p[0] * y - y * r2)])


def _bautin():
    """r' = r (b1 + b2 r^2 - r^4), theta' = 1: cycles b1 = rho^2 - b2 rho (rho = r^2),
    folding (LPC) on b1 = -b2^2 / 4 at rho = b2 / 2. p = (b1, b2)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    r2 = x[0] ** 2 + x[1] ** 2
    g = p[0] + p[1] * r2 - r2 ** 2
    return ca.Function("F", [x, p], [ca.vertcat(g * x[0] - x[1], x[0] + g * x[1])])


def _bautin_ring(e=0.5):
    """The Bautin normal form with the angular speed 1 + e cos(theta): the same cycles
    and fold, period 2 pi / sqrt(1 - e^2), and a non-uniform flow along them that
    collocation discretizes with an error (the trivial multiplier is not exactly 1)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    r2 = x[0] ** 2 + x[1] ** 2
    g = p[0] + p[1] * r2 - r2 ** 2
    w = 1 + e * x[0] / ca.sqrt(r2)
    return ca.Function("F", [x, p], [ca.vertcat(g * x[0] - w * x[1], g * x[1] + w * x[0])])


def _torus(omega=0.3, a=0.7):
    """The unit circle r' = r (1 - r^2), theta' = 1 in (x1, x2) (period 2 pi) and a
    transverse plane y' = B(t) y, B = (rate + a x1 (1 + x2)) I + [[0, -omega + x2 / 5],
    [omega, 0]], rate = mu - nu^2. B's parts do not commute, yet by Liouville the
    transverse pair's product is exp(int tr B) = exp(4 pi rate): while complex, both lie
    on the circle |mu| = exp(2 pi rate), so a Neimark-Sacker on mu = nu^2."""
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 2)
    x1, x2, y1, y2 = x[0], x[1], x[2], x[3]
    r2 = x1 ** 2 + x2 ** 2
    rate = p[0] - p[1] ** 2 + a * x1 * (1 + x2)
    return ca.Function("F", [x, p], [ca.vertcat(
        x1 * (1 - r2) - x2, x2 * (1 - r2) + x1,
        rate * y1 + (x2 / 5 - omega) * y2, rate * y2 + omega * y1)])


def _circle(radius=1.0, centre=0.0, z=0, phase=0.013):
    """A circle guess (``z`` zero components appended); its phase puts extrema off the
    mesh points (a minimum at a mesh point is a kink of the condition, where finite
    differences do not apply)."""
    def orbit(t):
        t = np.atleast_1d(t) + phase
        u = np.c_[centre + radius * np.cos(2 * np.pi * t), radius * np.sin(2 * np.pi * t)]
        return np.c_[u, np.zeros((len(t), int(z)))] if z else u
    return orbit


def _cycle(F, orbit, params, active, period=2 * np.pi):
    prob = C.CycleProblem(F, orbit, period, params, active, settings=SETTINGS)
    step = C.ContinuationIterator(prob, C.PALC(), C.ContinuationSettings()).start()
    assert step is not None
    return prob, step.X


def _curve(cycle, X, second, condition, bounds, max_steps=100):
    curve = C.CycleCurveProblem(cycle, X, (cycle.active, second), condition)
    return curve, C.continuation(curve, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.5, max_steps=max_steps, bounds=bounds, compute_eigenvalues=False))


def _fd_gradient_error(curve, X, seed=1):
    """Largest relative error of g_X . d against central differences of g along
    random directions d (the condition's own value function, a different route)."""
    rng = np.random.default_rng(seed)
    g = curve.jacobian(X).toarray()[-1]
    errors = []
    for _ in range(3):
        d = rng.standard_normal(X.size)
        d /= np.linalg.norm(d)
        h = 1e-6
        fd = (curve.residual(X + h * d)[-1] - curve.residual(X - h * d)[-1]) / (2 * h)
        errors.append(abs(g @ d - fd) / max(1.0, np.abs(g).max()))
    return max(errors)


def test_grazing_curve_of_the_shifted_circle_is_c_equal_sqrt_b():
    cycle, X = _cycle(_shifted_hopf(), _circle(0.5, 0.6), {"b": 0.25, "c": 0.6}, "c")
    wall = C.Extremum(rows=[[1.0, 0.0]], level=0.0)
    curve, branch = _curve(cycle, X, "b", wall, {"b": (0.2, 1.0)})
    b, c = branch.par("b"), branch.par("c")
    assert branch.status == "bound" and b.max() > 0.9
    assert np.max(np.abs(c - np.sqrt(b))) < 1e-8
    assert _fd_gradient_error(curve, curve.X0) < 1e-6


def test_lpc_located_by_newton_and_continued_on_the_bautin_fold_curve():
    rho = 0.5
    cycle, X = _cycle(_bautin(), _circle(np.sqrt(0.55)), {"b1": -0.24, "b2": 1.0}, "b1")
    square, result = C.locate_cycle(cycle, X, C.CycleFold())
    assert result.converged
    assert abs(square.par_dict(result.X)["b1"] + 0.25) < 1e-9
    assert np.allclose(np.sum(square.nodes(result.X) ** 2, axis=1), rho, atol=1e-8)
    mu = square.multipliers(result.X)
    assert np.sort(np.abs(mu - 1))[1] < 1e-6                 # the double multiplier at +1
    v = square.condition.null_vector(square, result.X)       # the turn: radial, T fixed
    U = result.X[: v.size - 1]
    assert abs(np.linalg.norm(v) - 1) < 1e-12 and abs(v[-1]) < 1e-10
    assert abs(abs(v[:-1] @ U) / (np.linalg.norm(v[:-1]) * np.linalg.norm(U)) - 1) < 1e-10
    curve, branch = _curve(square, result.X, "b2", C.CycleFold(), {"b2": (0.6, 1.6)})
    b1, b2 = branch.par("b1"), branch.par("b2")
    assert branch.status == "bound" and b2.max() > 1.45
    assert np.max(np.abs(b1 + b2 ** 2 / 4)) < 1e-8
    assert _fd_gradient_error(curve, curve.X0) < 1e-5


def test_section_multiplier_of_a_fold_is_not_split_from_the_trivial_one():
    """At a fold the monodromy has a Jordan block at +1: a discretization error e of
    the trivial multiplier splits the pair by O(sqrt e). The Poincare section's
    multiplier (no trivial one) is off by O(e) only. Bautin ring on a coarse mesh
    (NTST = 8, NCOL = 3): pair off by 1.7e-6, section by 5e-11. Away from the fold
    (rho = 0.6), the section multiplier is the closed form
    exp(2 rho (b2 - 2 rho) T), T = 2 pi / sqrt(1 - e^2), by collocation and by shooting."""
    T = 2 * np.pi / np.sqrt(0.75)
    coarse = C.CollocationSettings(ntst=8, ncol=3)
    cycle = C.CycleProblem(_bautin_ring(), _circle(np.sqrt(0.55)), T,
                           {"b1": -0.24, "b2": 1.0}, "b1", settings=coarse)
    X = C.ContinuationIterator(cycle, C.PALC(), C.ContinuationSettings()).start().X
    square, result = C.locate_cycle(cycle, X, C.CycleFold())
    assert result.converged
    pair = np.sort(np.abs(square.multipliers(result.X) - 1))
    (nu,) = square.section_multipliers(result.X)
    assert abs(nu - 1) < 1e-9 and pair[0] > 100 * abs(nu - 1)
    exact = np.exp(2 * 0.6 * (1.0 - 2 * 0.6) * T)
    params = {"b1": 0.6 ** 2 - 0.6, "b2": 1.0}
    fine, X = _cycle(_bautin_ring(), _circle(np.sqrt(0.6)), params, "b1", period=T)
    shooting = C.ShootingProblem(_bautin_ring(), _circle(np.sqrt(0.6)), T, params, "b1",
                                 settings=C.ShootingSettings(segments=4))
    Y = C.ContinuationIterator(shooting, C.PALC(), C.ContinuationSettings()).start().X
    for problem, Z in ((fine, X), (shooting, Y)):
        (nu,) = problem.section_multipliers(Z)
        assert abs(nu / exact - 1) < 1e-7


def test_period_doubling_located_and_continued_on_mu_equal_nu_squared(models):
    """The half-twisted cycle (conftest) with the transverse rate mu - nu^2: a period
    doubling on mu = nu^2."""
    F = models.half_twisted(n_par=2, rate=lambda p: p[0] - p[1] ** 2)
    cycle, X = _cycle(F, _circle(z=1), {"mu": 0.05, "nu": 0.0}, "mu")
    square, result = C.locate_cycle(cycle, X, C.PeriodDoubling())
    assert result.converged and abs(square.par_dict(result.X)["mu"]) < 1e-9
    mu = square.multipliers(result.X)
    assert np.min(np.abs(mu + 1)) < 1e-6
    curve, branch = _curve(square, result.X, "nu", C.PeriodDoubling(), {"nu": (-0.1, 0.6)})
    m, nu = branch.par("mu"), branch.par("nu")
    assert branch.status == "bound" and nu.max() > 0.35
    assert np.max(np.abs(m - nu ** 2)) < 1e-9
    assert _fd_gradient_error(curve, curve.X0) < 1e-5


def test_neimark_sacker_located_and_continued_on_mu_equal_nu_squared():
    cycle, X = _cycle(_torus(), _circle(z=2), {"mu": 0.05, "nu": 0.0}, "mu")
    square, result = C.locate_cycle(cycle, X, C.NeimarkSacker())
    assert result.converged and abs(square.par_dict(result.X)["mu"]) < 1e-9
    mu = square.multipliers(result.X)
    pair = mu[np.abs(mu.imag) > 0.1]
    assert pair.size == 2 and np.max(np.abs(np.abs(pair) - 1)) < 1e-6
    located = square.condition.multiplier_at(square, result.X)
    assert abs(abs(located) - 1) < 1e-12 and np.min(np.abs(pair - located)) < 1e-6
    curve, branch = _curve(square, result.X, "nu", C.NeimarkSacker(), {"nu": (-0.1, 0.6)})
    m, nu = branch.par("mu"), branch.par("nu")
    assert branch.status == "bound" and nu.max() > 0.35
    assert np.max(np.abs(m - nu ** 2)) < 1e-9
    assert _fd_gradient_error(curve, curve.X0) < 1e-5


def test_neimark_sacker_needs_a_complex_pair(models):
    cycle, X = _cycle(models.half_twisted(), _circle(z=1), {"mu": 0.05}, "mu")
    with pytest.raises(ValueError, match="complex pair"):
        C.locate_cycle(cycle, X, C.NeimarkSacker())


def test_locating_fails_cleanly_far_from_any_fold():
    cycle, X = _cycle(_bautin(), _circle(np.sqrt(0.9)), {"b1": 0.0, "b2": 1.0}, "b1")
    square, result = C.locate_cycle(cycle, X, C.CycleFold(),
                                    C.NewtonSettings(max_iter=3))
    if result.converged:      # Newton may still reach the fold: it must then be the fold
        assert abs(square.par_dict(result.X)["b1"] + 0.25) < 1e-8
    else:
        assert "did not converge" in result.message or "singular" in result.message
