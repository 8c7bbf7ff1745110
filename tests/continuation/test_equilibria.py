"""Equilibrium branches: folds, branch points, Hopf points, l1, failures."""

import math

import casadi as ca
import numpy as np
import pytest

import continuation as C

from .conftest import window_oscillator



def settings(**kw):
    base = dict(ds=0.02, ds_max=0.1, max_steps=100)
    base.update(kw)
    return C.ContinuationSettings(**base)


def test_bratu_type_fold_located_and_passed(models):
    # 0 = mu e^x - x: fold where mu e^x = x and mu e^x = 1, i.e. x = 1, mu = 1/e.
    F = models.scalar(lambda x, p: p[0] * ca.exp(x) - x)
    br = C.continuation(C.EquilibriumProblem(F, [0.0], {"mu": 0.0}, "mu"),
                        settings=settings(max_steps=60))
    folds = br.special("fold")
    assert len(folds) == 1 and folds[0].status == "converged"
    assert abs(folds[0].x[0] - 1.0) < 1e-10
    assert abs(folds[0].params["mu"] - math.exp(-1)) < 1e-12
    mu, x = br.par("mu"), br.x[:, 0]
    # continued around the fold: beyond it the branch lies on x > 1 with mu decreasing
    assert x[-1] > 2.0 and mu[-1] < mu.max() - 0.1
    assert np.all(np.abs(mu * np.exp(x) - x) < 1e-9)
    # the lower branch is stable (eigenvalue mu e^x - 1 < 0), the upper unstable
    assert np.all(br.stable[x < 0.99]) and not np.any(br.stable[x > 1.01])


def test_fold_normal_form_coefficient(models):
    """On the centre manifold x = x0 + y v (|v| = 1): ydot = a y^2, a = F_xx / (2 m(x0)).

    mu e^x - x at the fold x = 1: F_xx = mu e^x = 1 -> a = 1/2; with the mass
    m(x) = 2 + x^2 (m(1) = 3): a = 1/6; mu - x^2 with m = 1: a = -1 (v = +1: the
    null vector is oriented with its largest entry positive).
    """
    x, p = ca.SX.sym("x", 1), ca.SX.sym("p", 1)
    cases = [(models.scalar(lambda x, p: p[0] * ca.exp(x) - x), None, 0.0, 0.5),
             (models.scalar(lambda x, p: p[0] * ca.exp(x) - x),
              ca.Function("M", [x, p], [2 + x[0] ** 2]), 0.0, 1 / 6),
             (models.scalar(lambda x, p: p[0] - x**2), None, 1.0, -1.0)]
    for F, M, x0, a in cases:
        mu0, direction = (0.0, 1) if x0 == 0.0 else (1.0, -1)
        br = C.continuation(C.EquilibriumProblem(F, [x0], {"mu": mu0}, "mu", M=M),
                            settings=settings(max_steps=60, direction=direction))
        (fold,) = br.special("fold")
        assert fold.data["a"] == pytest.approx(a, rel=1e-10)


def test_closed_curve_without_branch_jumping(models):
    # x^2 + mu^2 = 1: one and a half turns, folds at mu = +-1 (x = 0).
    F = models.scalar(lambda x, p: x**2 + p[0]**2 - 1)
    br = C.continuation(C.EquilibriumProblem(F, [0.9], {"mu": 0.0}, "mu"),
                        settings=settings(ds=0.05, ds_max=0.1, max_steps=100))
    x, mu = br.x[:, 0], br.par("mu")
    assert np.all(np.abs(x**2 + mu**2 - 1) < 1e-10)
    theta = np.unwrap(np.arctan2(mu, x))
    steps = np.diff(theta)
    assert np.all(steps > 0) and np.all(steps < 0.11)  # monotone, no jumps
    assert theta[-1] - theta[0] > 3 * math.pi           # went around and on
    folds = br.special("fold")
    assert len(folds) == 3
    for f in folds:
        assert abs(f.x[0]) < 1e-10 and abs(abs(f.params["mu"]) - 1) < 1e-12


