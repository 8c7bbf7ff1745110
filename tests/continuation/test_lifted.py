"""Lifted matrices ``A(p) + P D(x, p) L``: their functions and the collocation Jacobians of
a field that has them against AD of the plain field (their batched evaluation:
``test_internals_compiled``)."""

import casadi as ca
import numpy as np
import pytest

import continuation as C

from .conftest import galerkin


def test_lifted_function_equals_ad_of_the_field():
    s = galerkin()
    K = 7
    X, p = np.random.default_rng(1).normal(size=(K, s["n"])), np.array([0.7, 0.4])
    for lifted, ref in s["by_ad"]:
        for k in range(K):
            exact = np.array(ref(X[k], p))
            assert np.max(np.abs(np.array(lifted.function()(X[k], p)) - exact)) \
                < 1e-13 * np.max(np.abs(exact))


def test_a_vector_field_with_lifted_matrices_gives_the_plain_collocation_jacobian():
    """Same residual Jacobian (and so Newton steps and multipliers) with the lifted ``M``,
    ``dF/dx`` and ``d(M v)/dx`` as with AD of the plain ``F``, ``M`` and ``M v``."""
    s = galerkin()
    fun = lambda name, args, out: ca.Function(name, args, [out])
    x, p, v = s["x"], s["p"], s["v"]
    mvx = C.Lifted(fun("D", [x, p, v], ca.jacobian(s["Mv"], x)), np.eye(s["n"]), np.eye(s["n"]))
    plain = C.VectorField(fun("F", [x, p], s["F"]), fun("M", [x, p], s["M"]), ("a", "b"),
                          expand=False, mass_action=fun("Mv", [x, p, v], s["Mv"]))
    lifted = C.VectorField(fun("F", [x, p], s["F"]), s["mass"], ("a", "b"), expand=False,
                           mass_action=fun("Mv", [x, p, v], s["Mv"]), jacobian=s["jac"],
                           mass_action_jacobian=mvx)
    assert set(lifted.lifted) == {"M", "Fx", "Mvx"}
    ntst, ncol = 4, 3
    rng = np.random.default_rng(3)
    X = np.concatenate([rng.normal(size=s["n"] * ntst * ncol + 1), [0.4]])
    orbit = rng.normal(size=(8, s["n"]))
    problems = [C.CycleProblem(vf, orbit, 6.0, {"a": 0.7, "b": 0.4}, "b",
                               settings=C.CollocationSettings(ntst=ntst, ncol=ncol, backend="mx"))
                for vf in (plain, lifted)]
    J = [problem.jacobian(X) for problem in problems]
    assert abs(J[0] - J[1]).max() < 1e-13 * abs(J[0]).max()
    # the dense interval blocks of the condensed solver (lifted matrices taken dense)
    for problem in problems:
        blocks = problem.interval_jacobian(X).toarray()
        assert np.max(np.abs(blocks - J[0].toarray())) < 1e-13 * abs(J[0]).max()


def test_lifted_of_mismatched_shapes_is_refused():
    x, p = ca.MX.sym("x", 3), ca.MX.sym("p", 1)
    D = ca.Function("D", [x, p], [ca.MX(4, 5)])
    with pytest.raises(ValueError, match="P must be 3 x 4 and L 5 x 3"):
        C.Lifted(D, np.zeros((3, 5)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="A must map p"):
        C.Lifted(D, np.zeros((3, 4)), np.zeros((5, 3)), ca.Function("A", [p], [ca.MX(2, 2)]))
