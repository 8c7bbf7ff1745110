"""Multiple shooting (CVODES and its sensitivities) against collocation and known values."""

import casadi as ca
import numpy as np
import pytest

import continuation as C

VDP_T1 = 6.663286859323130   # Van der Pol period at mu = 1 (published benchmark value)


@pytest.fixture(scope="module")
def vdp_routes(models):
    F = models.van_der_pol()
    co = C.CycleProblem(F, models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                        settings=C.CollocationSettings(ntst=40, ncol=4))
    sh = C.ShootingProblem(F, models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                           settings=C.ShootingSettings(segments=8))
    return co, models.corrected(co), sh, models.corrected(sh)


def test_van_der_pol_period_by_both_routes(vdp_routes):
    co, Xc, sh, Xs = vdp_routes
    assert abs(co.period(Xc) - VDP_T1) < 5e-9
    assert abs(sh.period(Xs) - VDP_T1) < 1e-9
    assert abs(co.period(Xc) - sh.period(Xs)) < 5e-9


def test_van_der_pol_multipliers_agree_and_obey_liouville(vdp_routes):
    """Shooting and collocation multipliers agree; their product equals
    exp(int_0^T tr J dt) = exp(int mu (1 - x1^2) dt) (NumPy's Gauss-Legendre rule, exact
    for the square of the collocation polynomial on each interval)."""
    co, Xc, sh, Xs = vdp_routes
    mc, ms = co.multipliers(Xc), sh.multipliers(Xs)
    assert abs(mc[0] - 1) < 1e-9 and abs(ms[0] - 1) < 1e-9
    assert abs(mc[1] / ms[1] - 1) < 1e-7
    s, w = np.polynomial.legendre.leggauss(co.ncol + 1)
    h = np.diff(co.mesh)
    t = co.mesh[:-1, None] + h[:, None] * (s[None, :] + 1) / 2
    x1 = co.evaluate(Xc, t.ravel())[:, 0].reshape(t.shape)
    trace = np.sum(h[:, None] / 2 * w[None, :] * (1 - x1 ** 2)) * co.period(Xc)
    assert abs(np.log(ms[1].real) - trace) < 1e-7


def test_shooting_with_state_dependent_mass(models):
    """M = (2 + x1) I on the unit circle cycle: period 4 pi, multiplier exp(-4 pi)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    r2 = x[0] ** 2 + x[1] ** 2
    F = ca.Function("F", [x, p], [ca.vertcat((1 - r2) * x[0] - x[1], (1 - r2) * x[1] + x[0])])
    M = ca.Function("M", [x, p], [(2 + x[0] + 0 * p[0]) * ca.SX.eye(2)])
    sh = C.ShootingProblem(F, lambda t: np.c_[np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)],
                           12.0, {"e": 0.0}, "e", M=M,
                           settings=C.ShootingSettings(segments=3))
    X = models.corrected(sh)
    assert abs(sh.period(X) - 4 * np.pi) < 1e-9
    mu = sh.multipliers(X)
    assert abs(mu[0] - 1) < 1e-9 and abs(mu[1] / np.exp(-4 * np.pi) - 1) < 1e-7


def test_shooting_branch_matches_collocation_branch(models):
    """Continue Van der Pol in mu by shooting; re-solve each point by collocation."""
    F = models.van_der_pol()
    sh = C.ShootingProblem(F, models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                           settings=C.ShootingSettings(segments=8))
    br = C.continuation(sh, settings=C.ContinuationSettings(ds=0.1, ds_max=0.3, max_steps=4))
    assert br.status == "max_steps" and br.par("mu")[-1] > 1.2
    assert np.all(np.diff(br.columns["period"]) > 0) and br.stable.all()
    for mu, T, x0 in zip(br.par("mu")[1:], br.columns["period"][1:], br.x[1:]):
        co = C.CycleProblem(F, models.van_der_pol_guess, T, {"mu": float(mu)}, "mu",
                            settings=C.CollocationSettings(ntst=40, ncol=4))
        Xc = models.corrected(co)
        assert abs(co.period(Xc) - T) < 1e-8


def test_integrator_failure_is_data(models):
    """A hopeless guess makes CVODES fail; the run ends as status 'failed'."""
    F = models.van_der_pol()
    sh = C.ShootingProblem(F, models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                           settings=C.ShootingSettings(segments=2, abstol=1e-12))
    sh.X0[-2] = 400.0
    br = C.continuation(sh, settings=C.ContinuationSettings(max_steps=2))
    assert br.status == "failed" and len(br) == 0 and "start point" in br.message


def test_shooting_settings_validation(models):
    with pytest.raises(ValueError, match="segments"):
        C.ShootingSettings(segments=0)
    with pytest.raises(ValueError, match="integrator"):
        C.ShootingSettings(integrator="euler")
    with pytest.raises(ValueError, match="settings"):
        C.ShootingProblem(models.van_der_pol(), models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                          settings=C.CollocationSettings())


def test_shooting_multipliers_keep_a_strongly_contracting_one(models):
    """r' = 3 r (1 - r^2) on the unit circle, period 2 pi: multiplier exp(-12 pi) = 4.2e-17,
    below round-off relative to the trivial one. The default route (periodic Schur of the
    8 segments' sensitivities) keeps it to 1e-5 relative (measured 9e-9; the integrator's
    tolerance against each segment's contraction exp(-1.5 pi) bounds it), and so does
    the Poincare map's; the product of the sensitivities loses it."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    g = 3 * (1 - x[0] ** 2 - x[1] ** 2)
    F = ca.Function("F", [x, p], [ca.vertcat(g * x[0] - x[1] + 0 * p[0], g * x[1] + x[0])])
    orbit = lambda t: np.c_[np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)]  # noqa: E731
    sh = C.ShootingProblem(F, orbit, 2 * np.pi, {"e": 0.0}, "e",
                           settings=C.ShootingSettings(segments=8))
    X = models.corrected(sh)
    exact = np.exp(-12 * np.pi)
    mu = sh.multipliers(X)
    assert abs(mu[0] - 1) < 1e-9 and abs(mu[1] / exact - 1) < 1e-5
    assert abs(sh.section_multipliers(X)[0] / exact - 1) < 1e-5
    prod = C.ShootingProblem(F, orbit, 2 * np.pi, {"e": 0.0}, "e", settings=C.ShootingSettings(
        segments=8, floquet="product")).multipliers(X)
    assert abs(prod[0] - 1) < 1e-9 and abs(prod[1] / exact - 1) > 1e-2
