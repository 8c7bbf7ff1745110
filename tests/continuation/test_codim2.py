"""Codimension-two points of Hopf curves and their normal-form coefficients, against
normal forms with known coefficients, closed forms and an independent route."""

import dataclasses

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import continuation as C


def run(problem, **kw):
    base = dict(ds=0.02, ds_max=0.1, max_steps=100)
    base.update(kw)
    return C.continuation(problem, settings=C.ContinuationSettings(**base))


def hopf_curve(F, x0, params, first, second, bounds, M=None, **kw):
    """The Hopf curve in ``(first, second)`` through the Hopf point met along ``first``."""
    prob = C.EquilibriumProblem(F, x0, params, first, M=M)
    (h,) = run(prob, bounds={first: bounds[0]}).special("hopf")
    return run(C.HopfCurveProblem.from_point(prob, h, second), bounds={second: bounds[1]}, **kw)


def sheared_bautin(omega, b, c=0.7, d=-0.4, mass=None):
    """The Bautin normal form ``w' = (mu + i omega) w + a w|w|^2 + b w|w|^4`` (``w = y1 +
    i y2``) in the coordinates ``x = (y1, y2 + c y1^2 + d y1^3)``: a near-identity change,
    so ``l1 = 2 a / omega`` and at ``a = 0`` ``l2 = 4 b / omega`` (module docstring of the
    normal forms); ``mass`` (a scalar ``m(x)``) multiplies both sides."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    y = ca.vertcat(x[0], x[1] - c * x[0] ** 2 - d * x[0] ** 3)
    r2 = y[0] ** 2 + y[1] ** 2
    g = ca.vertcat(p[0] * y[0] - omega * y[1], omega * y[0] + p[0] * y[1]) \
        + (p[1] * r2 + b * r2 ** 2) * y
    f = ca.vertcat(g[0], g[1] + (2 * c * y[0] + 3 * d * y[0] ** 2) * g[0])
    if mass is None:
        return ca.Function("F", [x, p], [f]), None
    m = mass(x)
    return ca.Function("F", [x, p], [m * f]), ca.Function("M", [x, p], [m * ca.SX.eye(2)])


@pytest.mark.parametrize("omega, b, mass", [
    (1.7, -0.8, None), (0.6, 0.5, None), (1.3, -0.3, lambda x: 1.5 + 0.5 * x[0] + x[1] ** 2)])
def test_generalized_hopf_second_lyapunov_on_the_bautin_normal_form(omega, b, mass):
    F, M = sheared_bautin(omega, b, mass=mass)
    curve = hopf_curve(F, [0.0, 0.0], {"mu": -0.2, "a": -0.5}, "mu", "a",
                       [(-1, 0.2), (-1, 1)], M=M)
    (gh,) = curve.special("gh")
    assert gh.status == "converged" and abs(gh.params["a"]) < 1e-10
    assert gh.data["omega"] == pytest.approx(omega, rel=1e-12)
    assert abs(gh.data["l1"]) < 1e-9
    assert gh.data["l2"] == pytest.approx(4 * b / omega, rel=1e-9)


def test_second_lyapunov_against_the_return_map():
    """Independent route: at the located generalized Hopf point of a planar field with
    quadratic to quartic terms, the return map of the section ``y = 0, x = s > 0``
    (integrated) is ``s -> s + 2 pi l2 s^5 / k^4 + O(s^6)``: ``|z|' = l2 omega |z|^5`` in
    the normal form, ``s = k |z|`` with ``k = 2 |q_1| = sqrt 2`` for ``q = (1, -i)/sqrt 2``."""
    def field(x, y, mu, nu):
        r2 = x ** 2 + y ** 2
        return (mu * x - y + x ** 2 - 0.5 * x * y + nu * x * r2 + 0.3 * y ** 3
                - 0.2 * x ** 2 * y ** 2,
                x + mu * y + 0.7 * x * y + y ** 2 + 0.2 * x * r2 + 0.1 * x ** 4)
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    F = ca.Function("F", [x, p], [ca.vertcat(*field(x[0], x[1], p[0], p[1]))])
    curve = hopf_curve(F, [0.0, 0.0], {"mu": -0.2, "nu": -3.0}, "mu", "nu",
                       [(-1, 0.2), (-3, 3)], max_steps=200)
    (gh,) = curve.special("gh")
    mu, nu = gh.params["mu"], gh.params["nu"]
    crossing = lambda t, z: z[1]
    crossing.direction = 1

    def gain(s):
        sol = solve_ivp(lambda t, z: field(z[0], z[1], mu, nu), (0, 20), [s, 0.0],
                        method="DOP853", rtol=1e-13, atol=1e-16, events=crossing)
        later = sol.t_events[0] > 1.0
        return sol.y_events[0][later][0][0] - s

    s = np.linspace(0.01, 0.05, 9)
    fit = np.polyfit(s, np.array([gain(v) for v in s]) / s ** 5, 3)
    assert fit[-1] * 4 / (2 * np.pi) == pytest.approx(gh.data["l2"], rel=1e-4)
    assert abs(gh.data["l2"]) > 0.1


def double_hopf(a, c=0.6, omega=(1.0, 1.7)):
    """The truncated double-Hopf normal form ``w1' = (mu1 + i omega1) w1 + (a11 |w1|^2 +
    a12 |w2|^2) w1``, ``w2' = (mu2 + i omega2) w2 + (a21 |w1|^2 + a22 |w2|^2) w2`` (``w1 =
    y1 + i y2, w2 = y3 + i y4``), sheared (``u4 = y4 + c y1^2``) and rotated (``x = Q^T
    u``, Q orthogonal): near-identity and orthogonal changes keep the coefficients, and
    ``|q| = 1`` (``w = sqrt 2 z``) gives ``p_jk = 2 Re a_jk``."""
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 2)
    Q = np.linalg.qr(np.random.default_rng(3).standard_normal((4, 4)))[0]
    u = ca.mtimes(ca.DM(Q), x)
    y = ca.vertcat(u[0], u[1], u[2], u[3] - c * u[0] ** 2)
    w1, w2 = (y[0], y[1]), (y[2], y[3])
    s1, s2 = y[0] ** 2 + y[1] ** 2, y[2] ** 2 + y[3] ** 2

    def mode(w, mu, om, k1, k2):   # (mu + i om + k1 s1 + k2 s2) w, k complex
        re, im = mu + k1.real * s1 + k2.real * s2, om + k1.imag * s1 + k2.imag * s2
        return [re * w[0] - im * w[1], im * w[0] + re * w[1]]

    g = mode(w1, p[0], omega[0], a[0][0], a[0][1]) + mode(w2, p[1], omega[1], a[1][0], a[1][1])
    g[3] = g[3] + 2 * c * y[0] * g[0]
    return ca.Function("F", [x, p], [ca.mtimes(ca.DM(Q.T), ca.vertcat(*g))])


@pytest.mark.parametrize("a, simple, torus", [
    ([[-1 + 0.3j, 0.5 - 0.2j], [-1.5 + 0.1j, -2 + 0.4j]], True, True),
    ([[-1 + 0.3j, 1 - 0.2j], [-1.5 + 0.1j, 1 + 0.4j]], False, True),
    ([[-1 + 0.3j, 0.5 - 0.2j], [-1.5 + 0.1j, 1 + 0.4j]], False, False)])
def test_double_hopf_coefficients_on_the_normal_form(a, simple, torus):
    """Stable torus of the amplitude equations: ``p11 p22 - p12 p21 > 0`` and ``p11 < 0``
    or ``p22 < 0`` (the 2x2 Jacobian at ``r1, r2 > 0`` is ``2 diag(r^2) [p]``)."""
    curve = hopf_curve(double_hopf(a), np.zeros(4), {"mu1": -0.3, "mu2": -0.4}, "mu1", "mu2",
                       [(-1, 0.3), (-1, 0.5)])
    (hh,) = curve.special("hh")
    assert hh.status == "converged" and abs(hh.params["mu2"]) < 1e-10
    d = hh.data
    assert (d["omega1"], d["omega2"]) == pytest.approx((1.0, 1.7), rel=1e-10)
    p = {k: 2 * a[i][j].real for k, (i, j) in
         {"p11": (0, 0), "p12": (0, 1), "p21": (1, 0), "p22": (1, 1)}.items()}
    assert {k: d[k] for k in p} == pytest.approx(p, rel=1e-9)
    assert d["theta"] == pytest.approx(p["p12"] / p["p22"], rel=1e-9)
    assert d["delta"] == pytest.approx(p["p21"] / p["p11"], rel=1e-9)
    assert (d["simple"], d["stable_torus"]) == (simple, torus)


@pytest.mark.parametrize("theta", [0.8, -1.2])
def test_zero_hopf_on_the_normal_form(theta):
    """``xi' = b1 + xi^2 - |w|^2``, ``w' = (b2 + i omega + (theta + 0.4 i) xi) w``:
    equilibria ``w = 0, xi = +-sqrt(-b1)`` with eigenvalues ``2 xi`` and ``b2 + theta xi
    +- i omega``; the Hopf curve ``b2 = -theta xi``, ``b1 = -b2^2 / theta^2`` passes the
    zero-Hopf point ``b1 = b2 = 0`` where the real eigenvalue ``2 xi`` crosses zero. Its
    normal form is the system itself: ``B = 1``, ``C = -2``, ``D = theta + 0.4 i``."""
    x, p = ca.SX.sym("x", 3), ca.SX.sym("p", 2)
    xi, s2, omega = x[0], x[1] ** 2 + x[2] ** 2, 1.3
    re, im = p[1] + theta * xi, omega + 0.4 * xi
    F = ca.Function("F", [x, p], [ca.vertcat(p[0] + xi ** 2 - s2, re * x[1] - im * x[2],
                                             im * x[1] + re * x[2])])
    b1 = -0.25
    curve = hopf_curve(F, [-0.5, 0.0, 0.0], {"b1": b1, "b2": 0.5 * theta - 0.2}, "b2", "b1",
                       [(-2, 2), (-1, 0.01)], max_steps=200)
    (zh,) = curve.special("zh")
    assert zh.status == "converged"
    assert abs(zh.params["b1"]) < 1e-10 and abs(zh.params["b2"]) < 1e-8
    assert abs(zh.x[0]) < 1e-8 and zh.data["omega"] == pytest.approx(omega, rel=1e-8)
    b1, b2 = curve.par("b1"), curve.par("b2")
    assert np.max(np.abs(b1 + b2 ** 2 / theta ** 2)) < 1e-10
    assert b2.min() < -0.1 and b2.max() > 0.1       # through the point, on both sides
    # the fold curve b1 = 0 (xi = 0) meets the same point where Re = b2 crosses zero
    prob = C.EquilibriumProblem(F, [-0.5, 0.0, 0.0], {"b1": -0.25, "b2": -0.3}, "b1")
    (fold,) = run(prob, bounds={"b1": (-1, 0.5)}).special("fold")
    folds = run(C.FoldCurveProblem.from_point(prob, fold, "b2"), bounds={"b2": (-1, 1)})
    (zh2,) = folds.special("zh")
    assert zh2.status == "converged" and abs(zh2.params["b2"]) < 1e-8
    assert zh2.data["omega"] == pytest.approx(omega, rel=1e-8)
    for point in (zh, zh2):    # u = xi, |w|^2 = 2 |z|^2 (|q| = 1), D = d lambda / d xi
        d = point.data
        assert (d["B"], d["C"], d["D_re"], d["D_im"]) == pytest.approx((1, -2, theta, 0.4),
                                                                       abs=1e-7)
        assert d["s"] == -1 and d["theta"] == pytest.approx(theta, abs=1e-7)


def branch_point(F, x0, mu0, bounds=(-1.0, 1.0)):
    problem = C.EquilibriumProblem(F, x0, {"mu": mu0}, "mu")
    branch = run(problem, ds=0.1, ds_max=0.1, max_steps=60, bounds={"mu": bounds})
    (bp,) = [b for b in branch.special("bp") if b.status == "converged"]
    return problem, bp


def switched(problem, bp, amplitude):
    new = C.equilibrium_from_bp(problem, bp, amplitude=amplitude)
    return run(new, ds=0.05, ds_max=0.1, max_steps=60, bounds={"mu": (-1.0, 1.0)})


@pytest.mark.parametrize("amplitude", [0.02, -0.02])
def test_switching_at_a_transcritical_point_both_ways(amplitude):
    """``x' = mu x - x^2 + x y``, ``y' = -y + x^2``: the branches ``x = y = 0`` and
    ``mu = x - x^2, y = x^2`` cross at ``mu = 0``; from either one the switch lands on
    the other, on the side of the amplitude's sign."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    F = ca.Function("F", [x, p], [ca.vertcat(p[0] * x[0] - x[0] ** 2 + x[0] * x[1],
                                             -x[1] + x[0] ** 2)])
    problem, bp = branch_point(F, [0.0, 0.0], -0.5)          # from the trivial branch
    assert abs(bp.params["mu"]) < 1e-10
    other = switched(problem, bp, amplitude)
    u, mu = other.x[:, 0], other.par("mu")
    assert other.status == "bound" and np.all(np.sign(u[1:]) == np.sign(amplitude))
    assert np.max(np.abs(mu - u + u ** 2)) < 1e-9 and np.allclose(other.x[:, 1], u ** 2)
    x0 = (1 - np.sqrt(3)) / 2                                 # mu = -0.5 on x - x^2
    problem, bp = branch_point(F, [x0, x0 ** 2], -0.5, (-1.0, 0.2))
    back = switched(problem, bp, amplitude)
    assert back.status == "bound" and np.max(np.abs(back.x)) < 1e-9
    assert np.all(np.sign(np.diff(back.par("mu"))) == np.sign(amplitude))


