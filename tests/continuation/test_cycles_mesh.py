"""Mesh adaptation by equidistribution and the a-posteriori error indicator."""

import casadi as ca
import numpy as np
import pytest

import continuation as C


def _settings(**kw):
    return C.ContinuationSettings(**{**dict(ds=0.5, ds_max=5.0, max_steps=60,
                                            bounds={"mu": (0.5, 10.0)}), **kw})


@pytest.fixture(scope="module")
def relaxation(models):
    """Van der Pol near mu = 8 (a relaxation oscillation: the last cycle below mu = 8.5)
    and its period by shooting."""
    F = models.van_der_pol()
    co = C.CycleProblem(F, models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                        settings=C.CollocationSettings(ntst=40, ncol=4, adapt_every=3))
    X = list(C.ContinuationIterator(co, C.PALC(), _settings(bounds={"mu": (0.5, 8.5)})))[-1].X
    mu, T = co.params(X)[0], co.period(X)
    sh = C.ShootingProblem(F, lambda t: co.evaluate(X, t), T, {"mu": mu}, "mu",
                           settings=C.ShootingSettings(segments=20))
    return F, co, X, mu, sh.period(models.corrected(sh))


def test_adapted_mesh_beats_uniform_mesh_per_unknown(relaxation, models):
    """Same NTST = 40 (same number of unknowns): two equidistribution passes reduce
    the period error from ~0.3 to ~3e-7 (reference: shooting, independent route)."""
    F, co, X, mu, T_ref = relaxation
    uni = C.CycleProblem(F, lambda t: co.evaluate(X, t), co.period(X), {"mu": mu}, "mu",
                         settings=C.CollocationSettings(ntst=40, ncol=4))
    Xu = models.corrected(uni)
    ad, Xa = uni.remesh(Xu)
    Xa = models.corrected(ad)
    ad2, Xa2 = ad.remesh(Xa)
    Xa2 = models.corrected(ad2)
    err_u, err_a = abs(uni.period(Xu) - T_ref), abs(ad2.period(Xa2) - T_ref)
    assert err_u > 1e-2 and err_a < 1e-5 and err_a < 1e-3 * err_u
    assert Xa2.size == Xu.size
    h = np.diff(ad2.mesh)
    assert h.max() / h.min() > 10          # the mesh concentrates at the fast jumps