def test_failed_corrector_is_reported_with_residual(models):
    F = models.scalar(lambda x, p: x - p[0] ** 2 + 0.3 * x**3)
    strict = C.NewtonSettings(tol=1e-14, max_iter=1)
    br = C.continuation(C.EquilibriumProblem(F, [0.0], {"mu": 0.0}, "mu"),
                        settings=settings(ds=0.1, ds_min=1e-2, newton=strict))
    assert br.status == "failed"
    assert br.failure["residual"] > 1e-14 and np.isfinite(br.failure["residual"])
    assert f"{br.failure['residual']:.3e}" in br.message
    assert len(br) >= 1 and np.all(np.isfinite(br.x))


def test_start_point_failure_is_data(models):
    F = models.scalar(lambda x, p: x**2 + 1 + p[0] ** 2)
    br = C.continuation(C.EquilibriumProblem(F, [0.5], {"mu": 0.0}, "mu"))
    assert br.status == "failed" and len(br) == 0
    assert br.failure["residual"] >= 1.0
    assert "start point did not converge" in br.message


@pytest.mark.parametrize("expr", [lambda x, p: p[0] * x - x**3,
                                  lambda x, p: p[0] * x - x**2])
def test_branch_point_on_trivial_branch(expr, models):
    F = models.scalar(expr)
    br = C.continuation(C.EquilibriumProblem(F, [0.0], {"mu": -0.5}, "mu"),
                        settings=settings(max_steps=30, bounds={"mu": (-1, 0.5)}))
    bps = br.special("bp")
    assert br.status == "bound"
    assert len(bps) == 1 and bps[0].status == "converged"
    assert abs(bps[0].params["mu"]) < 1e-10 and abs(bps[0].x[0]) < 1e-10
    assert not br.special("fold")


def test_bounds_stop_the_run(models):
    F = models.scalar(lambda x, p: x - p[0])
    br = C.continuation(C.EquilibriumProblem(F, [0.0], {"mu": 0.0}, "mu"),
                        settings=settings(bounds={"mu": (-1.0, 0.35)}))
    assert br.status == "bound" and "mu" in br.message
    assert br.par("mu").max() <= 0.35 and br.par("mu").max() > 0.2


def test_direction_and_step_growth(models):
    F = models.scalar(lambda x, p: x - p[0])
    br = C.continuation(C.EquilibriumProblem(F, [0.0], {"mu": 0.0}, "mu"),
                        settings=settings(direction=-1, max_steps=20, ds_max=0.08))
    assert np.all(np.diff(br.par("mu")) < 0)
    assert br.ds[-1] == pytest.approx(0.08)


@pytest.mark.parametrize("k", [
    dict(a1=0.3, a2=-0.2, a3=0.5, b1=0.1, b2=0.4, b3=-0.3, c1=-1.0, c2=-0.5, d1=-0.2, d2=-0.7),
    dict(a1=-0.4, a2=0.6, a3=0.1, b1=0.5, b2=-0.3, b3=0.2, c1=0.8, c2=0.3, d1=0.4, d2=0.2),
])
def test_hopf_normal_form_lyapunov(k, models):
    w = 1.0
    a = models.guckenheimer_holmes_a(k, w)
    F = models.hopf_normal_form(k)
    br = C.continuation(C.EquilibriumProblem(F, [0.0, 0.0], {"mu": -0.3, "w": w}, "mu"),
                        settings=settings(bounds={"mu": (-1, 0.3)}))
    (h,) = br.special("hopf")
    assert h.status == "converged"
    assert abs(h.params["mu"]) < 1e-12 and np.max(np.abs(h.x)) < 1e-12
    assert abs(h.data["omega"] - 1.0) < 1e-12
    assert abs(h.data["l1"] - 2 * a / w) < 1e-10
    assert np.sign(h.data["l1"]) == np.sign(a) != 0


def test_lyapunov_scales_with_frequency(models):
    k = dict(a1=0, a2=0, a3=0, b1=0, b2=0, b3=0, c1=-0.7, c2=-0.7, d1=-0.7, d2=-0.7)
    vf = C.VectorField(models.hopf_normal_form(k), None, ("mu", "w"))
    for w in (0.5, 3.0):  # x' = mu x - w y - 0.7 x r^2 ...: l1 = 2 (-0.7) / w
        assert C.first_lyapunov(vf, np.zeros(2), np.array([0.0, w]), w) == \
            pytest.approx(-1.4 / w, rel=1e-12)