@pytest.mark.parametrize("amplitude", [0.02, -0.02])
def test_switching_at_a_pitchfork_onto_both_halves(amplitude):
    """``x' = mu x - x^3 + x y``, ``y' = -2 y + x^2``: the new branch ``mu = x^2 / 2``,
    ``y = x^2 / 2`` (``x = +-sqrt(2 mu)``), on the side of the amplitude's sign."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    F = ca.Function("F", [x, p], [ca.vertcat(p[0] * x[0] - x[0] ** 3 + x[0] * x[1],
                                             -2 * x[1] + x[0] ** 2)])
    problem, bp = branch_point(F, [0.0, 0.0], -0.5)
    other = switched(problem, bp, amplitude)
    u, mu = other.x[:, 0], other.par("mu")
    assert other.status == "bound" and mu[-1] > 0.9
    assert np.all(np.sign(u) == np.sign(amplitude))
    assert np.max(np.abs(mu - u ** 2 / 2)) < 1e-9 and np.allclose(other.x[:, 1], u ** 2 / 2)
    reloaded = dataclasses.replace(bp, tangent=np.zeros(0))   # as from Branch.load
    assert np.allclose(switched(problem, reloaded, amplitude).x, other.x)


@pytest.mark.parametrize("s", [1.0, -1.0])
def test_bogdanov_takens_coefficients_on_hopf_and_fold_curves(s):
    """``x' = y``, ``y' = b1 + b2 x + x^2 + s x y`` is the normal form itself (``q0 = e1``,
    ``q1 = e2``): ``a = 1``, ``b = s``; the Hopf curve ``b1 = 0, b2 < 0`` and the fold
    curve ``b1 = b2^2 / 4`` end at ``b1 = b2 = 0``."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    F = ca.Function("F", [x, p], [ca.vertcat(x[1], p[0] + p[1] * x[0] + x[0] ** 2
                                             + s * x[0] * x[1])])
    x0 = (1 - np.sqrt(3)) / 2  # root of x^2 - x - 1/2 (b1 = -1/2, b2 = -1)
    prob = C.EquilibriumProblem(F, [x0, 0.0], {"b1": -0.5, "b2": -1.0}, "b1")
    branch = run(prob, bounds={"b1": (-1, 0.3)})
    for kind, cls in (("hopf", C.HopfCurveProblem), ("fold", C.FoldCurveProblem)):
        (point,) = branch.special(kind)
        curve = run(cls.from_point(prob, point, "b2"), bounds={"b2": (-1.5, 0.5)})
        (bt,) = curve.special("bt")
        assert abs(bt.params["b1"]) < 1e-8 and abs(bt.params["b2"]) < 1e-8
        assert (bt.data["a"], bt.data["b"]) == pytest.approx((1.0, s), abs=1e-7)


