"""Periodic orbits by collocation: closed-form cycles, convergence orders, mass
matrices, Hopf branch switching, Floquet multipliers and cycle folds."""

import casadi as ca
import numpy as np
import pytest

import continuation as C
from continuation._cycles.collocation import builder


def _ring(theta_gain=0.0, radial=1.0):
    """r' = radial r (1 - r^2), theta' = 1 + e cos(theta) (e = p[0]).

    Cycle r = 1 with period 2 pi / sqrt(1 - e^2), non-trivial multiplier
    exp(-2 radial T); the speed along the cycle is non-uniform for e != 0.
    """
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    r2 = x[0] ** 2 + x[1] ** 2
    th = 1 + p[0] * x[0] / ca.sqrt(r2)
    g = radial * (1 - r2)
    return ca.Function("F", [x, p], [ca.vertcat(g * x[0] - x[1] * th, g * x[1] + x[0] * th)])


def _circle(t):
    return np.c_[np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)]


def _solve(F, e, ntst, ncol, period, M=None, floquet="auto"):
    prob = C.CycleProblem(F, _circle, period, {"e": e}, "e", M=M,
                          settings=C.CollocationSettings(ntst=ntst, ncol=ncol, floquet=floquet))
    step = C.ContinuationIterator(prob, C.PALC(), C.ContinuationSettings()).start()
    assert step is not None
    return prob, step.X


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
    F, e = _ring(), 0.5
    T = 2 * np.pi / np.sqrt(1 - e ** 2)
    err_T, err_r = [], []
    for ntst in ntsts:
        prob, X = _solve(F, e, ntst, ncol, T)
        err_T.append(abs(prob.period(X) - T))
        err_r.append(np.max(np.abs(_mesh_radius(prob, X) - 1)))
    assert abs(_order(ntsts, err_T) - 2 * ncol) < 0.6, err_T
    assert abs(_order(ntsts, err_r) - 2 * ncol) < 0.8, err_r


def test_floquet_multipliers_closed_form_and_trivial():
    F, e = _ring(), 0.5
    T = 2 * np.pi / np.sqrt(1 - e ** 2)
    prob, X = _solve(F, e, 40, 4, T)
    mu = prob.multipliers(X)
    assert abs(mu[0] - 1) < 1e-10
    assert abs(mu[1] / np.exp(-2 * T) - 1) < 1e-6


def test_pencil_keeps_strongly_contracting_multiplier():
    """Radial rate 3: multiplier exp(-6 T) = 4.2e-17, below round-off relative to the
    trivial one. The block-cyclic pencil keeps it to 1e-7 relative (measured 3e-9);
    the explicit product of the 60 transfer matrices loses it completely."""
    F = _ring(radial=3.0)
    T = 2 * np.pi
    prob, X = _solve(F, 0.0, 60, 4, T, floquet="pencil")
    exact = np.exp(-6 * T)
    mu = prob.multipliers(X)
    assert abs(mu[0] - 1) < 1e-9
    assert abs(mu[1] / exact - 1) < 1e-7
    prod = C.CycleProblem(F, _circle, T, {"e": 0.0}, "e", settings=C.CollocationSettings(
        ntst=60, ncol=4, floquet="product")).multipliers(X)
    assert abs(prod[0] - 1) < 1e-9
    assert abs(prod[1] / exact - 1) > 0.1


def test_scalar_state_dependent_mass_rescales_time():
    """M = (2 + x1) I: same orbit r = 1, period int_0^{2 pi} (2 + cos s) ds = 4 pi,
    same Poincare map, so the same multiplier exp(-4 pi)."""
    F = _ring()
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    M = ca.Function("M", [x, p], [(2 + x[0]) * ca.SX.eye(2)])
    prob, X = _solve(F, 0.0, 40, 4, 10.0, M=M)
    assert abs(prob.period(X) - 4 * np.pi) < 1e-9
    assert np.max(np.abs(_mesh_radius(prob, X) - 1)) < 1e-9
    mu = prob.multipliers(X)
    assert abs(mu[0] - 1) < 1e-9 and abs(mu[1] / np.exp(-4 * np.pi) - 1) < 1e-6


