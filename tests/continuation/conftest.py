"""Small models with known answers, shared by the continuation tests."""

import casadi as ca
import numpy as np

import continuation as C


def scalar(expr_fun, n_par=1):
    x, p = ca.SX.sym("x", 1), ca.SX.sym("p", n_par)
    return ca.Function("F", [x, p], [expr_fun(x[0], p)])


def brusselator():
    """x' = A - (B+1) x + x^2 y, y' = B x - x^2 y; p = (A, B)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    A, B = p[0], p[1]
    u, v = x[0], x[1]
    return ca.Function("F", [x, p], [ca.vertcat(A - (B + 1) * u + u ** 2 * v,
                                                 B * u - u ** 2 * v)])


def hopf_normal_form(coef):
    """x' = mu x - w y + f2 + f3, y' = w x + mu y + g2 + g3; p = (mu, w).

    coef = dict(a1, a2, a3 (x^2, xy, y^2 in f), b1, b2, b3 (in g),
                c1, c2 (x^3, x y^2 in f), d1, d2 (x^2 y, y^3 in g)).
    """
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    X, Y = x[0], x[1]
    mu, w = p[0], p[1]
    k = coef
    f = k["a1"] * X**2 + k["a2"] * X * Y + k["a3"] * Y**2 + k["c1"] * X**3 + k["c2"] * X * Y**2
    g = k["b1"] * X**2 + k["b2"] * X * Y + k["b3"] * Y**2 + k["d1"] * X**2 * Y + k["d2"] * Y**3
    return ca.Function("F", [x, p], [ca.vertcat(mu * X - w * Y + f, w * X + mu * Y + g)])


def guckenheimer_holmes_a(k, w):
    """Guckenheimer-Holmes (3.4.11) coefficient a for x' = -w y + f, y' = w x + g."""
    fxx, fxy, fyy = 2 * k["a1"], k["a2"], 2 * k["a3"]
    gxx, gxy, gyy = 2 * k["b1"], k["b2"], 2 * k["b3"]
    fxxx, fxyy, gxxy, gyyy = 6 * k["c1"], 2 * k["c2"], 2 * k["d1"], 6 * k["d2"]
    return (fxxx + fxyy + gxxy + gyyy) / 16 + (
        fxy * (fxx + fyy) - gxy * (gxx + gyy) - fxx * gxx + fyy * gyy) / (16 * w)


def mass_model(with_q=False):
    """M(x) xdot = F(x, p) with c = (1, 1), y = x - c:

    F = (p y1 - y2 - y1 |y|^2 + y1 y2, y1 - y2 |y|^2 + y1^2),
    M(x) = [[1 + x1^2, x2], [0, 1 + x2^2]]  (M(c) = [[2, 1], [0, 2]]).
    The equilibrium is x = c for all p. M(c)^{-1} J(p) = [[p/2 - 1/4, -1/2],
    [1/2, 0]]: trace p/2 - 1/4, det 1/4, so the Hopf point is p = 1/2 with
    omega = 1/2 (with M = I it would be p = 0, omega = 1).
    with_q: p = (p, q) and M22 = q + x2^2, M(c) = [[2, 1], [0, q + 1]]; then
    M(c)^{-1} J = [[p/2 - 1/(2(q+1)), -1/2], [1/(q+1), 0]] and the Hopf curve is
    p = 1/(1+q), omega = (2 (1+q))^{-1/2}.
    """
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2 if with_q else 1)
    q = p[1] if with_q else 1
    y1, y2 = x[0] - 1, x[1] - 1
    r2 = y1**2 + y2**2
    F = ca.Function("F", [x, p], [ca.vertcat(p[0] * y1 - y2 - y1 * r2 + y1 * y2,
                                             y1 - y2 * r2 + y1**2)])
    M = ca.Function("M", [x, p], [ca.vertcat(ca.horzcat(1 + x[0]**2, x[1]),
                                             ca.horzcat(0, q + x[1]**2))])
    return F, M


def van_der_pol():
    """x'' - mu (1 - x^2) x' + x = 0 as a first-order system; p = (mu,)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    return ca.Function("F", [x, p], [ca.vertcat(x[1], p[0] * (1 - x[0] ** 2) * x[1] - x[0])])