def test_error_indicator_follows_order_and_drops_after_remesh(models):
    """Smooth cycle (ring with e = 1/2): the indicator decreases like NTST^-(NCOL+1)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    r2 = x[0] ** 2 + x[1] ** 2
    th = 1 + p[0] * x[0] / ca.sqrt(r2)
    F = ca.Function("F", [x, p], [ca.vertcat((1 - r2) * x[0] - x[1] * th,
                                             (1 - r2) * x[1] + x[0] * th)])
    est = []
    ns = (16, 32, 64)
    for ntst in ns:
        pr = C.CycleProblem(F, lambda t: np.c_[np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)],
                            7.0, {"e": 0.5}, "e", settings=C.CollocationSettings(ntst=ntst, ncol=3))
        est.append(pr.error_estimate(models.corrected(pr)))
    order = -np.polyfit(np.log(ns), np.log(est), 1)[0]
    assert abs(order - 4) < 0.5, est


def test_adaptive_continuation_restarts_and_lowers_the_error(models):
    """adapt_every = 3 re-meshes during the run (driver restarts, columns recorded with
    each point's own mesh); at the end of the run (mu near 10) the error indicator is
    more than 10x below that of the uniform run with the same NTST."""
    F = models.van_der_pol()
    runs = {}
    for adapt in (0, 3):
        co = C.CycleProblem(F, models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                            settings=C.CollocationSettings(ntst=40, ncol=4, adapt_every=adapt))
        runs[adapt] = C.continuation(co, settings=_settings())
        assert runs[adapt].status == "bound" and runs[adapt].par("mu")[-1] > 8
    assert runs[3].stats.get("restarts", 0) >= 3 and "restarts" not in runs[0].stats
    assert runs[3].columns["error_estimate"][-1] < 0.1 * runs[0].columns["error_estimate"][-1]


def test_mesh_validation(models):
    with pytest.raises(ValueError, match="mesh"):
        C.CycleProblem(models.van_der_pol(), models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                       settings=C.CollocationSettings(ntst=3), mesh=[0, 0.5, 0.4, 1])
    with pytest.raises(ValueError, match="adapt_every"):
        C.CollocationSettings(adapt_every=-1)


def test_van_der_pol_large_mu_matches_dorodnitsyn_asymptotics(models):
    """Adaptive-mesh continuation from mu = 1 to 40 (NTST = 60). The period follows
    T3 = (3 - 2 ln 2) mu + 3 a mu^(-1/3) - (2/3) ln(mu)/mu (a = 2.338107, first Airy
    zero; Dorodnitsyn) up to the next term c/mu: mu (T - T3) stays within
    [-1.75, -1.40] for mu >= 5 and moves monotonically (measured -1.71 at mu = 5,
    -1.46 at mu = 39); at mu = 1 the published T = 6.663286859323130."""
    F = models.van_der_pol()
    co = C.CycleProblem(F, models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                        settings=C.CollocationSettings(ntst=60, ncol=4, adapt_every=2))
    br = C.continuation(co, settings=C.ContinuationSettings(
        ds=0.5, ds_max=10.0, max_steps=200, bounds={"mu": (0.5, 41.0)}))
    mu, T = br.par("mu"), br.columns["period"]
    assert br.status == "bound" and mu[-1] > 38
    assert abs(T[0] - 6.663286859323130) < 1e-8
    a = 2.338107410459767
    T3 = (3 - 2 * np.log(2)) * mu + 3 * a * mu ** (-1 / 3) - 2 / 3 * np.log(mu) / mu
    c = (mu * (T - T3))[mu >= 5]
    assert np.all((c > -1.75) & (c < -1.40)) and np.all(np.diff(c) > 0)


class _CorrectedRestarts(C.CycleProblem):
    """The same problem, restarted the other way: each re-meshed cycle corrected on its
    new mesh with a fresh tangent before the branch goes on (no carried tangent)."""

    def restart(self, X):
        out = super().restart(X)
        if out is None:
            return None
        new, X_new = out[:2]
        new.__class__ = _CorrectedRestarts
        return new, X_new


def test_continuous_remesh_restarts_stay_on_the_cycles_and_save_corrections(models):
    """Re-meshing every point (adapt_every = 1): the branch goes on from the interpolated
    cycle along the interpolated tangent (as AUTO-07p adapts), with no correction of its
    own. Independent check: every recorded cycle, integrated over its period from its
    u(0) by solve_ivp (rtol 1e-12), returns to u(0) to the collocation error (measured
    3.3e-7, the same as with corrected restarts); and against corrected restarts it
    needs fewer Newton iterations for the same parameter range (39 against 56)."""
    from scipy.integrate import solve_ivp
    F = models.van_der_pol()
    settings = C.ContinuationSettings(ds=0.5, ds_max=2.0, max_steps=25, bounds={"mu": (0.5, 4.0)})
    runs = {}
    for make in (C.CycleProblem, _CorrectedRestarts):
        co = make(F, models.van_der_pol_guess, 6.6, {"mu": 1.0}, "mu",
                  settings=C.CollocationSettings(ntst=30, ncol=4, adapt_every=1))
        runs[make] = C.continuation(co, settings=settings)
        assert runs[make].status == "bound" and runs[make].stats["restarts"] >= 10
    branch = runs[C.CycleProblem]
    rhs = lambda t, u, mu: [u[1], mu * (1 - u[0] ** 2) * u[1] - u[0]]
    for mu, u0, T in zip(branch.par("mu"), branch.x, branch.columns["period"]):
        end = solve_ivp(rhs, (0, T), u0, args=(mu,), rtol=1e-12, atol=1e-12).y[:, -1]
        assert np.max(np.abs(end - u0)) < 1e-6
    corrected = runs[_CorrectedRestarts]
    per_step = lambda b: b.stats["newton_iterations"] / b.stats["steps"]
    assert per_step(branch) < per_step(corrected)
