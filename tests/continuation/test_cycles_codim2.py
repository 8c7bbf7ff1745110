"""Cycles switched onto from Hopf curves: from any point of a Hopf curve, and the fold of
cycles curve born at a generalized Hopf point, against the Bautin normal form's closed
forms and, for a field that is not a normal form, against time integration."""

import casadi as ca
import numpy as np
import pytest

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


@pytest.mark.parametrize("b, omega", [(-0.8, 1.3), (0.5, 0.7)])
def test_fold_of_cycles_curve_from_a_generalized_hopf_point(b, omega):
    """The continued LPC curve is ``mu = a^2 / (4 b)`` with the merging cycles' radius
    ``r^2 = -a / (2 b)`` (closed forms of the normal form; ``a b < 0``)."""
    curve, branch = hopf_curve(bautin(omega, b), 2, -0.4, (-0.8, 0.5))
    (gh,) = branch.special("gh")
    lpc = C.lpc_from_gh(curve, gh, epsilon=0.05, settings=SETTINGS)
    folds = run(lpc, direction=lpc.away_direction, max_steps=25, ds=0.05, ds_max=0.3,
                record=radius)
    assert folds.status != "failed" and len(folds) > 10
    mu, a = mu_a(folds.par("s"), folds.par("t"))
    assert np.all(a * b < 0) and np.ptp(a) > 0.2                 # moved away from a = 0
    np.testing.assert_allclose(mu, a ** 2 / (4 * b), rtol=0, atol=1e-8)
    # the radius at a fold is the square root of what fixes it: discretization shows more
    for r in (folds.columns["r"], folds.columns["r_min"]):
        np.testing.assert_allclose(r, np.sqrt(-a / (2 * b)), rtol=2e-6)


def settles(F, s, t, x0, t_end=3000.0):
    """``max |(x1, x2)|`` over the last tenth of ``[0, t_end]`` from ``x0`` at ``(s, t)``
    (CVODES, tolerances 1e-10)."""
    x, p = ca.SX.sym("x", len(x0)), ca.SX.sym("p", 2)
    grid = np.linspace(0.9 * t_end, t_end, 400)
    flow = ca.integrator("flow", "cvodes", {"x": x, "p": p, "ode": F(x, p)}, 0.0, grid,
                         {"reltol": 1e-10, "abstol": 1e-12, "max_num_steps": 10 ** 6})
    tail = np.asarray(flow(x0=x0, p=[s, t])["xf"])
    return float(np.max(np.hypot(tail[0], tail[1])))


def test_fold_of_cycles_curve_against_time_integration():
    """Not a normal form (a stable third mode feeds the amplitude back): between the Hopf
    curve ``mu = 0`` and the continued LPC curve, at 1 % of their distance inside, the
    equilibrium and a large cycle are both stable (the hysteresis); at 1 % outside the
    large start decays to the equilibrium. (The fold is far from the normal form's
    ``mu = a^2 / (4 b)``: the third mode moves it.)"""
    F = bautin(extra=True)
    curve, branch = hopf_curve(F, 3, -0.4, (-0.8, 0.5))
    (gh,) = branch.special("gh")
    lpc = C.lpc_from_gh(curve, gh, epsilon=0.05, settings=SETTINGS)
    folds = run(lpc, direction=lpc.away_direction, max_steps=25, ds=0.05, ds_max=0.3,
                record=radius)
    k = np.argmin(np.abs(folds.par("t") - 0.25))
    s_fold, t, r = folds.par("s")[k], folds.par("t")[k], folds.columns["r"][k]
    s_hopf = -0.4 * t                                          # mu = 0 at x = 0
    assert s_fold < s_hopf and abs(mu_a(s_fold, t)[0]) > 1e-3
    inside, outside = (s_fold + f * (s_hopf - s_fold) for f in (0.01, -0.01))
    large = [2 * r, 0.0, 0.0]
    assert settles(F, inside, t, [0.05 * r, 0.0, 0.0]) < 1e-6
    assert settles(F, inside, t, large) > 0.5 * r
    assert settles(F, outside, t, large) < 1e-6