def test_brusselator_hopf_point(models):
    # J = [[B-1, A^2], [-B, -A^2]]: trace B - 1 - A^2, det A^2 -> B = 1 + A^2, omega = A.
    A = 1.5
    br = C.continuation(C.EquilibriumProblem(models.brusselator(), [A, 1 / A], {"A": A, "B": 1.0},
                                             "B"), settings=settings(bounds={"B": (0, 5)}))
    (h,) = br.special("hopf")
    assert abs(h.params["B"] - (1 + A**2)) < 1e-12
    assert abs(h.data["omega"] - A) < 1e-12
    assert np.allclose(h.x, [A, (1 + A**2) / A], atol=1e-12)
    assert br.stable[br.par("B") < 1 + A**2 - 1e-6].all()
    assert not br.stable[br.par("B") > 1 + A**2 + 1e-6].any()


def test_state_dependent_mass_matrix_hopf(models):
    F, M = models.mass_model()
    prob = C.EquilibriumProblem(F, [1.0, 1.0], {"p": 0.0}, "p", M=M)
    br = C.continuation(prob, settings=settings(bounds={"p": (-1, 1)}))
    (h,) = br.special("hopf")
    assert h.status == "converged"
    assert abs(h.params["p"] - 0.5) < 1e-12 and abs(h.data["omega"] - 0.5) < 1e-12
    ev = br.eigenvalues[0]
    assert np.all(ev.real < 0)


def test_mass_matrix_lyapunov_agrees_with_explicit_form(models):
    """l1 of M(x) xdot = F equals l1 of xdot = M(x)^{-1} F (independent route)."""
    F, M = models.mass_model()
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    f = ca.Function("f", [x, p], [ca.mtimes(ca.inv(M(x, p)), F(x, p))])
    xs, ps = np.ones(2), np.array([0.5])
    l1_mass = C.first_lyapunov(C.VectorField(F, M, ("p",)), xs, ps, 0.5)
    l1_explicit = C.first_lyapunov(C.VectorField(f, None, ("p",)), xs, ps, 0.5)
    assert l1_mass == pytest.approx(l1_explicit, rel=1e-10, abs=1e-12)
    # freezing M at M(c) gives a different value: the state dependence matters
    Mc = ca.Function("Mc", [x, p], [ca.DM([[2, 1], [0, 2]])])
    l1_frozen = C.first_lyapunov(C.VectorField(F, Mc, ("p",)), xs, ps, 0.5)
    assert abs(l1_frozen - l1_mass) > 1e-2


def test_scalar_mass_leaves_l1_invariant(models):
    """xdot = F / m(x), m > 0, is a time rescaling: same orbits, same l1."""
    k = dict(a1=0.3, a2=-0.2, a3=0.5, b1=0.1, b2=0.4, b3=-0.3, c1=-1.0, c2=-0.5,
             d1=-0.2, d2=-0.7)
    F = models.hopf_normal_form(k)
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    m = 1 + 0.4 * x[0] - 0.3 * x[1] + x[0] ** 2
    M = ca.Function("M", [x, p], [m * ca.SX.eye(2)])
    l1_id = C.first_lyapunov(C.VectorField(F, None, ("mu", "w")), np.zeros(2),
                             np.array([0.0, 1.0]), 1.0)
    l1_m = C.first_lyapunov(C.VectorField(F, M, ("mu", "w")), np.zeros(2),
                            np.array([0.0, 1.0]), 1.0)
    assert l1_m == pytest.approx(l1_id, rel=1e-11)
    assert l1_id == pytest.approx(2 * models.guckenheimer_holmes_a(k, 1.0), rel=1e-11)