def van_der_pol_guess(t):
    """The harmonic guess of radius 2 at phase t in [0, 1]."""
    t = np.atleast_1d(t)
    return np.c_[2 * np.cos(2 * np.pi * t), -2 * np.sin(2 * np.pi * t)]


def corrected(problem):
    """The unknowns of ``problem``'s start guess after the first corrector."""
    step = C.ContinuationIterator(problem, C.PALC(), C.ContinuationSettings()).start()
    assert step is not None
    return step.X


def benchmark(name):
    """The script ``benchmarks/<name>.py`` as a module (scripts are not a package)."""
    import importlib.util
    import pathlib
    path = pathlib.Path(__file__).parents[2] / "benchmarks" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def half_twisted(n_par=1, rate=lambda p: p[0]):
    """The half-twisted cycle of test_cycles_pd (a period doubling where ``rate(p)``,
    default mu = p[0], crosses 0): the circle r = 1, z = 0 has the multipliers 1,
    -exp(2 pi rate), -exp(-2 pi)."""
    X, p = ca.SX.sym("x", 3), ca.SX.sym("p", n_par)
    x, y, z = X[0], X[1], X[2]
    r = ca.sqrt(x ** 2 + y ** 2)
    c, s = x / r, y / r
    v = ca.vertcat(r - 1, z)
    P = 0.5 * ca.vertcat(ca.horzcat(1 + c, s), ca.horzcat(s, 1 - c))
    Pv = ca.mtimes(P, v)
    dv = rate(p) * Pv - ca.dot(v, Pv) * Pv - (v - Pv) + 0.5 * ca.vertcat(-z, r - 1)
    return ca.Function("F", [X, p], [ca.vertcat(dv[0] * c - y, dv[0] * s + x, dv[1])])


import types

import pytest


@pytest.fixture(scope="session")
def models():
    """The model builders above, as a namespace (tests import nothing local)."""
    return types.SimpleNamespace(
        scalar=scalar, brusselator=brusselator, hopf_normal_form=hopf_normal_form,
        guckenheimer_holmes_a=guckenheimer_holmes_a, mass_model=mass_model,
        van_der_pol=van_der_pol, van_der_pol_guess=van_der_pol_guess, corrected=corrected,
        benchmark=benchmark, half_twisted=half_twisted)


def brusselator_cycles():
    """A cycle problem of the Brusselator from its Hopf point (NTST = 20, NCOL = 4) and a
    PALC iterator on it (4 steps)."""
    eq = C.EquilibriumProblem(brusselator(), [1, 2.5], {"A": 1.0, "B": 2.5}, "B")
    (hopf,) = C.continuation(eq, settings=C.ContinuationSettings(
        ds=0.05, bounds={"B": (1.5, 2.5)}, direction=-1)).special("hopf")
    cyc = C.cycle_from_hopf(eq, hopf, dp=1e-2, settings=C.CollocationSettings(ntst=20, ncol=4))
    it = C.ContinuationIterator(cyc, C.PALC(), C.ContinuationSettings(
        ds=0.1, max_steps=4, direction=cyc.hopf_direction))
    return cyc, it


def ring(theta_gain=0.0, radial=1.0):
    """r' = radial r (1 - r^2), theta' = 1 + e cos(theta) (e = p[0]).

    Cycle r = 1 with period 2 pi / sqrt(1 - e^2), non-trivial multiplier
    exp(-2 radial T); the speed along the cycle is non-uniform for e != 0.
    """
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    r2 = x[0] ** 2 + x[1] ** 2
    th = 1 + p[0] * x[0] / ca.sqrt(r2)
    g = radial * (1 - r2)
    return ca.Function("F", [x, p], [ca.vertcat(g * x[0] - x[1] * th, g * x[1] + x[0] * th)])


def circle(t):
    """The unit circle at phases ``t`` in [0, 1)."""
    return np.c_[np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)]


