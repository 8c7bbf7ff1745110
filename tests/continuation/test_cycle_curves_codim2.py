"""Codimension-two points on curves of cycles (fold, period doubling, torus): a cycle
with transverse blocks whose Floquet multipliers are closed forms, so every point is
known in advance.

The base is the circle of ``x' = g x - y, y' = x + g y`` (``g = g(rho, p)``, ``rho =
x^2 + y^2``, period 2 pi); appended, decoupled from it (their states vanish on the
cycle), are a scalar ``w' = d w`` (multiplier ``e^{2 pi d}``), a rotation ``z' = [[c, -k],
[k, c]] z`` (``e^{2 pi (c +- i k)}``), and a half-twisted plane whose frame turns by
half the cycle's angle: ``z' = ((a + b)/2 I + (a - b)/2 S(theta) + J/2) z``, ``S =
[[cos, sin], [sin, -cos]]``, which is ``R(theta/2) diag(a, b) R(-theta/2)`` in the turning
frame, so after one period ``-e^{2 pi a}``, ``-e^{2 pi b}``."""

import casadi as ca
import numpy as np
import pytest

import continuation as C

SETTINGS = C.CollocationSettings(ntst=16, ncol=4)


def _field(g, scalars=(), rotations=(), twisted=()):
    """The base circle of ``g(rho, p)`` with the blocks: ``scalars`` (d(p)), ``rotations``
    ((c(p), k(p))), ``twisted`` ((a(p), b(p))); ``p`` has two entries."""
    n = 2 + len(scalars) + 2 * len(rotations) + 2 * len(twisted)
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", 2)
    rho = x[0] ** 2 + x[1] ** 2
    r = ca.sqrt(rho)
    cos, sin = x[0] / r, x[1] / r
    G = g(rho, p)
    out, i = [G * x[0] - x[1], x[0] + G * x[1]], 2
    for d in scalars:
        out.append(d(p) * x[i])
        i += 1
    for c, k in rotations:
        out += [c(p) * x[i] - k(p) * x[i + 1], k(p) * x[i] + c(p) * x[i + 1]]
        i += 2
    for a, b in twisted:
        mean, half = (a(p) + b(p)) / 2, (a(p) - b(p)) / 2
        z1, z2 = x[i], x[i + 1]
        out += [mean * z1 + half * (cos * z1 + sin * z2) - z2 / 2,
                mean * z2 + half * (sin * z1 - cos * z2) + z1 / 2]
        i += 2
    return ca.Function("F", [x, p], [ca.vertcat(*out)]), n


def _start(F, n, radius, params, active, condition):
    """The special cycle of ``condition`` near the circle of ``radius``, located."""
    def orbit(t):
        t = np.atleast_1d(t) + 0.013
        return np.c_[radius * np.cos(2 * np.pi * t), radius * np.sin(2 * np.pi * t),
                     np.zeros((t.size, n - 2))]
    cycle = C.CycleProblem(F, orbit, 2 * np.pi, params, active, settings=SETTINGS)
    X = C.ContinuationIterator(cycle, C.PALC(), C.ContinuationSettings()).start().X
    square, located = C.locate_cycle(cycle, X, condition)
    assert located.converged
    return square, located.X


def _curve(square, X, second, condition, bounds, direction=1):
    curve = C.CycleCurveProblem(square, X, (square.active, second), condition)
    return C.continuation(curve, settings=C.ContinuationSettings(
        ds=0.02, ds_max=0.05, max_steps=300, bounds=bounds, locate_tol=1e-9,
        direction=direction))


def _found(branch, kinds=None):
    return {(sp.kind, round(sp.params["q"], 4)) for sp in branch.special_points
            if sp.kind != "fold" and (kinds is None or sp.kind in kinds)}


