"""Two-parameter continuation of Hopf and fold curves, codimension-two points."""

import casadi as ca
import numpy as np
import pytest

import continuation as C


def run(problem, **kw):
    base = dict(ds=0.02, ds_max=0.1, max_steps=100)
    base.update(kw)
    return C.continuation(problem, settings=C.ContinuationSettings(**base))


def one_hopf(branch):
    (h,) = branch.special("hopf")
    assert h.status == "converged"
    return h


@pytest.mark.parametrize("direction", [1, -1])
def test_brusselator_hopf_curve_matches_formula(models, direction):
    # Hopf curve B = 1 + A^2, omega = A (trace and determinant of J).
    A0 = 1.5
    prob = C.EquilibriumProblem(models.brusselator(), [A0, 1 / A0], {"A": A0, "B": 1.0}, "B")
    h = one_hopf(run(prob, bounds={"B": (0, 5)}))
    curve = run(C.HopfCurveProblem.from_point(prob, h, "A"), ds=0.05, ds_max=0.2,
                direction=direction, bounds={"A": (0.3, 3.0)})
    A, B = curve.par("A"), curve.par("B")
    assert curve.status == "bound"
    assert (A.max() > 2.9) if direction == 1 else (A.min() < 0.4)
    assert np.max(np.abs(B - (1 + A**2))) < 1e-8
    assert np.max(np.abs(curve.columns["omega"] - A)) < 1e-8
    assert np.allclose(curve.x, np.column_stack([A, B / A]), atol=1e-8)
    assert curve.special_points == []


def bt_model():
    # x' = y, y' = b1 + b2 x + x^2 + x y (Bogdanov-Takens normal form, s = +1).
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    return ca.Function("F", [x, p], [ca.vertcat(x[1], p[0] + p[1] * x[0] + x[0]**2
                                                + x[0] * x[1])])


def test_bogdanov_takens_on_hopf_and_fold_curves():
    """Equilibria x^2 + b2 x + b1 = 0, y = 0; J = [[0, 1], [b2 + 2x, x]].

    Hopf: trace x = 0 -> b1 = 0 with omega^2 = -b2 (b2 < 0); fold: b1 = b2^2/4,
    x = -b2/2; both end at the Bogdanov-Takens point b1 = b2 = 0.
    """
    F = bt_model()
    x0 = (1 - np.sqrt(3)) / 2  # root of x^2 - x - 1/2 (b1 = -1/2, b2 = -1)
    prob = C.EquilibriumProblem(F, [x0, 0.0], {"b1": -0.5, "b2": -1.0}, "b1")
    br = run(prob, bounds={"b1": (-1, 0.3)})
    h = one_hopf(br)
    assert abs(h.params["b1"]) < 1e-12 and abs(h.data["omega"] - 1) < 1e-12
    (fold,) = br.special("fold")
    assert abs(fold.params["b1"] - 0.25) < 1e-12 and abs(fold.x[0] - 0.5) < 1e-10

    hc = run(C.HopfCurveProblem.from_point(prob, h, "b2"), bounds={"b2": (-1.5, 0.5)})
    assert np.max(np.abs(hc.par("b1"))) < 1e-10
    kappa = hc.columns["kappa"]
    assert np.max(np.abs(kappa + hc.par("b2"))) < 1e-10  # omega^2 = -b2, then neutral saddle
    (bt,) = hc.special("bt")
    assert bt.status == "converged" and abs(bt.params["b2"]) < 1e-10

    fc = run(C.FoldCurveProblem.from_point(prob, fold, "b2"), bounds={"b2": (-1.5, 0.5)})
    b1, b2 = fc.par("b1"), fc.par("b2")
    assert np.max(np.abs(b1 - b2**2 / 4)) < 1e-10 and np.max(np.abs(fc.x[:, 0] + b2 / 2)) < 1e-10
    (bt2,) = fc.special("bt")
    assert bt2.status == "converged"
    assert abs(bt2.params["b2"]) < 1e-8 and abs(bt2.params["b1"]) < 1e-8


