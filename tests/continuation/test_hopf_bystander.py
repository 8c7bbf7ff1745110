"""Regression: Hopf location must track the eigenvalue that crosses, not the one nearest
the imaginary axis (a lightly damped bystander mode, as in undamped structures)."""
import casadi as ca
import pytest

import continuation as C


def test_hopf_located_next_to_a_lightly_damped_bystander():
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 1)
    mu = p[0]
    r2 = x[0] ** 2 + x[1] ** 2
    rhs = ca.vertcat((mu - 1) * x[0] - x[1] - x[0] * r2,
                     x[0] + (mu - 1) * x[1] - x[1] * r2,
                     -1e-3 * x[2] - 10 * x[3],
                     10 * x[2] - 1e-3 * x[3])
    F = ca.Function("F", [x, p], [rhs])
    problem = C.EquilibriumProblem(F, [0.0] * 4, {"mu": 0.0}, "mu")
    settings = C.ContinuationSettings(ds=0.4, ds_max=0.4, max_steps=20, bounds={"mu": (-1, 3)})
    branch = C.continuation(problem, settings=settings)
    (hopf,) = branch.special("hopf")
    assert hopf.status == "converged"
    assert hopf.params["mu"] == pytest.approx(1.0, abs=1e-12)
    assert hopf.data["omega"] == pytest.approx(1.0, abs=1e-12)
    assert hopf.data["l1"] == pytest.approx(-2.0, rel=1e-10)  # l1 = 2 a / omega, a = -1


def _two_oscillators(mu1, mu2, w2=3.0):
    """Two Hopf normal forms, ``x' = (mu - mu_k) x - w_k y - x r²`` etc.: Hopf points at
    mu = mu1 (omega 1) and mu = mu2 (omega w2), l1 = -2/omega each."""
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 1)
    rows = []
    for (a, b), c, w in (((0, 1), mu1, 1.0), ((2, 3), mu2, w2)):
        r2 = x[a] ** 2 + x[b] ** 2
        rows += [(p[0] - c) * x[a] - w * x[b] - x[a] * r2, w * x[a] + (p[0] - c) * x[b] - x[b] * r2]
    return ca.Function("F", [x, p], [ca.vertcat(*rows)])


def test_two_hopf_points_in_one_step_are_both_located():
    """Two pairs cross within one step (mu = 0.93 and 1.02, steps of 0.4, no eigenvalue step
    limit): the unstable count jumps by 4, the step is split at its middle until each part
    holds one crossing, and both Hopf points are located exactly, in order (one of them
    was missed before)."""
    problem = C.EquilibriumProblem(_two_oscillators(0.93, 1.02), [0.0] * 4, {"mu": 0.0}, "mu")
    settings = C.ContinuationSettings(ds=0.4, ds_max=0.4, max_steps=10, bounds={"mu": (-1, 3)},
                                      eigen_step=0.0)
    branch = C.continuation(problem, settings=settings)
    hopf = branch.special("hopf")
    assert [h.status for h in hopf] == ["converged", "converged"]
    assert [h.params["mu"] for h in hopf] == pytest.approx([0.93, 1.02], abs=1e-12)
    assert [h.data["omega"] for h in hopf] == pytest.approx([1.0, 3.0], abs=1e-10)
    assert branch.stats["split_steps"] >= 1