def double_hopf(a, c=0.6, omega=(1.0, 1.7), quadratic=0.0):
    """The truncated double-Hopf normal form ``w1' = (mu1 + i omega1) w1 + (a11 |w1|^2 +
    a12 |w2|^2) w1``, ``w2' = (mu2 + i omega2) w2 + (a21 |w1|^2 + a22 |w2|^2) w2``, sheared
    (``u4 = y4 + c y1^2``) and rotated: the cycles of pair 1, ``|w1|^2 = -mu1 / Re a11``,
    bifurcate into tori where ``w2`` stops decaying, ``mu2 + Re a21 |w1|^2 = 0``: the line
    ``mu2 = (Re a21 / Re a11) mu1`` (``mu1 / Re a11 < 0``). ``quadratic``: a term
    ``quadratic y1^2`` added to ``y3'``: the cycles of pair 1 leave its plane (not a
    normal form any more)."""
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 2)
    Q = np.linalg.qr(np.random.default_rng(3).standard_normal((4, 4)))[0]
    u = ca.mtimes(ca.DM(Q), x)
    y = ca.vertcat(u[0], u[1], u[2], u[3] - c * u[0] ** 2)
    s1, s2 = y[0] ** 2 + y[1] ** 2, y[2] ** 2 + y[3] ** 2
    g = []
    for (w0, w1), mu, om, (k1, k2) in (((y[0], y[1]), p[0], omega[0], a[0]),
                                       ((y[2], y[3]), p[1], omega[1], a[1])):
        re, im = mu + k1.real * s1 + k2.real * s2, om + k1.imag * s1 + k2.imag * s2
        g += [re * w0 - im * w1, im * w0 + re * w1]
    g[2] = g[2] + quadratic * y[0] ** 2
    g[3] = g[3] + 2 * c * y[0] * g[0]
    return ca.Function("F", [x, p], [ca.mtimes(ca.DM(Q.T), ca.vertcat(*g))])


@pytest.mark.parametrize("a", [
    [[-1 + 0.3j, 0.5 - 0.2j], [-1.5 + 0.1j, -2 + 0.4j]],
    [[1 + 0.3j, 0.5 - 0.2j], [0.7 + 0.1j, -2 + 0.4j]]])
def test_neimark_sacker_curve_from_a_double_hopf_point(a):
    """The continued torus curve is the closed-form line (1e-8); at its first point the
    period is ``2 pi / (omega1 + Im a11 r^2)`` and the multiplier on the unit circle is
    ``exp(+-i (omega2 + Im a21 r^2) T)`` (``r^2 = |w1|^2``), for both signs of ``p11``."""
    F = double_hopf(a)
    prob = C.EquilibriumProblem(F, np.zeros(4), {"mu1": -0.3, "mu2": -0.4}, "mu1")
    (h,) = run(prob, bounds={"mu1": (-1.0, 0.3)}).special("hopf")
    curve = C.HopfCurveProblem.from_point(prob, h, "mu2")
    (hh,) = run(curve, bounds={"mu2": (-1.0, 0.5)},
                compute_eigenvalues=True).special("hh")
    ns = C.ns_from_hh(curve, hh, epsilon=0.05, settings=SETTINGS)
    tori = run(ns, direction=ns.away_direction, max_steps=15, ds=0.05, ds_max=0.2)
    assert tori.status != "failed" and len(tori) > 10
    mu1, mu2 = tori.par("mu1"), tori.par("mu2")
    assert np.ptp(mu2) > 0.1 and np.all(mu1 / a[0][0].real < 0)
    np.testing.assert_allclose(mu2, a[1][0].real / a[0][0].real * mu1, rtol=0, atol=1e-8)
    r2 = -ns.par_dict(ns.X0)["mu1"] / a[0][0].real
    T = 2 * np.pi / (1.0 + a[0][0].imag * r2)
    assert ns.period(ns.X0) == pytest.approx(T, rel=1e-9)
    mu = ns.condition.multiplier_at(ns, ns.X0)
    turn = np.exp(1j * (1.7 + a[1][0].imag * r2) * T)
    assert min(abs(mu - turn), abs(mu - turn.conjugate())) < 1e-7


def test_neimark_sacker_curve_of_the_other_pair():
    """Along the other Hopf curve (``mu2 = 0``) the double Hopf point carries the
    coefficients with the pairs swapped, and the torus curve of the second pair's cycles
    is ``mu1 = (Re a12 / Re a22) mu2`` (``mu2 / Re a22 < 0``)."""
    a = [[-1 + 0.3j, 0.5 - 0.2j], [-1.5 + 0.1j, -2 + 0.4j]]
    prob = C.EquilibriumProblem(double_hopf(a), np.zeros(4), {"mu1": -0.3, "mu2": -0.4}, "mu2")
    (h,) = run(prob, bounds={"mu2": (-1.0, 0.3)}).special("hopf")
    curve = C.HopfCurveProblem.from_point(prob, h, "mu1")
    (hh,) = run(curve, bounds={"mu1": (-1.0, 0.5)}, compute_eigenvalues=True).special("hh")
    ns = C.ns_from_hh(curve, hh, epsilon=0.05, settings=SETTINGS)
    tori = run(ns, direction=ns.away_direction, max_steps=15, ds=0.05, ds_max=0.2)
    mu1, mu2 = tori.par("mu1"), tori.par("mu2")
    assert tori.status != "failed" and np.ptp(mu2) > 0.1 and np.all(mu2 / a[1][1].real < 0)
    np.testing.assert_allclose(mu1, a[0][1].real / a[1][1].real * mu2, rtol=0, atol=1e-8)


