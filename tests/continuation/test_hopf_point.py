"""hopf_point: Newton on the Hopf system from a guess (no branch needed)."""
import casadi as ca
import pytest

import continuation as C


def brusselator():
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    A, B = p[0], p[1]
    return ca.Function("F", [x, p], [ca.vertcat(A - (B + 1) * x[0] + x[0] ** 2 * x[1],
                                                B * x[0] - x[0] ** 2 * x[1])])


def test_hopf_point_from_a_rough_guess():
    """B = 1 + A^2, omega = A; start 3 % off in B, 10 % off in omega and in the state."""
    problem = C.EquilibriumProblem(brusselator(), [1.6, 2.0], {"A": 1.5, "B": 3.15}, "B")
    h = C.hopf_point(problem, [1.6, 2.0], omega=1.35)
    assert h.status == "converged" and h.kind == "hopf"
    assert h.params["B"] == pytest.approx(3.25, abs=1e-12)
    assert h.params["A"] == 1.5
    assert h.data["omega"] == pytest.approx(1.5, abs=1e-12)
    assert h.x == pytest.approx([1.5, 3.25 / 1.5], abs=1e-12)
    assert h.data["l1"] < 0


def test_hopf_point_rejects_bad_frequency():
    problem = C.EquilibriumProblem(brusselator(), [1.5, 2.0], {"A": 1.5, "B": 3.0}, "B")
    with pytest.raises(ValueError, match="omega"):
        C.hopf_point(problem, [1.5, 2.0], omega=-1.0)
