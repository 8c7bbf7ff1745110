"""Lifted matrices ``A(p) + P D(x, p) L``: batched evaluation against AD of the field."""

import casadi as ca
import numpy as np
import pytest

import continuation as C
from continuation._cycles.blocks import BlockCollocationSystem, point_kernel
from continuation._casadi.lifted import LiftedBatch


def galerkin(n=6, K=9, seed=0):
    """``F = A(p) x + P g(z)``, ``z = (L1 x, L2 x)``, ``g`` nodal in two variables, and a
    state-dependent mass ``M = I + P_m diag(1 + 0.1 z1^2) L1``; returns the pieces."""
    rng = np.random.default_rng(seed)
    L = rng.normal(size=(2 * K, n)) * (rng.random((2 * K, n)) < 0.7)   # some exact zeros
    P = rng.normal(size=(n, 2 * K)) / K
    Pm = rng.normal(size=(n, K)) / K
    x, p, v = ca.MX.sym("x", n), ca.MX.sym("p", 2), ca.MX.sym("v", n)
    z = ca.MX.sym("z", 2 * K)
    z1, z2 = z[:K], z[K:]
    g = ca.vertcat(p[0] * ca.sin(z1) * z2, z1 ** 2 - p[1] * ca.tanh(z2))
    lift = lambda e: ca.substitute(e, z, ca.mtimes(ca.DM(L), x))
    A = ca.diag(-1 - p[1] * ca.DM(np.arange(n)))
    F = ca.mtimes(A, x) + ca.mtimes(ca.DM(P), lift(g))
    m = 1 + 0.1 * z1 ** 2
    M = ca.DM.eye(n) + ca.mtimes(ca.DM(Pm), ca.mtimes(ca.diag(lift(m)), ca.DM(L[:K])))
    jac = C.Lifted(ca.Function("D", [x, p], [lift(ca.jacobian(g, z))]), P, L,
                   ca.Function("A", [p], [A]))
    mass = C.Lifted(ca.Function("Dm", [x, p], [lift(ca.diag(m))]), Pm, L[:K],
                    ca.Function("I", [p], [ca.DM.eye(n)]))
    Mv = ca.mtimes(M, v)
    mvx = ca.jacobian(Mv, x)
    return dict(x=x, p=p, v=v, F=F, M=M, Mv=Mv, jac=jac, mass=mass, mvx=mvx, n=n)


def test_batch_equals_ad_of_the_field_at_every_point():
    s = galerkin()
    K, n = 7, s["n"]
    rng = np.random.default_rng(1)
    X, p = rng.normal(size=(K, n)), np.array([0.7, 0.4])
    J_ad = ca.Function("J", [s["x"], s["p"]], [ca.jacobian(s["F"], s["x"])])
    M_ad = ca.Function("M", [s["x"], s["p"]], [s["M"]])
    for lifted, ref in ((s["jac"], J_ad), (s["mass"], M_ad)):
        batch = LiftedBatch(lifted, K)(X, p)
        for k in range(K):
            exact = np.array(ref(X[k], p))
            assert np.max(np.abs(batch[k] - exact)) < 1e-13 * np.max(np.abs(exact))
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
    Y = rng.normal(size=s["n"] * ntst * ncol + 1)
    D = np.concatenate([np.full(ntst, 1 / ntst), rng.normal(size=s["n"] * ntst * ncol)])
    P = np.array([0.7, 0.4])
    systems = [BlockCollocationSystem(point_kernel(vf, ntst * ncol), ntst, ncol)
               for vf in (plain, lifted)]
    J = [system.jacobian(Y, P, D, [1]) for system in systems]
    assert abs(J[0] - J[1]).max() < 1e-13 * abs(J[0]).max()
    # the dense interval blocks of the condensed solver (lifted matrices taken dense)
    for system in systems:
        blocks = system.interval_jacobian(Y, P, D, [1]).toarray()
        assert np.max(np.abs(blocks - J[0].toarray())) < 1e-13 * abs(J[0]).max()


def test_lifted_of_mismatched_shapes_is_refused():
    x, p = ca.MX.sym("x", 3), ca.MX.sym("p", 1)
    D = ca.Function("D", [x, p], [ca.MX(4, 5)])
    with pytest.raises(ValueError, match="P must be 3 x 4 and L 5 x 3"):
        C.Lifted(D, np.zeros((3, 5)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="A must map p"):
        C.Lifted(D, np.zeros((3, 4)), np.zeros((5, 3)), ca.Function("A", [p], [ca.MX(2, 2)]))