def test_fold_and_hopf_within_one_step():
    """z' = mu - z^2 (fold at z = 0) and an oscillator with growth rate 0.01 - z
    (Hopf at z = 0.01, mu = 1e-4, omega = 1). One step spans both: the unstable
    count jumps by 3, the complex one by 2; both points must be found (the eigenvalue
    step limit, which would split the step, is off)."""
    x, p = ca.SX.sym("x", 3), ca.SX.sym("p", 1)
    z, u, v = x[0], x[1], x[2]
    a = 0.01 - z
    F = ca.Function("F", [x, p], [ca.vertcat(p[0] - z**2, a * u - v - u * (u**2 + v**2),
                                             u + a * v - v * (u**2 + v**2))])
    br = C.continuation(C.EquilibriumProblem(F, [0.3, 0, 0], {"mu": 0.09}, "mu"),
                        settings=settings(ds=0.1, ds_max=0.1, direction=-1, max_steps=8,
                                          eigen_step=0.0))
    z = br.x[:, 0]
    assert any(z[i] > 0.01 and z[i + 1] < 0 for i in range(len(z) - 1))  # one step spans both
    (fold,) = br.special("fold")
    (hopf,) = br.special("hopf")
    assert abs(fold.x[0]) < 1e-10 and abs(fold.params["mu"]) < 1e-12
    assert abs(hopf.x[0] - 0.01) < 1e-10 and abs(hopf.params["mu"] - 1e-4) < 1e-12
    assert abs(hopf.data["omega"] - 1) < 1e-10


def test_dae_constant_singular_mass_lyapunov_matches_reduced_ode():
    """M = diag(1, 1, 0): the constraint z = x^2 + y eliminated by hand gives a planar
    ODE. Hopf at mu = 0 with omega = 1 in both; l1 scales with |q|^2 in the full state:
    q3 = (q2, q2_y) with q2 = (1, -i)/sqrt(2), so l1_dae = l1_ode * |q2|^2/|q3|^2 = 2/3 l1_ode."""
    x, p = ca.SX.sym("x", 3), ca.SX.sym("p", 1)
    X, Y, Z = x[0], x[1], x[2]
    r2 = X**2 + Y**2
    F = ca.Function("F", [x, p], [ca.vertcat(
        p[0] * X - Y - X * r2 + 0.5 * Z * X + 0.3 * Z * Y,
        X + p[0] * Y - Y * r2 + 0.2 * Z**2, Z - X**2 - Y)])
    M = ca.Function("M", [x, p], [ca.diag(ca.vertcat(1, 1, 0))])
    br = C.continuation(C.EquilibriumProblem(F, [0, 0, 0], {"mu": -0.3}, "mu", M=M),
                        settings=settings(bounds={"mu": (-1, 0.3)}))
    (h,) = br.special("hopf")
    assert abs(h.params["mu"]) < 1e-12 and abs(h.data["omega"] - 1) < 1e-12
    assert all(ev.size == 2 for ev in br.eigenvalues)  # the infinite eigenvalue is dropped
    x2 = ca.SX.sym("x", 2)
    z, r2 = x2[0] ** 2 + x2[1], x2[0] ** 2 + x2[1] ** 2
    f = ca.Function("f", [x2, p], [ca.vertcat(
        p[0] * x2[0] - x2[1] - x2[0] * r2 + 0.5 * z * x2[0] + 0.3 * z * x2[1],
        x2[0] + p[0] * x2[1] - x2[1] * r2 + 0.2 * z**2)])
    l1_ode = C.first_lyapunov(C.VectorField(f, None, ("mu",)), np.zeros(2), np.zeros(1), 1.0)
    assert h.data["l1"] == pytest.approx(2 / 3 * l1_ode, rel=1e-10)


def _gh_coefficient_in_normal_coordinates(F, xs, ps, omega, q):
    """Guckenheimer-Holmes a for F at (xs, ps) in coordinates x = xs + T y with
    T = [Re q, -Im q], where the linear part becomes [[0, -omega], [omega, 0]]."""
    T = np.column_stack([q.real, -q.imag])
    y = ca.SX.sym("y", 2)
    g = ca.mtimes(ca.DM(np.linalg.inv(T)), F(ca.DM(xs) + ca.mtimes(ca.DM(T), y), ca.DM(ps)))
    d = {}
    for name, idx in {"xx": (0, 0), "xy": (0, 1), "yy": (1, 1), "xxx": (0, 0, 0),
                      "xyy": (0, 1, 1), "xxy": (0, 0, 1), "yyy": (1, 1, 1)}.items():
        for comp in (0, 1):
            e = g[comp]
            for k in idx:
                e = ca.jacobian(e, y[k])
            d[("f" if comp == 0 else "g") + name] = float(ca.Function("d", [y], [e])([0, 0]))
    return (d["fxxx"] + d["fxyy"] + d["gxxy"] + d["gyyy"]) / 16 + (
        d["fxy"] * (d["fxx"] + d["fyy"]) - d["gxy"] * (d["gxx"] + d["gyy"])
        - d["fxx"] * d["gxx"] + d["fyy"] * d["gyy"]) / (16 * omega)