def test_generalized_hopf_where_l1_changes_sign(models):
    # z' = (mu + i) z + nu z|z|^2 - z|z|^4: Hopf curve mu = 0, l1 = 2 nu -> GH at nu = 0.
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    r2 = x[0]**2 + x[1]**2
    rhs = ca.vertcat(p[0] * x[0] - x[1], x[0] + p[0] * x[1]) * 1 + (p[1] * r2 - r2**2) * x
    F = ca.Function("F", [x, p], [rhs])
    prob = C.EquilibriumProblem(F, [0.0, 0.0], {"mu": -0.2, "nu": -0.5}, "mu")
    h = one_hopf(run(prob, bounds={"mu": (-1, 0.2)}))
    assert h.data["l1"] == pytest.approx(-1.0, rel=1e-10)
    hc = run(C.HopfCurveProblem.from_point(prob, h, "nu"), bounds={"nu": (-1, 1)})
    (gh,) = hc.special("gh")
    assert gh.status == "converged" and abs(gh.params["nu"]) < 1e-10
    assert np.max(np.abs(hc.par("mu"))) < 1e-12


@pytest.mark.parametrize("kind", ["hh", "zh"])
def test_double_hopf_and_zero_hopf_reports(kind):
    # oscillator (mu1 +- i) plus either a second one (mu2 +- 2i), crossing at mu2 = 0,
    # or a fold mode w' = mu2 + w^2 (eigenvalue 2w, w = -+sqrt(-mu2)): the Hopf curve
    # turns at mu2 = 0 where the real eigenvalue crosses zero (zero-Hopf).
    n = 4 if kind == "hh" else 3
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", 2)
    r2 = x[0]**2 + x[1]**2
    osc = ca.vertcat(p[0] * x[0] - x[1] - x[0] * r2, x[0] + p[0] * x[1] - x[1] * r2)
    if kind == "hh":
        s2 = x[2]**2 + x[3]**2
        rest = ca.vertcat(p[1] * x[2] - 2 * x[3] - x[2] * s2, 2 * x[2] + p[1] * x[3] - x[3] * s2)
    else:
        rest = p[1] + x[2]**2 + 0.3 * x[0] * x[2]
    F = ca.Function("F", [x, p], [ca.vertcat(osc, rest)])
    x0 = np.zeros(n) if kind == "hh" else np.array([0, 0, -np.sqrt(0.4)])
    prob = C.EquilibriumProblem(F, x0, {"mu1": -0.3, "mu2": -0.4}, "mu1")
    h = one_hopf(run(prob, bounds={"mu1": (-1, 0.3)}))
    hc = run(C.HopfCurveProblem.from_point(prob, h, "mu2"), bounds={"mu2": (-1, 0.5)})
    (sp_,) = hc.special(kind)
    assert sp_.status == "converged" and abs(sp_.params["mu2"]) < 1e-8
    assert not [s for s in hc.special_points if s.kind != kind]


def test_curve_problem_validation(models):
    vf = C.VectorField(models.brusselator(), None, ("A", "B"))
    with pytest.raises(ValueError, match="free"):
        C.HopfCurveProblem(vf, [1.0, 2.0], {"A": 1.0, "B": 2.0}, 1.0, ("A", "A"))
    with pytest.raises(ValueError, match="omega"):
        C.HopfCurveProblem(vf, [1.0, 2.0], {"A": 1.0, "B": 2.0}, -1.0, ("A", "B"))
    with pytest.raises(ValueError, match="unknown parameter"):
        C.FoldCurveProblem(vf, [1.0, 2.0], {"A": 1.0, "B": 2.0}, ("A", "Q"))


def test_hopf_curve_with_state_dependent_mass(models):
    F, M = models.mass_model(with_q=True)
    prob = C.EquilibriumProblem(F, [1.0, 1.0], {"p": 0.0, "q": 1.0}, "p", M=M)
    h = one_hopf(run(prob, bounds={"p": (-1, 1)}))
    assert abs(h.params["p"] - 0.5) < 1e-12 and abs(h.data["omega"] - 0.5) < 1e-12
    curve = run(C.HopfCurveProblem.from_point(prob, h, "q"), ds=0.05, ds_max=0.2,
                bounds={"q": (0.0, 3.0)}, newton=C.NewtonSettings(tol=1e-12))
    p, q = curve.par("p"), curve.par("q")
    assert q.max() > 2.8
    assert np.max(np.abs(p - 1 / (1 + q))) < 1e-10
    assert np.max(np.abs(curve.columns["omega"] - 1 / np.sqrt(2 * (1 + q)))) < 1e-10