def test_fold_curve_codim_two_points_at_their_closed_forms():
    """g = b + q s - s^3, s = rho - 1: folds where q = 3 s^2, b = -2 s^3, a cusp at
    b = q = 0 (s = 0). Along the curve (s from -0.6 up): the scalar crosses +1 at b =
    0.12 (R1), the twisted plane -1 at b = 0.03 (fold-flip), the rotation the circle at
    b = -0.06 (fold-Neimark-Sacker)."""
    F, n = _field(lambda rho, p: p[0] + p[1] * (rho - 1) - (rho - 1) ** 3,
                  scalars=[lambda p: p[0] - 0.12], rotations=[(lambda p: p[0] + 0.06,
                                                               lambda p: 0.3)],
                  twisted=[(lambda p: p[0] - 0.03, lambda p: -1.0)])
    q0, s1 = 1.08, -0.64                       # a cycle at s1, its fold at s = -0.6
    square, X = _start(F, n, np.sqrt(1 + s1), {"b": s1 ** 3 - q0 * s1, "q": q0}, "b",
                       C.CycleFold())
    branch = _curve(square, X, "q", C.CycleFold(), {"q": (-0.1, 1.2)}, direction=-1)
    points = {sp.kind: sp for sp in branch.special_points if sp.kind != "fold"}
    assert set(points) == {"r1", "lppd", "cpc", "lpns"}, branch.special_points
    for kind, b in (("r1", 0.12), ("lppd", 0.03), ("cpc", 0.0), ("lpns", -0.06)):
        sp = points[kind]
        s = -np.cbrt(b / 2)
        assert sp.status == "converged"
        assert abs(sp.params["b"] - b) < 1e-7 and abs(sp.params["q"] - 3 * s ** 2) < 1e-6
    assert abs(points["r1"].data["multiplier_re"] - 1) < 1e-7
    assert abs(points["lppd"].data["multiplier_re"] + 1) < 1e-7
    mu = complex(points["lpns"].data["multiplier_re"], points["lpns"].data["multiplier_im"])
    assert abs(mu - np.exp(2j * np.pi * 0.3)) < 1e-7
    order = [sp.kind for sp in branch.special_points if sp.kind != "fold"]
    assert order == ["r1", "lppd", "cpc", "lpns"]


def test_period_doubling_curve_codim_two_points():
    """The unit circle (g = 1 - rho) with a twisted plane a = m (PD on m = 0 for every
    q), b = q - 0.7 (a second -1: R2 at q = 0.7); the scalar crosses +1 at q = 0.45
    (fold-flip), the rotation the circle at q = 0.2 (flip-Neimark-Sacker)."""
    F, n = _field(lambda rho, p: 1 - rho, scalars=[lambda p: p[1] - 0.45],
                  rotations=[(lambda p: p[1] - 0.2, lambda p: 0.27)],
                  twisted=[(lambda p: p[0], lambda p: p[1] - 0.7)])
    square, X = _start(F, n, 1.0, {"m": 0.02, "q": 0.05}, "m", C.PeriodDoubling())
    branch = _curve(square, X, "q", C.PeriodDoubling(), {"q": (0.0, 0.85)})
    assert np.max(np.abs(branch.par("m"))) < 1e-9
    assert [(k, q) for k, q in sorted(_found(branch), key=lambda f: f[1])] == \
        [("pdns", 0.2), ("lppd", 0.45), ("r2", 0.7)]
    for sp in branch.special_points:
        if sp.kind != "fold":
            assert sp.status == "converged"
            assert abs(sp.params["q"] - {"pdns": 0.2, "lppd": 0.45, "r2": 0.7}[sp.kind]) < 1e-8


def test_torus_curve_codim_two_points_and_resonances():
    """The unit circle with the rotation c = m, k = q: a torus curve m = 0 whose pair
    e^{+-2 pi i q} passes the 1:4 (q = 1/4) and 1:3 (q = 1/3) resonances; the scalar
    crosses +1 at q = 0.1 (fold-NS), the twisted plane -1 at q = 0.15 (flip-NS), a second
    rotation the circle at q = 0.3 (double NS)."""
    F, n = _field(lambda rho, p: 1 - rho, scalars=[lambda p: p[1] - 0.1],
                  rotations=[(lambda p: p[0], lambda p: p[1]),
                             (lambda p: p[1] - 0.3, lambda p: 0.13)],
                  twisted=[(lambda p: p[1] - 0.15, lambda p: -1.0)])
    square, X = _start(F, n, 1.0, {"m": 0.02, "q": 0.05}, "m", C.NeimarkSacker())
    branch = _curve(square, X, "q", C.NeimarkSacker(), {"q": (0.0, 0.42)})
    assert np.max(np.abs(branch.par("m"))) < 1e-9
    expected = {"lpns": 0.1, "pdns": 0.15, "r4": 0.25, "nsns": 0.3, "r3": 1 / 3}
    assert sorted(_found(branch), key=lambda f: f[1]) == \
        [(k, round(q, 4)) for k, q in expected.items()]
    for sp in branch.special_points:
        if sp.kind != "fold":
            assert sp.status == "converged" and abs(sp.params["q"] - expected[sp.kind]) < 1e-8
    r4 = next(sp for sp in branch.special_points if sp.kind == "r4")
    assert abs(complex(r4.data["multiplier_re"], r4.data["multiplier_im"]) - 1j) < 1e-8


