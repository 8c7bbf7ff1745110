"""Periodic orbits by collocation: closed-form cycles, convergence orders, mass
matrices, Hopf branch switching, Floquet multipliers and cycle folds."""

import casadi as ca
import numpy as np
import pytest

import continuation as C

from .conftest import circle, cycle_from_circle, ring


def _hopf_normal_form(quintic=False):
    """r' = r (mu + a r^2 [- r^4]), theta' = 1; p = (mu, a)."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    r2 = x[0] ** 2 + x[1] ** 2
    g = p[0] + p[1] * r2 - (r2 ** 2 if quintic else 0)
    return ca.Function("F", [x, p], [ca.vertcat(g * x[0] - x[1], x[0] + g * x[1])])


def _cycle_branch(F, a, ntst=20, max_steps=20, bounds=(-1, 1)):
    eq = C.EquilibriumProblem(F, [0, 0], {"mu": -0.5, "a": a}, "mu")
    (hopf,) = C.continuation(eq, settings=C.ContinuationSettings(
        ds=0.1, bounds={"mu": (-1, 1)})).special("hopf")
    cyc = C.cycle_from_hopf(eq, hopf, dp=1e-3,
                            settings=C.CollocationSettings(ntst=ntst, ncol=4))
    settings = C.ContinuationSettings(ds=0.05, ds_max=0.3, max_steps=max_steps,
                                      direction=cyc.hopf_direction, bounds={"mu": bounds})
    return hopf, cyc, C.continuation(cyc, settings=settings)


def _mesh_radius(cyc, X):
    return np.linalg.norm(cyc.nodes(X)[:: cyc.ncol], axis=1)


def _nontrivial(mu):
    return mu[np.argmax(np.abs(mu - 1))]


@pytest.mark.parametrize("a", [-1.0, -0.5])
def test_hopf_switching_onto_normal_form_cycles(a):
    """Supercritical Hopf: cycles r = sqrt(-mu/a), T = 2 pi, multiplier exp(-4 pi mu)."""
    hopf, cyc, br = _cycle_branch(_hopf_normal_form(), a)
    assert hopf.data["l1"] == pytest.approx(2 * a, rel=1e-10)
    assert cyc.hopf_direction == 1 and cyc.X0[-1] == pytest.approx(1e-3)
    assert br.status == "max_steps" and br.par("mu")[-1] > 0.1
    mu = br.par("mu")
    radius = np.linalg.norm(br.x, axis=1)        # x = u(0), a mesh point
    err = np.abs(radius - np.sqrt(-mu / a))
    # near the Hopf point the radial contraction -2 mu T is weak, so a residual of
    # 1e-10 allows a larger radius error there
    assert np.max(err) < 5e-8 and np.max(err[mu > 0.01]) < 1e-10
    assert np.max(np.abs(br.columns["period"] - 2 * np.pi)) < 1e-9
    nontriv = np.array([_nontrivial(ev) for ev in br.eigenvalues])
    assert np.max(np.abs(np.log(nontriv.real) + 4 * np.pi * mu)) < 1e-7
    trivial = br.tests["trivial_error"]
    assert np.max(trivial) < 1e-7 and np.max(trivial[mu > 0.01]) < 1e-9 and br.stable.all()


def test_hopf_start_guess_is_normal_form_accurate():
    """The normal-form guess is O(dp) from the corrected cycle; the corrected
    start point lies at p_H + dp with radius sqrt(dp) (a = -1)."""
    _, cyc, br = _cycle_branch(_hopf_normal_form(), -1.0, max_steps=1)
    step = C.ContinuationIterator(cyc, C.PALC(), C.ContinuationSettings()).start()
    assert np.max(np.abs(step.X - cyc.X0)) < 1e-3 * 1e-3 ** 0.5
    assert np.max(np.abs(_mesh_radius(cyc, step.X) - 1e-3 ** 0.5)) < 1e-10


def _order(ns, errs):
    return -np.polyfit(np.log(ns), np.log(errs), 1)[0]


@pytest.mark.parametrize("ncol, ntsts", [(2, (16, 32, 64)), (3, (8, 16, 32)), (4, (12, 16, 24))])
def test_collocation_superconvergence_order(ncol, ntsts):
    """Period and mesh-point errors decrease as NTST^(-2 NCOL) (non-uniform speed,
    e = 1/2: T = 2 pi / sqrt(3/4))."""
    F, e = ring(), 0.5
    T = 2 * np.pi / np.sqrt(1 - e ** 2)
    err_T, err_r = [], []
    for ntst in ntsts:
        prob, X = cycle_from_circle(F, e, ntst, ncol, T)
        err_T.append(abs(prob.period(X) - T))
        err_r.append(np.max(np.abs(_mesh_radius(prob, X) - 1)))
    assert abs(_order(ntsts, err_T) - 2 * ncol) < 0.6, err_T
    assert abs(_order(ntsts, err_r) - 2 * ncol) < 0.8, err_r


def test_floquet_multipliers_closed_form_and_trivial():
    F, e = ring(), 0.5
    T = 2 * np.pi / np.sqrt(1 - e ** 2)
    prob, X = cycle_from_circle(F, e, 40, 4, T)
    mu = prob.multipliers(X)
    assert abs(mu[0] - 1) < 1e-10
    assert abs(mu[1] / np.exp(-2 * T) - 1) < 1e-6


def test_pencil_keeps_strongly_contracting_multiplier():
    """Radial rate 3: multiplier exp(-6 T) = 4.2e-17, below round-off relative to the
    trivial one. The block-cyclic pencil keeps it to 1e-7 relative (measured 3e-9);
    the explicit product of the 60 transfer matrices loses it completely."""
    F = ring(radial=3.0)
    T = 2 * np.pi
    prob, X = cycle_from_circle(F, 0.0, 60, 4, T, floquet="pencil")
    exact = np.exp(-6 * T)
    mu = prob.multipliers(X)
    assert abs(mu[0] - 1) < 1e-9
    assert abs(mu[1] / exact - 1) < 1e-7
    prod = C.CycleProblem(F, circle, T, {"e": 0.0}, "e", settings=C.CollocationSettings(
        ntst=60, ncol=4, floquet="product")).multipliers(X)
    assert abs(prod[0] - 1) < 1e-9
    assert abs(prod[1] / exact - 1) > 0.1


def test_default_multipliers_of_a_stiff_cycle_hold_the_small_one():
    """The default route (periodic Schur of the transfer maps) on the radial-rate-3 and
    -4 rings: the trivial multiplier agrees with the product's and the pencil's, and the
    contracting one, exp(-6 T) = 4.2e-17 and exp(-8 T) = 1.2e-22, is kept to 1e-6
    relative (the collocation's own error), also in the Poincare map's multipliers."""
    T = 2 * np.pi
    for radial in (3.0, 4.0):
        F = ring(radial=radial)
        prob, X = cycle_from_circle(F, 0.0, 60, 4, T)
        exact = np.exp(-2 * radial * T)
        mu, rest = prob.multipliers(X), prob.section_multipliers(X)
        assert abs(mu[1] / exact - 1) < 1e-6 and abs(rest[0] / exact - 1) < 1e-6
        for method in ("product", "pencil"):
            other = C.CycleProblem(F, circle, T, {"e": 0.0}, "e", settings=C.CollocationSettings(
                ntst=60, ncol=4, floquet=method)).multipliers(X)
            assert abs(other[0] - mu[0]) < 1e-10


def test_scalar_state_dependent_mass_rescales_time():
    """M = (2 + x1) I: same orbit r = 1, period int_0^{2 pi} (2 + cos s) ds = 4 pi,
    same Poincare map, so the same multiplier exp(-4 pi)."""
    F = ring()
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    M = ca.Function("M", [x, p], [(2 + x[0]) * ca.SX.eye(2)])
    prob, X = cycle_from_circle(F, 0.0, 40, 4, 10.0, M=M)
    assert abs(prob.period(X) - 4 * np.pi) < 1e-9
    assert np.max(np.abs(_mesh_radius(prob, X) - 1)) < 1e-9
    mu = prob.multipliers(X)
    assert abs(mu[0] - 1) < 1e-9 and abs(mu[1] / np.exp(-4 * np.pi) - 1) < 1e-6


def test_general_mass_matrix_agrees_with_explicit_form():
    """M(x) xdot = F against xdot = M(x)^{-1} F (symbolic inverse): period and
    multipliers agree (the collocation Jacobian carries the D_x M terms)."""
    F = ring()
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    Mx = ca.vertcat(ca.horzcat(1.5 + 0.5 * x[0] ** 2, 0.3 * x[1]),
                    ca.horzcat(0.2 * x[0], 1.2 + 0.3 * x[1] ** 2))
    M = ca.Function("M", [x, p], [Mx])
    G = ca.Function("G", [x, p], [ca.solve(Mx, F(x, p))])
    pm, Xm = cycle_from_circle(F, 0.3, 40, 4, 9.0, M=M)
    pe, Xe = cycle_from_circle(G, 0.3, 40, 4, 9.0)
    assert abs(pm.period(Xm) - pe.period(Xe)) < 1e-9
    mm, me = pm.multipliers(Xm), pe.multipliers(Xe)
    assert np.max(np.abs(mm - me) / np.abs(me)) < 1e-7
    assert abs(mm[0] - 1) < 1e-9


def test_cycle_fold_of_subcritical_hopf_with_quintic_term():
    """r' = r (mu + r^2 - r^4): cycles mu = r^4 - r^2, fold at mu = -1/4 (r^2 = 1/2),
    multiplier exp(2 pi 2 r^2 (1 - 2 r^2)): unstable below the fold, stable above."""
    hopf, cyc, br = _cycle_branch(_hopf_normal_form(quintic=True), 1.0, max_steps=40,
                                  bounds=(-1, 0.5))
    assert hopf.data["l1"] > 0 and cyc.hopf_direction == -1
    (fold,) = br.special("fold")
    assert fold.status == "converged" and abs(fold.params["mu"] + 0.25) < 1e-10
    assert abs(fold.data["period"] - 2 * np.pi) < 1e-9
    R2 = np.sum(br.x ** 2, axis=1)
    mu = br.par("mu")
    ok = R2 < 1.0
    assert np.max(np.abs(mu - (R2 ** 2 - R2))[ok]) < 1e-8
    rate = np.log(np.array([_nontrivial(ev).real for ev in br.eigenvalues]))
    assert np.max(np.abs(rate - 4 * np.pi * R2 * (1 - 2 * R2))[ok]) < 1e-6
    assert np.all(br.n_unstable[R2 < 0.45] == 1) and np.all(br.n_unstable[R2 > 0.55] == 0)


def test_collocation_jacobian_matches_finite_differences():
    F, e = ring(), 0.4
    prob = C.CycleProblem(F, lambda t: 1.1 * circle(t) + 0.05, 7.0, {"e": e}, "e",
                          settings=C.CollocationSettings(ntst=5, ncol=3))
    X = prob.X0
    J = prob.jacobian(X).toarray()
    h = 1e-6
    fd = np.column_stack([(prob.residual(X + h * ei) - prob.residual(X - h * ei)) / (2 * h)
                          for ei in np.eye(X.size)])
    assert np.max(np.abs(J - fd)) < 1e-7 * max(1, np.max(np.abs(J)))


def test_bad_input_raises_naming_the_field():
    with pytest.raises(ValueError, match="ncol"):
        C.CollocationSettings(ncol=8)
    with pytest.raises(ValueError, match="ntst"):
        C.CollocationSettings(ntst=1)
    with pytest.raises(ValueError, match="floquet"):
        C.CollocationSettings(floquet="naive")
    F = ring()
    with pytest.raises(ValueError, match="period"):
        C.CycleProblem(F, circle, -1.0, {"e": 0.0}, "e")
    with pytest.raises(ValueError, match="orbit"):
        C.CycleProblem(F, np.zeros((5, 3)), 1.0, {"e": 0.0}, "e")
    with pytest.raises(ValueError, match="unknown parameter"):
        C.CycleProblem(F, circle, 1.0, {"e": 0.0}, "f")
    eq = C.EquilibriumProblem(F, [0.0, 0.0], {"e": 0.0}, "e")
    fold = C.SpecialPoint("fold", 0, np.zeros(2), {"e": 0.0}, "converged", 0.0, {})
    with pytest.raises(ValueError, match="hopf"):
        C.cycle_from_hopf(eq, fold)


def test_sampled_orbit_guess_and_compile_cache():
    """An array of samples is accepted as the guess; the system compiles once per
    (NTST, NCOL) and VectorField, by either Jacobian route."""
    F = ring()
    samples = circle(np.arange(50) / 50) * 1.05
    prob = C.CycleProblem(F, samples, 6.5, {"e": 0.0}, "e",
                          settings=C.CollocationSettings(ntst=12, ncol=3))
    step = C.ContinuationIterator(prob, C.PALC(), C.ContinuationSettings()).start()
    assert abs(prob.period(step.X) - 2 * np.pi) < 1e-5
    again = C.CycleProblem(prob.vf, samples, 6.5, {"e": 0.0}, "e",
                           settings=C.CollocationSettings(ntst=12, ncol=3))
    assert again.system.compiled is prob.system.compiled
    graph = [C.CycleProblem(prob.vf, samples, 6.5, {"e": 0.0}, "e", settings=C.CollocationSettings(
        ntst=12, ncol=3, jacobian="graph")) for _ in range(2)]
    assert graph[0].system.compiled is graph[1].system.compiled is not prob.system.compiled


@pytest.mark.parametrize("ncol", [2, 3])
def test_flow_defect_vanishes_at_the_superconvergent_order(ncol):
    """The exact monodromy maps the flow onto itself; the discretized one misses it by
    ``flow_defect``, which on the ring (non-uniform speed) falls like ``h^(2 NCOL)``,
    the order of Gauss collocation at the mesh points (measured 4.0 / 4.0 and 6.6 / 5.4
    between NTST = 8, 16, 32)."""
    F, e = ring(), 0.5
    period = 2 * np.pi / np.sqrt(1 - e ** 2)
    defects = [p.flow_defect(X) for p, X in (cycle_from_circle(F, e, ntst, ncol, period)
                                             for ntst in (8, 16, 32))]
    orders = np.log2(np.array(defects[:-1]) / np.array(defects[1:]))
    assert np.all(orders > 2 * ncol - 0.7), orders
    assert defects[-1] < 1e-4
