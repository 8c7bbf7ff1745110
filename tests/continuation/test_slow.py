"""Deep checks (run with ``pytest -m slow``): larger problems, independent routes."""

import importlib.util
import pathlib

import casadi as ca
import numpy as np
import pytest
import scipy.linalg

import continuation as C

pytestmark = pytest.mark.slow


def chain_model(N=60, eps=1.0):
    """q'' + D q' + K q = u S q - q^3 with M(x) = blockdiag(I, I + eps diag(q) W diag(q)
    + 0.05 ones/N): n = 2N, dense state-dependent mass, flutter-like Hopf."""
    n = 2 * N
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", 2)
    q, qd = x[:N], x[N:]
    rng = np.random.default_rng(0)
    K = ca.DM(np.diag(np.arange(1, N + 1) ** 2 * 1.0))
    S = np.zeros((N, N))
    S[0, 1], S[1, 0] = 3.0, -3.0
    F = ca.Function("F", [x, p], [ca.vertcat(
        qd, -ca.mtimes(K, q) - 0.02 * qd + p[0] * ca.mtimes(ca.DM(S), q) - q**3)])
    W = ca.DM(0.01 * rng.standard_normal((N, N)))
    M22 = ca.SX.eye(N) + p[1] * ca.mtimes(ca.diag(q), ca.mtimes(W, ca.diag(q))) \
        + 0.05 * ca.DM(np.ones((N, N))) / N
    M = ca.Function("M", [x, p], [ca.diagcat(ca.SX.eye(N), M22)])
    return F, M, n


def test_dense_state_dependent_mass_hopf_and_l1_independent_routes():
    F, M, n = chain_model()
    prob = C.EquilibriumProblem(F, np.zeros(n), {"u": 0.0, "eps": 1.0}, "u", M=M)
    br = C.continuation(prob, settings=C.ContinuationSettings(
        ds=0.1, ds_max=0.2, max_steps=40, bounds={"u": (0, 5)}))
    (h,) = br.special("hopf")
    assert h.status == "converged"
    # independent check of the location: dense QZ eigenvalues at the located point
    x, p = h.x, np.array([h.params["u"], 1.0])
    vf = prob.vf
    ev = scipy.linalg.eigvals(vf.jac_x(x, p).toarray(), vf.mass(x, p).toarray())
    top = ev[np.argmax(ev.real)]
    assert abs(top.real) < 1e-10 and abs(abs(top.imag) - h.data["omega"]) < 1e-10
    # independent route for l1: xdot = M(x)^{-1} F through an MX linear solve
    xs, ps = ca.MX.sym("x", n), ca.MX.sym("p", 2)
    f = ca.Function("f", [xs, ps], [ca.solve(M(xs, ps), F(xs, ps), "lapackqr")])
    l1_explicit = C.first_lyapunov(C.VectorField(f, None, ("u", "eps")), x, p,
                                   h.data["omega"])
    assert h.data["l1"] == pytest.approx(l1_explicit, rel=1e-8)


def test_benchmark_n1000_matches_discrete_hopf():
    path = pathlib.Path(__file__).parents[2] / "benchmarks" / "bench_continuation.py"
    spec = importlib.util.spec_from_file_location("bench_continuation", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    row = bench.run(500, 100, 1e-10)
    assert row["err_A"] < 1e-11 and row["err_w"] < 1e-11 and row["max_res"] <= 1e-10