def test_no_codim_two_points_without_the_multipliers():
    F, n = _field(lambda rho, p: 1 - rho, scalars=[lambda p: p[1] - 0.45],
                  twisted=[(lambda p: p[0], lambda p: -1.0)])
    square, X = _start(F, n, 1.0, {"m": 0.02, "q": 0.3}, "m", C.PeriodDoubling())
    curve = C.CycleCurveProblem(square, X, ("m", "q"), C.PeriodDoubling())
    branch = C.continuation(curve, settings=C.ContinuationSettings(
        ds=0.02, ds_max=0.05, max_steps=40, bounds={"q": (0.0, 0.6)},
        compute_eigenvalues=False))
    assert not [sp for sp in branch.special_points if sp.kind != "fold"]


def test_grazing_curve_meets_a_fold_of_cycles_curve():
    """The circle of radius sqrt(b) (g = b - rho) grazes the wall x = -0.9 on b = 0.81,
    for every q; the scalar's multiplier crosses +1 at q = 0.3: there the grazing curve
    meets a curve of folds (branch points) of cycles ('lpc'), and the rotation's pair
    crosses the circle at q = 0.5 ('ns')."""
    F, n = _field(lambda rho, p: p[0] - rho, scalars=[lambda p: p[1] - 0.3],
                  rotations=[(lambda p: p[1] - 0.5, lambda p: 0.21)])
    wall = C.Extremum(rows=[[1.0, 0.0, 0.0, 0.0, 0.0]], level=-0.9)
    square, X = _start(F, n, 0.85, {"b": 0.7225, "q": 0.1}, "b", wall)
    branch = _curve(square, X, "q", wall, {"q": (0.0, 0.7)})
    assert np.max(np.abs(branch.par("b") - 0.81)) < 1e-8
    found = {sp.kind: sp for sp in branch.special_points if sp.kind != "fold"}
    assert set(found) == {"lpc", "ns"}
    assert abs(found["lpc"].params["q"] - 0.3) < 1e-8 and abs(found["ns"].params["q"] - 0.5) < 1e-8