def test_general_mass_matrix_agrees_with_explicit_form():
    """M(x) xdot = F against xdot = M(x)^{-1} F (symbolic inverse): period and
    multipliers agree (the collocation Jacobian carries the D_x M terms)."""
    F = _ring()
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    Mx = ca.vertcat(ca.horzcat(1.5 + 0.5 * x[0] ** 2, 0.3 * x[1]),
                    ca.horzcat(0.2 * x[0], 1.2 + 0.3 * x[1] ** 2))
    M = ca.Function("M", [x, p], [Mx])
    G = ca.Function("G", [x, p], [ca.solve(Mx, F(x, p))])
    pm, Xm = _solve(F, 0.3, 40, 4, 9.0, M=M)
    pe, Xe = _solve(G, 0.3, 40, 4, 9.0)
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
    F, e = _ring(), 0.4
    prob = C.CycleProblem(F, lambda t: 1.1 * _circle(t) + 0.05, 7.0, {"e": e}, "e",
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
    F = _ring()
    with pytest.raises(ValueError, match="period"):
        C.CycleProblem(F, _circle, -1.0, {"e": 0.0}, "e")
    with pytest.raises(ValueError, match="orbit"):
        C.CycleProblem(F, np.zeros((5, 3)), 1.0, {"e": 0.0}, "e")
    with pytest.raises(ValueError, match="unknown parameter"):
        C.CycleProblem(F, _circle, 1.0, {"e": 0.0}, "f")
    eq = C.EquilibriumProblem(F, [0.0, 0.0], {"e": 0.0}, "e")
    fold = C.SpecialPoint("fold", 0, np.zeros(2), {"e": 0.0}, "converged", 0.0, {})
    with pytest.raises(ValueError, match="hopf"):
        C.cycle_from_hopf(eq, fold)


def test_sampled_orbit_guess_and_compile_cache():
    """An array of samples is accepted as the guess; the system compiles once per
    (NTST, NCOL) and VectorField."""
    F = _ring()
    samples = _circle(np.arange(50) / 50) * 1.05
    prob = C.CycleProblem(F, samples, 6.5, {"e": 0.0}, "e",
                          settings=C.CollocationSettings(ntst=12, ncol=3))
    step = C.ContinuationIterator(prob, C.PALC(), C.ContinuationSettings()).start()
    assert abs(prob.period(step.X) - 2 * np.pi) < 1e-5
    again = C.CycleProblem(prob.vf, samples, 6.5, {"e": 0.0}, "e",
                           settings=C.CollocationSettings(ntst=12, ncol=3))
    assert again.system.compiled is prob.system.compiled
    assert callable(builder(12, 3))


def test_dense_and_sparse_condensation_agree(monkeypatch):
    """Both condensation paths of the sparse Jacobian (batched dense for small or
    well-filled blocks, SuperLU on the block diagonal of the others) give the same transfer
    matrices, and so do the maps of the condensed Newton solver."""
    from continuation._cycles import floquet as _floquet
    F, e = _ring(), 0.5
    prob, X = _solve(F, e, 12, 3, 2 * np.pi / np.sqrt(1 - e ** 2))
    J = C.CycleProblem.jacobian(prob, X)
    n, ntst, ncol = prob.vf.n, prob.ntst, prob.ncol
    calls = []
    monkeypatch.setattr(_floquet, "sparse_transfer_matrices",
                        lambda *a, f=_floquet.sparse_transfer_matrices: calls.append(1) or f(*a))
    dense = _floquet.transfer_matrices(J, n, ntst, ncol, full=True)
    assert not calls
    monkeypatch.setattr(_floquet, "DENSE_ALWAYS", 0)
    monkeypatch.setattr(_floquet, "DENSE_MAX", 0)
    sparse = _floquet.transfer_matrices(J, n, ntst, ncol, full=True)
    assert calls
    assert np.max(np.abs(dense - sparse)) < 1e-12 * np.max(np.abs(dense))
    assert prob.condensed
    condensed = prob.transfer_matrices(X, full=True)
    assert np.max(np.abs(dense - condensed)) < 1e-12 * np.max(np.abs(dense))


def test_extrema_of_the_collocation_polynomial_match_dense_sampling():
    """``extrema`` (Newton on each interval's polynomial) equals the extremes of the same
    piecewise polynomial sampled at 400 001 times, to the sampling's resolution, also
    where the extremum sits on a mesh point (cos at t = 0) or inside an interval."""
    from continuation._cycles.collocation import evaluate, extrema
    ntst, ncol, n = 20, 4, 3
    t = np.linspace(0, 1, ntst * ncol, endpoint=False)
    U = np.column_stack([np.cos(2 * np.pi * t), np.cos(4 * np.pi * t + 0.2) ** 3,
                         np.sin(2 * np.pi * t) ** 5]).ravel()
    mesh = np.sort(np.concatenate([[0.0, 1.0], np.random.default_rng(1).uniform(0, 1, ntst - 1)]))
    A = np.vstack([np.eye(n), np.random.default_rng(0).normal(size=(4, n))])
    lo, hi = extrema(U, mesh, ncol, n, A)
    dense = evaluate(U, mesh, ncol, n, np.linspace(0, 1, 400001)) @ A.T
    scale = np.abs(dense).max()
    # never beyond the polynomial's true extremes, and no sample beyond them
    assert np.all(lo <= dense.min(axis=0) + 1e-14) and np.all(hi >= dense.max(axis=0) - 1e-14)
    assert np.max(np.abs(lo - dense.min(axis=0))) < 1e-9 * scale
    assert np.max(np.abs(hi - dense.max(axis=0))) < 1e-9 * scale


def test_minimizer_over_many_rows_matches_dense_sampling():
    """``minimizer`` (only the intervals that can beat a row's best sample are polished)
    finds ``min_{t, j} (A u(t))_j`` of 200 rows of a cycle to the resolution of 400 001
    samples, where it is taken, and the least of ``extrema``'s row minima."""
    from continuation._cycles.collocation import evaluate, extrema, minimizer
    ntst, ncol, n = 20, 4, 3
    t = np.linspace(0, 1, ntst * ncol, endpoint=False)
    U = np.column_stack([np.cos(2 * np.pi * t), np.sin(6 * np.pi * t + 0.3),
                         np.cos(4 * np.pi * t) ** 2]).ravel()
    mesh = np.linspace(0.0, 1.0, ntst + 1)
    A = np.random.default_rng(2).normal(size=(200, n))
    value, i, s, j = minimizer(U, mesh, ncol, n, A)
    times = np.linspace(0, 1, 400001)
    dense = evaluate(U, mesh, ncol, n, times) @ A.T
    scale = np.abs(dense).max()
    assert value <= dense.min() + 1e-14 and abs(value - dense.min()) < 1e-9 * scale
    k, j_dense = np.unravel_index(np.argmin(dense), dense.shape)
    assert j == j_dense and abs(mesh[i] + s * (mesh[i + 1] - mesh[i]) - times[k]) < 1e-4
    assert value == extrema(U, mesh, ncol, n, A)[0].min()


def test_transfer_matrices_on_a_kept_layout_and_with_duplicate_entries(monkeypatch):
    """The interval layout of a Jacobian's pattern is found once and reused: a second
    Jacobian of the same pattern with other values gives its own maps (equal to the dense
    route's on it), and a non-canonical Jacobian (entries split into duplicates) gives
    the same maps as the canonical one, by both routes."""
    import scipy.sparse as sp
    from continuation._cycles import floquet as _floquet
    F, e = _ring(), 0.5
    prob, X = _solve(F, e, 12, 3, 2 * np.pi / np.sqrt(1 - e ** 2))
    J = sp.csc_matrix(C.CycleProblem.jacobian(prob, X))
    n, ntst, ncol = prob.vf.n, prob.ntst, prob.ncol
    other = J.copy()
    other.data = other.data * (1.0 + 0.1 * np.sin(np.arange(other.nnz)))
    cols = [slice(J.indptr[j], J.indptr[j + 1]) for j in range(J.shape[1])]
    split = sp.csc_matrix((np.concatenate([np.r_[0.25 * J.data[c], 0.75 * J.data[c]]
                                           for c in cols]),
                           np.concatenate([np.r_[J.indices[c], J.indices[c]] for c in cols]),
                           2 * J.indptr), shape=J.shape)
    assert not split.has_canonical_format
    assert _floquet._Layout.of(J, n, ntst, ncol) is _floquet._Layout.of(other, n, ntst, ncol)
    for dense_limit in (None, 0):
        if dense_limit == 0:
            monkeypatch.setattr(_floquet, "DENSE_ALWAYS", 0)
            monkeypatch.setattr(_floquet, "DENSE_MAX", 0)
        maps = [_floquet.transfer_matrices(A, n, ntst, ncol, full=True)
                for A in (J, other, J, split)]
        blocks = [_floquet.block_transfer_matrices(_dense_blocks(A, n, ntst, ncol), n, True)
                  for A in (J, other)]
        scale = np.abs(maps[0]).max()
        assert np.abs(maps[0] - blocks[0]).max() < 1e-12 * scale
        assert np.abs(maps[1] - blocks[1]).max() < 1e-12 * scale
        assert np.abs(maps[1] - maps[0]).max() > 1e-3 * scale     # its own values
        assert np.abs(maps[2] - maps[0]).max() < 1e-13 * scale
        assert np.abs(maps[3] - maps[0]).max() < 1e-12 * scale


def _dense_blocks(J, n, ntst, ncol):
    """``[B_L, B_R]`` of every interval read from the dense Jacobian (independent of
    the sparse layout): rows of interval ``i``, columns of its nodes 0..NCOL wrapped."""
    D = J.toarray()
    m, N = n * ncol, n * ncol * ntst
    out = np.empty((ntst, m, m + n))
    for i in range(ntst):
        cols = (i * m + np.arange(m + n)) % N
        out[i] = D[i * m:(i + 1) * m][:, cols]
    return out


@pytest.mark.parametrize("ncol", [2, 3])
def test_flow_defect_vanishes_at_the_superconvergent_order(ncol):
    """The exact monodromy maps the flow onto itself; the discretized one misses it by
    ``flow_defect``, which on the ring (non-uniform speed) falls like ``h^(2 NCOL)``,
    the order of Gauss collocation at the mesh points (measured 4.0 / 4.0 and 6.6 / 5.4
    between NTST = 8, 16, 32)."""
    F, e = _ring(), 0.5
    period = 2 * np.pi / np.sqrt(1 - e ** 2)
    defects = [p.flow_defect(X) for p, X in (_solve(F, e, ntst, ncol, period)
                                             for ntst in (8, 16, 32))]
    orders = np.log2(np.array(defects[:-1]) / np.array(defects[1:]))
    assert np.all(orders > 2 * ncol - 0.7), orders
    assert defects[-1] < 1e-4
