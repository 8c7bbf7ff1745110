"""The block-assembled collocation system ('blocks') against whole-graph CasADi AD
('graph'): residuals, Jacobians (states, period, parameters), Floquet multipliers and
continued branches agree to round-off; a state-dependent mass and several parameters
included."""

import casadi as ca
import numpy as np
import pytest

import continuation as C

RTOL = 1e-10


def _rel(a, b) -> float:
    """max |a - b| / max |a|."""
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))


def _vdp_mass():
    """M(x) = [[1 + x1^2, 0], [0, 1]], F = Van der Pol with p = (mu, k):
    (1 + x1^2) x1' = x2, x2' = mu (1 - x1^2) x2 - k x1."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    F = ca.Function("F", [x, p], [ca.vertcat(x[1], p[0] * (1 - x[0] ** 2) * x[1]
                                             - p[1] * x[0])])
    M = ca.Function("M", [x, p], [ca.vertcat(ca.horzcat(1 + x[0] ** 2, 0),
                                             ca.horzcat(0, 1))])
    return F, M


def _vdp_mass_action():
    """The state-dependent mass model with its matrix-free product ``M v`` given to the
    field: blocks then differentiate ``mass_action``, the graph route ``M(x) v``."""
    F, M = _vdp_mass()
    x, p, v = ca.SX.sym("x", 2), ca.SX.sym("p", 2), ca.SX.sym("v", 2)
    Mv = ca.Function("Mv", [x, p, v], [ca.vertcat((1 + x[0] ** 2) * v[0], v[1])])
    return C.VectorField(F, M, ("mu", "k"), mass_action=Mv)


def _mx_field(models):
    """The two-parameter mass model as an MX VectorField kept MX (``expand=False``)."""
    F, M = models.mass_model(with_q=True)
    x, p = ca.MX.sym("x", 2), ca.MX.sym("p", 2)
    Fm = ca.Function("F", [x, p], [F(x, p)])
    Mm = ca.Function("M", [x, p], [M(x, p)])
    return C.VectorField(Fm, Mm, ("p", "q"), expand=False)


def _cases(models):
    """``name -> (F, M, params, active, guess, period)``."""
    F_b = models.brusselator()
    F_m, M_m = models.mass_model(with_q=True)
    F_v, M_v = _vdp_mass()
    ring = lambda t: 1.0 + 0.3 * models.van_der_pol_guess(t)
    return {
        "van_der_pol": (models.van_der_pol(), None, {"mu": 1.0}, "mu",
                        models.van_der_pol_guess, 6.6),
        "brusselator": (F_b, None, {"A": 1.0, "B": 3.0}, "B",
                        lambda t: np.array([1.0, 3.0]) + 0.5 * models.van_der_pol_guess(t),
                        7.0),
        "mass_model": (F_m, M_m, {"p": 0.6, "q": 1.0}, "q", ring, 12.0),
        "vdp_mass": (F_v, M_v, {"mu": 0.8, "k": 1.0}, "mu", models.van_der_pol_guess, 8.0),
        "vdp_mass_action": (_vdp_mass_action(), None, {"mu": 0.8, "k": 1.0}, "mu",
                            models.van_der_pol_guess, 8.0),
        "mass_model_mx": (_mx_field(models), None, {"p": 0.6, "q": 1.0}, "p", ring, 12.0),
    }


def _problem(case, jacobian, ntst=7, ncol=3, mesh=None):
    F, M, params, active, guess, period = case
    settings = C.CollocationSettings(ntst=ntst, ncol=ncol, jacobian=jacobian)
    return C.CycleProblem(F, guess, period, params, active, M=M, settings=settings,
                          mesh=mesh)


def _pair(case, **kw):
    return _problem(case, "graph", **kw), _problem(case, "blocks", **kw)


def _perturbed(prob, seed=0):
    """A point off the solution set, with a random phase reference (data D)."""
    rng = np.random.default_rng(seed)
    X = prob.X0 + 0.05 * rng.standard_normal(prob.X0.size)
    return X, rng


@pytest.mark.parametrize("name", ["van_der_pol", "brusselator", "mass_model", "vdp_mass",
                                  "vdp_mass_action", "mass_model_mx"])
def test_residual_and_jacobian_equal_the_graph_ones(models, name):
    mesh = np.r_[0.0, np.cumsum(np.linspace(1.0, 2.0, 7))] / np.sum(np.linspace(1.0, 2.0, 7))
    graph, blocks = _pair(_cases(models)[name], mesh=mesh)
    X, rng = _perturbed(graph)
    D = graph.system.D + np.r_[np.zeros(7), 0.1 * rng.standard_normal(graph.system.D.size - 7)]
    graph.system.D, blocks.system.D = D, D.copy()
    assert _rel(graph.residual(X), blocks.residual(X)) < RTOL
    Jg, Jb = graph.jacobian(X).toarray(), blocks.jacobian(X).toarray()
    assert Jg.shape == Jb.shape
    assert _rel(Jg, Jb) < RTOL
    assert _rel(Jg[:, -2], Jb[:, -2]) < RTOL          # d/dT
    assert _rel(Jg[:, -1], Jb[:, -1]) < RTOL          # d/dp of the active parameter


@pytest.mark.parametrize("name", ["brusselator", "mass_model", "vdp_mass", "vdp_mass_action"])
def test_several_parameter_columns_in_any_order(models, name):
    graph, blocks = _pair(_cases(models)[name], ntst=5, ncol=4)
    X, _ = _perturbed(graph, seed=1)
    Y, p, D = X[:-1], graph.params(X), graph.system.D
    for cols in [(0,), (1,), (0, 1), (1, 0), ()]:
        Jg = graph.system.compiled.jacobian(Y, p, D, cols).toarray()
        Jb = blocks.system.compiled.jacobian(Y, p, D, cols).toarray()
        assert _rel(Jg, Jb) < RTOL
        for j in range(Y.size, Y.size + len(cols)):
            assert _rel(Jg[:, j], Jb[:, j]) < RTOL


def test_pattern_is_fixed_and_caller_arrays_untouched(models):
    _, blocks = _pair(_cases(models)["vdp_mass"])
    X, _ = _perturbed(blocks)
    X_copy = X.copy()
    A, B = blocks.jacobian(X), blocks.jacobian(X + 0.01)
    assert np.array_equal(A.indptr, B.indptr) and np.array_equal(A.indices, B.indices)
    assert A.has_canonical_format
    blocks.residual(X)
    assert np.array_equal(X, X_copy)


def test_kernel_is_built_once_per_field_and_number_of_points(models):
    case = _cases(models)["van_der_pol"]
    a = _problem(case, "blocks", ntst=6, ncol=4)
    b = _problem((a.vf,) + case[1:], "blocks", ntst=8, ncol=3)      # same K = 24
    c = _problem((a.vf,) + case[1:], "blocks", ntst=6, ncol=4)
    assert b.system.compiled.kernel is a.system.compiled.kernel
    assert c.system.compiled is a.system.compiled


@pytest.mark.parametrize("name", ["van_der_pol", "vdp_mass", "vdp_mass_action"])
def test_floquet_multipliers_equal(models, name):
    graph, blocks = _pair(_cases(models)[name], ntst=12, ncol=4)
    X = models.corrected(graph)
    blocks.system.D = graph.system.D.copy()                # the accepted reference
    assert np.max(np.abs(blocks.residual(X))) < 1e-10
    mu_g, mu_b = graph.multipliers(X), blocks.multipliers(X)
    assert np.max(np.abs(mu_g - mu_b)) < RTOL * max(1.0, np.max(np.abs(mu_g)))
    Ag, Ab = graph.transfer_matrices(X, full=True), blocks.transfer_matrices(X, full=True)
    assert _rel(Ag, Ab) < RTOL


@pytest.mark.parametrize("name,adapt", [("van_der_pol", 0), ("vdp_mass", 0),
                                        ("van_der_pol", 3)])
def test_continued_branches_equal(models, name, adapt):
    F, M, params, active, guess, period = _cases(models)[name]
    settings = C.ContinuationSettings(ds=0.1, ds_max=0.3, max_steps=8)
    branches = []
    for jacobian in ("graph", "blocks"):
        s = C.CollocationSettings(ntst=10, ncol=4, jacobian=jacobian, adapt_every=adapt)
        prob = C.CycleProblem(F, guess, period, params, active, M=M, settings=s)
        branches.append(C.continuation(prob, settings=settings))
    g, b = branches
    assert len(g) == len(b) == settings.max_steps + 1
    assert np.array_equal(g.iterations, b.iterations)
    assert abs(g.columns["period"][-1] - b.columns["period"][-1]) < RTOL
    assert abs(g.par(active)[-1] - b.par(active)[-1]) < RTOL


def test_bad_backend_raises_naming_the_field():
    with pytest.raises(ValueError, match="jacobian.*'blocks'.*'graph'"):
        C.CollocationSettings(jacobian="fd")
    assert C.CollocationSettings().jacobian == "blocks"


def test_mass_action_is_validated():
    F, M = _vdp_mass()
    with pytest.raises(ValueError, match="mass_action needs a mass matrix"):
        C.VectorField(F, None, ("mu", "k"), mass_action=M)
    with pytest.raises(ValueError, match="mass_action must be a casadi.Function"):
        C.VectorField(F, M, ("mu", "k"), mass_action=M)
