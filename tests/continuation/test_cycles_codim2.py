"""Cycles switched onto from Hopf curves: from any point of a Hopf curve, and the fold of
cycles curve born at a generalized Hopf point, against the Bautin normal form's closed
forms and, for a field that is not a normal form, against time integration."""

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import continuation as C

SETTINGS = C.CollocationSettings(ntst=20, ncol=4)


def run(problem, record=None, **kw):
    base = dict(ds=0.02, ds_max=0.1, max_steps=100)
    base.update(kw)
    return C.continuation(problem, settings=C.ContinuationSettings(**base), record=record)


def bautin(omega=1.3, b=-0.8, c=0.7, d=-0.4, extra=False):
    """The Bautin normal form ``w' = (mu + i omega) w + a w|w|^2 + b w|w|^4`` (``w = y1 +
    i y2``) in the coordinates ``x = (y1, y2 + c y1^2 + d y1^3)`` and the parameters
    ``(s, t)`` with ``mu = s + 0.4 t``, ``a = t - 0.5 s``: its cycles are the circles
    ``|w|^2 = r^2``, ``mu + a r^2 + b r^4 = 0``, so ``max x1 = r``, and its folds of
    cycles are ``mu = a^2 / (4 b)``, ``r^2 = -a / (2 b)`` (where ``a b < 0``). ``extra``:
    a third, stable coordinate ``x3' = -x3 + x1^2`` (not a normal form any more)."""
    x, p = ca.SX.sym("x", 3 if extra else 2), ca.SX.sym("p", 2)
    mu, a = p[0] + 0.4 * p[1], p[1] - 0.5 * p[0]
    y = ca.vertcat(x[0], x[1] - c * x[0] ** 2 - d * x[0] ** 3)
    r2 = y[0] ** 2 + y[1] ** 2
    if extra:
        mu = mu + 0.5 * x[2]                       # the stable mode feeds back
    g = ca.vertcat(mu * y[0] - omega * y[1], omega * y[0] + mu * y[1]) + (a * r2 + b * r2 ** 2) * y
    f = ca.vertcat(g[0], g[1] + (2 * c * y[0] + 3 * d * y[0] ** 2) * g[0])
    if extra:
        f = ca.vertcat(f, -x[2] + x[0] ** 2)
    return ca.Function("F", [x, p], [f])


def mu_a(s, t):
    return s + 0.4 * t, t - 0.5 * s


def hopf_curve(F, n, t0, bounds):
    """The Hopf curve in (s, t) through the Hopf point met along s at t = t0."""
    prob = C.EquilibriumProblem(F, np.zeros(n), {"s": -0.3, "t": t0}, "s")
    (h,) = run(prob, bounds={"s": (-1.0, 1.0)}).special("hopf")
    curve = C.HopfCurveProblem.from_point(prob, h, "t")
    return curve, run(curve, bounds={"t": bounds})


def radius(problem, X, c=0.7, d=-0.4):
    """The largest and least ``|w|`` at the cycle's nodes (``w = y1 + i y2`` of :func:`bautin`)."""
    x = problem.nodes(X)
    r = np.hypot(x[:, 0], x[:, 1] - c * x[:, 0] ** 2 - d * x[:, 0] ** 3)
    return {"r": float(r.max()), "r_min": float(r.min())}


def at(curve, branch, i):
    """A Hopf curve problem whose ``X0`` is point ``i`` of the curve's ``branch``."""
    params = dict(zip(branch.par_names, branch.params[i]))
    return C.HopfCurveProblem(curve.vf, branch.x[i], params, branch.columns["omega"][i],
                              curve.free)


@pytest.mark.parametrize("active", ["s", "t"])
def test_cycle_from_a_point_of_a_hopf_curve(active):
    """A supercritical point of the Hopf curve (a < 0), not a special point: the cycles
    continued in either parameter are the circles ``mu + a r^2 + b r^4 = 0``."""
    b = -0.8
    curve, branch = hopf_curve(bautin(b=b), 2, -0.4, (-0.8, -0.2))
    point = at(curve, branch, len(branch) // 2)
    cycle = C.cycle_from_hopf(point, point.X0, dp=1e-3, settings=SETTINGS, active=active)
    cycles = run(cycle, direction=cycle.hopf_direction, max_steps=12, ds=0.01, ds_max=0.02,
                 record=radius)
    assert cycles.status != "failed" and len(cycles) > 10
    for k in range(len(cycles)):
        mu, a = mu_a(*cycles.params[k])
        r2 = (-a - np.sqrt(a * a - 4 * b * mu)) / (2 * b)
        for r in (cycles.columns["r"][k], cycles.columns["r_min"][k]):
            assert r == pytest.approx(np.sqrt(r2), rel=1e-6)


def test_cycle_from_a_hopf_curve_checks_its_point():
    curve, branch = hopf_curve(bautin(), 2, -0.4, (-0.8, -0.2))
    with pytest.raises(ValueError, match="active"):
        C.cycle_from_hopf(curve, curve.X0, active="mu")
    with pytest.raises(ValueError, match="unknowns"):
        C.cycle_from_hopf(curve, curve.X0[:-1], active="s")