@pytest.mark.parametrize("A", [0.7, 1.5, 2.5])
def test_brusselator_lyapunov_against_guckenheimer_holmes(models, A):
    """Independent route: transform the Brusselator at its Hopf point to the rotation
    normal coordinates y (x = x* + T y, T = [Re q, -Im q], |q| = 1) and apply the
    Guckenheimer-Holmes formula. There q_y = (1, -i)/sqrt(2) maps to q/sqrt(2), so the
    library's |q| = 1 value is l1 = 2 * (2 a / omega) = 4 a / omega."""
    import scipy.linalg
    F = models.brusselator()
    br = C.continuation(C.EquilibriumProblem(F, [A, 1 / A], {"A": A, "B": 1.0}, "B"),
                        settings=settings(bounds={"B": (0, 1 + A**2 + 1)}))
    (h,) = br.special("hopf")
    ps = np.array([A, h.params["B"]])
    vf = C.VectorField(F, None, ("A", "B"))
    lam, V = scipy.linalg.eig(vf.jac_x(h.x, ps).toarray(), vf.mass(h.x, ps).toarray())
    q = V[:, np.argmin(np.abs(lam - 1j * h.data["omega"]))]
    q = q / np.linalg.norm(q)
    a = _gh_coefficient_in_normal_coordinates(F, h.x, ps, h.data["omega"], q)
    assert h.data["l1"] == pytest.approx(4 * a / h.data["omega"], rel=1e-9)
    assert h.data["l1"] < 0  # the Brusselator Hopf bifurcation is supercritical


def test_narrow_unstable_window_is_resolved_by_the_eigenvalue_step_limit():
    """A window of width 0.02 inside steps of 0.3: without the limit both ends of the
    step are stable and the window is missed; with it (the default) both Hopf points
    are found at their known values."""
    F = window_oscillator(1e-4)
    run = lambda **kw: C.continuation(C.EquilibriumProblem(F, [0.0, 0.0], {"mu": 0.0}, "mu"),
                                      settings=settings(ds=0.3, ds_max=0.3, max_steps=40,
                                                        bounds={"mu": (0.0, 2.0)}, **kw))
    assert run(eigen_step=0.0).special("hopf") == []
    hopf = sorted(h.params["mu"] for h in run().special("hopf"))
    assert np.allclose(hopf, [0.99, 1.01], atol=1e-10, rtol=0)


def test_narrow_window_of_divergence_is_resolved_by_the_eigenvalue_step_limit():
    """A real eigenvalue a = eps - (mu - 1)^2 of the trivial branch of x' = a x - x^3,
    y' = mu - y: positive only for |mu - 1| < 0.01 (two pitchforks, det F_x changes sign
    twice), inside steps of 0.3. Without the limit the window is jumped over; with it
    both branch points are found at their known values 1 -+ 0.01."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    a = 1e-4 - (p[0] - 1) ** 2
    F = ca.Function("F", [x, p], [ca.vertcat(a * x[0] - x[0] ** 3, p[0] - x[1])])
    run = lambda **kw: C.continuation(C.EquilibriumProblem(F, [0.0, 0.0], {"mu": 0.0}, "mu"),
                                      settings=settings(ds=0.3, ds_max=0.3, max_steps=40,
                                                        bounds={"mu": (0.0, 2.0)}, **kw))
    assert run(eigen_step=0.0).special("bp") == []
    bps = sorted(b.params["mu"] for b in run().special("bp") if b.status == "converged")
    assert np.allclose(bps, [0.99, 1.01], atol=1e-9, rtol=0)


def test_eigenvalue_step_limit_costs_few_steps_on_a_plain_crossing():
    """a = mu - 1 (one crossing, no window): the limit lets the step cross at once, so
    the branch takes at most two more points than without it (no Zeno shrinking)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    a = p[0] - 1
    F = ca.Function("F", [x, p], [ca.vertcat(a * x[0] - x[1], x[0] + a * x[1])])
    run = lambda **kw: C.continuation(C.EquilibriumProblem(F, [0.0, 0.0], {"mu": 0.0}, "mu"),
                                      settings=settings(ds=0.05, ds_max=0.3, max_steps=60,
                                                        bounds={"mu": (0.0, 2.0)}, **kw))
    plain, limited = run(eigen_step=0.0), run()
    assert len(limited) <= len(plain) + 2
    (h,) = limited.special("hopf")
    assert abs(h.params["mu"] - 1.0) < 1e-10