def test_bogdanov_takens_coefficients_after_a_change_of_coordinates():
    """The normal form ``y1' = y2, y2' = b1 + b2 y1 + y1^2 - y1 y2 + 0.7 y1 y3`` with a
    stable ``y3' = -2 y3 + y1^2`` (cubic on the centre manifold: ``a, b`` unchanged),
    sheared (``u2 = y2 + y1^2 / 2``) and rotated (``x = Q^T u``): ``(a, b) = sigma (1, -1)``
    with ``q0 = sigma Q^T e1`` (its largest entry positive)."""
    Q = np.linalg.qr(np.random.default_rng(0).standard_normal((3, 3)))[0]
    x, p = ca.SX.sym("x", 3), ca.SX.sym("p", 2)
    u = ca.mtimes(ca.DM(Q), x)
    y = ca.vertcat(u[0], u[1] - 0.5 * u[0] ** 2, u[2])
    g = ca.vertcat(y[1], p[0] + p[1] * y[0] + y[0] ** 2 - y[0] * y[1] + 0.7 * y[2] * y[0],
                   -2 * y[2] + y[0] ** 2)
    F = ca.Function("F", [x, p], [ca.mtimes(ca.DM(Q.T), ca.vertcat(g[0], g[1] + y[0] * g[0],
                                                                    g[2]))])
    prob = C.EquilibriumProblem(F, np.zeros(3), {"b1": 0.0, "b2": -1.0}, "b1")
    (fold,) = run(prob, bounds={"b1": (-1, 0.3)}).special("fold")
    curve = run(C.FoldCurveProblem.from_point(prob, fold, "b2"), bounds={"b2": (-1.5, 0.5)})
    (bt,) = curve.special("bt")
    sigma = np.sign(Q[0][np.argmax(np.abs(Q[0]))])
    assert (bt.data["a"], bt.data["b"]) == pytest.approx((sigma, -sigma), abs=1e-7)
