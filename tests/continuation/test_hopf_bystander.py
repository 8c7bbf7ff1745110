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