def test_eigen_step_setting_is_validated():
    with pytest.raises(ValueError, match="eigen_step"):
        C.ContinuationSettings(eigen_step=1.5)


def test_max_turn_bounds_the_angle_between_successive_tangents():
    """The narrow fold p = -1 + (x/0.1)^2: its tangent turns by pi within |x| < 0.1. With
    steps of 0.5 the branch turns by up to about 1 rad from one point to the next;
    with ``max_turn`` = 0.2 every turn, measured on the exact tangent (1, 200 x) of the
    curve at the points, is at most 0.2 (and steps were rejected to make it so)."""
    x, p = ca.SX.sym("x"), ca.SX.sym("p")
    F = ca.Function("F", [x, p], [p + 1 - (x / 0.1) ** 2])

    def turns(max_turn):
        prob = C.EquilibriumProblem(F, np.array([-0.2]), {"p": 3.0}, "p")
        br = C.continuation(prob, settings=C.ContinuationSettings(
            ds=0.5, ds_max=0.5, direction=-1, max_steps=60, bounds={"p": (-2.0, 3.5)},
            max_turn=max_turn, compute_eigenvalues=False))
        t = np.c_[np.ones(len(br)), 200 * br.x[:, 0]]
        t /= np.linalg.norm(t, axis=1)[:, None]
        assert len(br.special("fold")) == 1 and br.x[-1, 0] > 0
        return np.arccos(np.clip(np.abs(np.sum(t[1:] * t[:-1], axis=1)), 0, 1)), br

    free, _ = turns(0.0)
    bounded, br = turns(0.2)
    assert free.max() > 0.5
    assert bounded.max() <= 0.2 + 1e-9 and br.stats["rejected_steps"] > 0


@pytest.mark.parametrize("amplitude", [0.05, -0.05])
def test_switching_at_a_pitchfork_follows_the_symmetry_breaking_branch(amplitude):
    """x' = mu x - x^3, y' = mu - y: the trivial branch has a pitchfork at mu = 0; the
    switched branch is x = +-sqrt(mu) (closed form), stable, on the side of the
    amplitude's sign."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    F = ca.Function("F", [x, p], [ca.vertcat(p[0] * x[0] - x[0] ** 3, p[0] - x[1])])
    problem = C.EquilibriumProblem(F, [0.0, -1.0], {"mu": -1.0}, "mu")
    trivial = C.continuation(problem, settings=settings(ds=0.1, ds_max=0.1, max_steps=40,
                                                        bounds={"mu": (-1.0, 1.0)}))
    (bp,) = [b for b in trivial.special("bp") if b.status == "converged"]
    assert abs(bp.params["mu"]) < 1e-10
    new = C.equilibrium_from_bp(problem, bp, amplitude=amplitude)
    branch = C.continuation(new, settings=settings(ds=0.05, ds_max=0.1, max_steps=40,
                                                   bounds={"mu": (-1.0, 1.0)}))
    mu, u = branch.par("mu"), branch.x[:, 0]
    assert branch.status == "bound" and mu[-1] > 0.9
    assert np.allclose(u, np.sign(amplitude) * np.sqrt(mu), atol=1e-8, rtol=0)   # corrector tol
    assert np.all(branch.n_unstable == 0)
    with pytest.raises(ValueError, match="amplitude"):
        C.equilibrium_from_bp(problem, bp, amplitude=0.0)