def cycle_from_circle(F, e, ntst, ncol, period, M=None, floquet="auto"):
    """The corrected cycle of ``F`` (parameter ``e``) from the unit circle: ``(problem, X)``."""
    prob = C.CycleProblem(F, circle, period, {"e": e}, "e", M=M,
                          settings=C.CollocationSettings(ntst=ntst, ncol=ncol, floquet=floquet))
    step = C.ContinuationIterator(prob, C.PALC(), C.ContinuationSettings()).start()
    assert step is not None
    return prob, step.X


def window_oscillator(eps: float):
    """u' = a u - v - u r^2, v' = u + a v - v r^2 with a = eps - (mu - 1)^2: the origin is
    unstable only for |mu - 1| < sqrt(eps) (Hopf points at 1 -+ sqrt(eps), omega = 1)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    a = eps - (p[0] - 1) ** 2
    r2 = x[0] ** 2 + x[1] ** 2
    return ca.Function("F", [x, p], [ca.vertcat(a * x[0] - x[1] - x[0] * r2,
                                                x[0] + a * x[1] - x[1] * r2)])


def galerkin(n=6, K=9, seed=0):
    """``F = A(p) x + P g(z)``, ``z = (L1 x, L2 x)``, ``g`` nodal in two variables, and a
    state-dependent mass ``M = I + P_m diag(1 + 0.1 z1^2) L1``; returns the pieces, and
    ``by_ad``: the lifted ``dF/dx`` and ``M`` each beside AD of the field."""
    rng = np.random.default_rng(seed)
    L = rng.normal(size=(2 * K, n)) * (rng.random((2 * K, n)) < 0.7)   # some exact zeros
    P = rng.normal(size=(n, 2 * K)) / K
    Pm = rng.normal(size=(n, K)) / K
    x, p, v = ca.MX.sym("x", n), ca.MX.sym("p", 2), ca.MX.sym("v", n)
    z = ca.MX.sym("z", 2 * K)
    z1, z2 = z[:K], z[K:]
    g = ca.vertcat(p[0] * ca.sin(z1) * z2, z1 ** 2 - p[1] * ca.tanh(z2))
    lift = lambda e: ca.substitute(e, z, ca.mtimes(ca.DM(L), x))
    A = ca.diag(-1 - p[1] * ca.DM(np.arange(n)))
    F = ca.mtimes(A, x) + ca.mtimes(ca.DM(P), lift(g))
    m = 1 + 0.1 * z1 ** 2
    M = ca.DM.eye(n) + ca.mtimes(ca.DM(Pm), ca.mtimes(ca.diag(lift(m)), ca.DM(L[:K])))
    jac = C.Lifted(ca.Function("D", [x, p], [lift(ca.jacobian(g, z))]), P, L,
                   ca.Function("A", [p], [A]))
    mass = C.Lifted(ca.Function("Dm", [x, p], [lift(ca.diag(m))]), Pm, L[:K],
                    ca.Function("I", [p], [ca.DM.eye(n)]))
    Mv = ca.mtimes(M, v)
    mvx = ca.jacobian(Mv, x)
    by_ad = ((jac, ca.Function("J", [x, p], [ca.jacobian(F, x)])),
             (mass, ca.Function("M", [x, p], [M])))
    return dict(x=x, p=p, v=v, F=F, M=M, Mv=Mv, jac=jac, mass=mass, mvx=mvx, n=n, by_ad=by_ad)


def van_der_pol_ring(n=6):
    """``n / 2`` Van der Pol oscillators ``u' = v``, ``v' = mu (1 - u^2) v - u + k (mean -
    u)`` coupled all-to-all (dense interval blocks, no band), ``p = (mu, k)``."""
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", 2)
    u, v = x[0::2], x[1::2]
    mean = ca.sum1(u) / (n // 2)
    f = ca.vertcat(*[ca.vertcat(v[i], p[0] * (1 - u[i] ** 2) * v[i] - u[i]
                                + p[1] * (mean - u[i])) for i in range(n // 2)])
    return ca.Function("F", [x, p], [f])