def test_neimark_sacker_curve_against_a_cycle_branch():
    """Not a normal form (quadratic coupling): the torus bifurcation of the cycle branch in
    mu1 at a fixed mu2 of the continued curve, detected by its Floquet multipliers
    (no NeimarkSacker condition), lies on the curve."""
    a = [[-1 + 0.3j, 0.5 - 0.2j], [-1.5 + 0.1j, -2 + 0.4j]]
    F = double_hopf(a, quadratic=0.8)
    prob = C.EquilibriumProblem(F, np.zeros(4), {"mu1": -0.3, "mu2": -0.4}, "mu1")
    (h,) = run(prob, bounds={"mu1": (-1.0, 0.3)}).special("hopf")
    curve = C.HopfCurveProblem.from_point(prob, h, "mu2")
    (hh,) = run(curve, bounds={"mu2": (-1.0, 0.5)}, compute_eigenvalues=True).special("hh")
    ns0 = C.ns_from_hh(curve, hh, epsilon=0.05, settings=SETTINGS)
    tori = run(ns0, max_steps=10, ds=0.05, ds_max=0.1, direction=ns0.away_direction)
    k = len(tori) - 1
    mu1, mu2 = tori.par("mu1")[k], tori.par("mu2")[k]
    eq = C.EquilibriumProblem(F, np.zeros(4), {"mu1": -0.2, "mu2": mu2}, "mu1")
    (h1,) = run(eq, bounds={"mu1": (-1.0, 0.3)}).special("hopf")
    cycle = C.cycle_from_hopf(eq, h1, dp=1e-3, settings=SETTINGS)
    cycles = run(cycle, direction=cycle.hopf_direction, ds=0.01, ds_max=0.05,
                 bounds={"mu1": (-1.0, 2 * mu1)})
    (ns,) = cycles.special("ns")
    assert ns.status == "converged" and abs(a[1][0].real / a[0][0].real * mu1 - mu2) > 1e-3
    assert ns.params["mu1"] == pytest.approx(mu1, rel=1e-7)


def zero_hopf(theta, e=-0.5, omega=1.3):
    """``xi' = b1 + xi^2 - r^2``, ``w' = (b2 + e r^2 + i omega + (theta + 0.4 i) xi) w``
    (``r = |w|``): the zero-Hopf point ``b1 = b2 = 0`` of the Hopf curve ``b1 = -b2^2 /
    theta^2`` (normal form B = 1, C = -1 per ``r^2``, D = theta + 0.4 i: ``s = -1``). The
    cycles are the amplitude equilibria ``b1 + xi^2 - r^2 = 0``, ``b2 + theta xi + e r^2 =
    0``; their Jacobian ``[[2 xi, -2 r], [theta r, 2 e r^2]]`` has the trace zero (a torus
    born) on ``xi = -e rho`` (``rho = r^2``): the Neimark-Sacker curve ``b1 = rho - e^2
    rho^2``, ``b2 = e (theta - 1) rho``, where the determinant ``2 rho (theta - 2 e^2 rho)``
    is positive, so only for ``theta > 0`` (``s theta < 0``)."""
    x, p = ca.SX.sym("x", 3), ca.SX.sym("p", 2)
    xi, r2 = x[0], x[1] ** 2 + x[2] ** 2
    re, im = p[1] + theta * xi + e * r2, omega + 0.4 * xi
    return ca.Function("F", [x, p], [ca.vertcat(p[0] + xi ** 2 - r2, re * x[1] - im * x[2],
                                                im * x[1] + re * x[2])])


def zero_hopf_curve(theta):
    F = zero_hopf(theta)
    prob = C.EquilibriumProblem(F, [-0.5, 0.0, 0.0], {"b1": -0.25, "b2": 0.5 * theta - 0.2},
                                "b2")
    (h,) = run(prob, bounds={"b2": (-2.0, 2.0)}).special("hopf")
    curve = C.HopfCurveProblem.from_point(prob, h, "b1")
    return curve, run(curve, bounds={"b1": (-1.0, 0.01)}, max_steps=200)


def test_torus_curve_switched_onto_from_a_zero_hopf_point():
    theta, e = 0.8, -0.5
    curve, branch = zero_hopf_curve(theta)
    (zh,) = branch.special("zh")
    assert zh.data["s"] == -1 and zh.data["theta"] == pytest.approx(theta, abs=1e-7)
    ns = C.ns_from_zh(curve, zh, epsilon=0.005, settings=SETTINGS)
    rho = ns.par_dict(ns.X0)["b2"] / (e * (theta - 1))
    assert rho > 0 and abs(ns.par_dict(ns.X0)["b1"] - (rho - e ** 2 * rho ** 2)) < 1e-8
    torus = C.continuation(ns, settings=C.ContinuationSettings(
        ds=0.01, ds_max=0.05, max_steps=150, direction=ns.away_direction,
        bounds={"b2": (0.0, 0.03)}, compute_eigenvalues=False))
    b1, b2 = torus.par("b1"), torus.par("b2")
    rho = b2 / (e * (theta - 1))
    assert torus.status == "bound" and rho.max() > 0.2
    assert np.max(np.abs(b1 - (rho - e ** 2 * rho ** 2))) < 1e-8
    with pytest.raises(ValueError, match="no torus curve"):
        other, branch = zero_hopf_curve(-1.2)
        C.ns_from_zh(other, branch.special("zh")[0], settings=SETTINGS)