def test_sparse_and_dense_eigenvalues_agree():
    """Shift-invert Arnoldi and dense QZ on a 1-D reaction-diffusion Jacobian (the
    linear field ``M x' = J x``) against SciPy's dense QZ."""
    import scipy.linalg
    import scipy.sparse as sp
    n = 120
    rng = np.random.default_rng(5)
    lap = sp.diags([1.0, -2.0, 1.0], [-1, 0, 1], shape=(n, n)) * 50.0
    J = sp.csc_matrix(lap + sp.diags(rng.uniform(-1, 1, n)) + sp.diags([0.7], [1], (n, n))
                      - sp.diags([0.7], [-1], (n, n)))
    M = sp.csc_matrix(sp.diags(1 + rng.uniform(0, 1, n)))
    x, p = ca.SX.sym("x", n), ca.SX.sym("p")
    prob = C.EquilibriumProblem(ca.Function("F", [x, p], [ca.mtimes(ca.DM(J.toarray()), x)]),
                                np.zeros(n), {"p": 0.0}, "p",
                                M=ca.Function("M", [x, p], [ca.DM(M.toarray())]))

    def eigenvalues(eigen):
        return prob.eigenvalues(prob.X0, C.ContinuationSettings(eigen=eigen))

    dense = eigenvalues(C.EigenSettings(dense_max=1000))
    sparse = eigenvalues(C.EigenSettings(dense_max=10, nev=6, sigma=0.0))
    reference = scipy.linalg.eigvals(J.toarray(), M.toarray())
    assert np.allclose(np.sort_complex(dense), np.sort_complex(reference), atol=1e-10)
    nearest = reference[np.argsort(np.abs(reference))[:6]]
    assert np.allclose(np.sort_complex(nearest), np.sort_complex(sparse), atol=1e-10)


def _rotation(a):
    c, s = ca.cos(a), ca.sin(a)
    return ca.vertcat(ca.horzcat(c, 0, s, 0), ca.horzcat(0, c, 0, s),
                      ca.horzcat(-s, 0, c, 0), ca.horzcat(0, -s, 0, c))


@pytest.mark.parametrize("kind", ["hopf", "fold"])
def test_curve_restarts_when_the_critical_space_rotates(kind):
    """F(x) = Q(a)^T g(Q(a) x): the critical eigenvector(s) rotate from span(e1, e2) to
    span(e3, e4) as a goes 0 -> pi/2, orthogonal to the initial reference vector c. The
    curve (mu = 0, omega = 1 for Hopf) continues past a = pi/2 only because c is rebuilt."""
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 2)
    Q = _rotation(p[1])
    y = ca.mtimes(Q, x)
    if kind == "hopf":
        r2 = y[0]**2 + y[1]**2
        g = ca.vertcat(p[0] * y[0] - y[1] - y[0] * r2, y[0] + p[0] * y[1] - y[1] * r2,
                       -y[2] + y[0]**2, -2 * y[3])
        x0, mu0 = [0, 0, 0, 0], -0.2
    else:
        g = ca.vertcat(p[0] - y[0]**2, -y[1] + y[0]**2, -y[2], -2 * y[3])
        x0, mu0 = [0.5, 0.25, 0, 0], 0.25
    F = ca.Function("F", [x, p], [ca.mtimes(Q.T, g)])
    prob = C.EquilibriumProblem(F, x0, {"mu": mu0, "a": 0.0}, "mu")
    br = run(prob, direction=1 if kind == "hopf" else -1, bounds={"mu": (-1, 0.3)})
    (point,) = br.special(kind)
    cls = C.HopfCurveProblem if kind == "hopf" else C.FoldCurveProblem
    curve = run(cls.from_point(prob, point, "a"), ds=0.05, ds_max=0.1, max_steps=300,
                bounds={"a": (-1, 3.5)})
    assert curve.status == "bound" and curve.par("a").max() > 3.4
    assert curve.stats["restarts"] >= 1
    assert np.max(np.abs(curve.par("mu"))) < 1e-10
    if kind == "hopf":
        assert np.max(np.abs(curve.columns["omega"] - 1)) < 1e-10