def _turning(k, z1, z2, cos, sin, first=True):
    """``cos(phi) zt^k`` (``first``) or ``sin(phi) zt^k`` with ``zt = cos(phi) z1 +
    sin(phi) z2``, ``phi = theta / 2``, ``k`` odd: a polynomial in ``cos(phi), sin(phi)``
    of even degree, written in ``cos theta, sin theta`` (single-valued on the plane)."""
    from math import comb
    c2, s2, cs = (1 + cos) / 2, (1 - cos) / 2, sin / 2
    out = 0
    for m in range(k + 1):                       # zt^k = sum C(k, m) (c z1)^(k-m) (s z2)^m
        i, j = k - m + (1 if first else 0), m + (0 if first else 1)
        low = min(i, j)
        rest = (c2 ** ((i - low) // 2)) * (s2 ** ((j - low) // 2))
        out = out + comb(k, m) * z1 ** (k - m) * z2 ** m * cs ** low * rest
    return out


def _flip_family(gamma=0.3, lam=1.0):
    """The unit circle with a half-twisted plane whose turning-frame coordinates follow
    ``zt1' = a zt1 + q zt1^3 - zt1^5 + gamma zt1 y``, ``zt2' = -zt2``, and a scalar
    ``y' = -lam y + zt1^2``. The plane's multipliers are ``-e^{2 pi a}``, ``-e^{-2 pi}``:
    period doubling on ``a = 0``. The doubled cycles are the turning frame's equilibria,
    ``a + (q + gamma / lam) zt1^2 - zt1^4 = 0``: sub- or supercritical by the sign of
    ``q + gamma / lam``, a generalized period doubling at ``q = -gamma / lam``."""
    x, p = ca.SX.sym("x", 5), ca.SX.sym("p", 2)
    rho = x[0] ** 2 + x[1] ** 2
    r = ca.sqrt(rho)
    cos, sin = x[0] / r, x[1] / r
    z1, z2, y = x[2], x[3], x[4]
    a, b, q = p[0], -1.0, p[1]
    mean, half = (a + b) / 2, (a - b) / 2
    lin1 = mean * z1 + half * (cos * z1 + sin * z2) - z2 / 2
    lin2 = mean * z2 + half * (sin * z1 - cos * z2) + z1 / 2
    # R(phi) (q zt^3 - zt^5 + gamma zt y, 0): cos(phi) and sin(phi) times the scalar
    nl = [q * _turning(3, z1, z2, cos, sin, f) - _turning(5, z1, z2, cos, sin, f)
          + gamma * y * _turning(1, z1, z2, cos, sin, f) for f in (True, False)]
    zt1_sq = (1 + cos) / 2 * z1 ** 2 + sin * z1 * z2 + (1 - cos) / 2 * z2 ** 2
    g = 1 - rho
    F = ca.vertcat(g * x[0] - x[1], x[0] + g * x[1], lin1 + nl[0], lin2 + nl[1],
                   -lam * y + zt1_sq)
    return ca.Function("F", [x, p], [F]), 5


def test_period_doubling_curve_generalized_period_doubling():
    """On the doubling curve a = 0 of :func:`_flip_family`, the doubled cycles' cubic
    coefficient changes sign at q = -gamma/lam = -0.3 (gamma = 0.3, lam = 1): the
    generalized period doubling; with gamma = 0 it moves to q = 0 (the coupling through
    the second-order term h2 is what moves it)."""
    for gamma, expected in ((0.3, -0.3), (0.0, 0.0)):
        F, n = _flip_family(gamma)
        square, X = _start(F, n, 1.0, {"a": 0.02, "q": -0.6}, "a", C.PeriodDoubling())
        branch = _curve(square, X, "q", C.PeriodDoubling(), {"q": (-0.7, 0.2)})
        assert np.max(np.abs(branch.par("a"))) < 1e-9
        found = [sp for sp in branch.special_points if sp.kind != "fold"]
        assert [sp.kind for sp in found] == ["gpd"], found
        assert found[0].status == "converged" and abs(found[0].params["q"] - expected) < 1e-9


def _torus_family(gamma, eps, delta, k=0.23):
    """The unit circle with a decoupled complex ``w`` and its slaves: ``w' = (m + i k) w
    + (q + i delta) w |w|^2 - w |w|^4 + gamma w s + eps conj(w) z``, ``s' = -s + |w|^2``,
    ``z' = -z + w^2``. A torus bifurcation on ``m = 0`` (the pair ``e^{2 pi (m +- i k)}``);
    on the invariant circle ``s = |w|^2`` and ``z = w^2 / (1 + 2 i k)``, so the cubic
    coefficient is ``q + i delta + gamma + eps / (1 + 2 i k)``: a Chenciner point where
    its real part vanishes, ``q = -gamma - eps / (1 + 4 k^2)``."""
    x, p = ca.SX.sym("x", 7), ca.SX.sym("p", 2)
    rho = x[0] ** 2 + x[1] ** 2
    w1, w2, s, z1, z2 = x[2], x[3], x[4], x[5], x[6]
    m, q = p[0], p[1]
    r2 = w1 ** 2 + w2 ** 2
    a, b = m + q * r2 - r2 ** 2 + gamma * s, k + delta * r2    # (a + i b) w
    cz1, cz2 = w1 * z1 + w2 * z2, w1 * z2 - w2 * z1             # conj(w) z
    g = 1 - rho
    F = ca.vertcat(g * x[0] - x[1], x[0] + g * x[1],
                   a * w1 - b * w2 + eps * cz1, a * w2 + b * w1 + eps * cz2,
                   -s + r2, -z1 + w1 ** 2 - w2 ** 2, -z2 + 2 * w1 * w2)
    return ca.Function("F", [x, p], [F]), 7


@pytest.mark.parametrize("gamma, eps, delta", [(0.2, 0.5, 0.7), (0.0, 0.0, -0.4)])
def test_torus_curve_chenciner_point(gamma, eps, delta):
    """The Chenciner point of :func:`_torus_family` at ``q = -gamma - eps / (1 + 4 k^2)``:
    the slaves move it through the second-order solutions (``s`` through the periodic
    ``h11``, ``z`` through ``h20``, twisted by ``mu^2``), ``delta`` tests the phase of the
    coefficient."""
    k = 0.23
    F, n = _torus_family(gamma, eps, delta, k)
    expected = -gamma - eps / (1 + 4 * k ** 2)
    square, X = _start(F, n, 1.0, {"m": 0.02, "q": expected - 0.3}, "m", C.NeimarkSacker())
    branch = _curve(square, X, "q", C.NeimarkSacker(), {"q": (expected - 0.35, expected + 0.3)})
    assert np.max(np.abs(branch.par("m"))) < 1e-9
    found = [sp for sp in branch.special_points if sp.kind != "fold"]
    assert [sp.kind for sp in found] == ["ch"], found
    assert found[0].status == "converged" and abs(found[0].params["q"] - expected) < 1e-8
