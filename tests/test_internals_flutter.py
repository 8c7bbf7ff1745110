"""White-box on purpose: continuation's pieces on fsicas' flutter field (MX, state-dependent
mass, matrix-free mass action): the Hopf system's structured Jacobian against CasADi AD
of its own residual; the kinematic rows ``dq/dt = r`` taken out of the interval LUs of its
cycles, against LAPACK on the sparse route's matrix and a branch by SuperLU."""
import casadi as ca
import numpy as np
import pytest

import continuation as C
import fsicas
from continuation._cycles.intervals import KinematicLU
from continuation._driver.newton import factorize
from continuation._equilibria.systems import hopf_system
from continuation._linalg.sparse import append_row
from fsicas.linear.adapter import flutter_field
from fsicas.linear.hopf import critical_velocity, flutter_problem
from fsicas.model import build_model

@pytest.fixture(scope="module")
def field():
    model = fsicas.build_model(fsicas.Scene(mstar=1.0, ustar=5.0, modes=4))
    return model, flutter_field(model)


def _ad_jacobian(system):
    """AD of the compiled residual G(Y, p; D) in Y and p (the route the structured
    Jacobian replaces), as a dense function."""
    g = system._g.fun
    Y, P, D = (ca.MX.sym(n, g.size1_in(i)) for i, n in enumerate("YPD"))
    G = g(Y, P, D)
    return ca.Function("ad", [Y, P, D], [ca.densify(ca.jacobian(G, ca.vertcat(Y, P)))])


def test_structured_hopf_jacobian_with_mass_action_equals_ad(field):
    model, vf = field
    assert vf.mass_action is not None and vf.mass_depends_on_state
    system = hopf_system(vf)
    ad = _ad_jacobian(system)
    st = fsicas.steady_state(fsicas.Scene(mstar=1.0, ustar=5.0, modes=4), model)
    rng = np.random.default_rng(5)
    n, k = vf.n, len(vf.par_names)
    p = np.zeros(k)
    p[0], p[1] = 0.8, 0.1
    values = dict(zip(model.parameter_names, st.p))
    p[2:] = [values[name] for name in vf.par_names[2:]]
    for _ in range(3):
        Y = np.concatenate([st.x + 1e-2 * rng.standard_normal(n), rng.standard_normal(2 * n),
                            [0.7]])
        D = rng.standard_normal(n)
        full = np.asarray(ad(Y, p, D))
        for free in ((0,), (1, 0), tuple(range(k))):
            fast = system.jacobian(Y, p, D, free).toarray()
            ref = np.hstack([full[:, :Y.size], full[:, Y.size + np.array(free)]])
            assert np.allclose(fast, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def test_the_position_rows_leave_the_interval_lus():
    """``dq_n/dt = r_n``: the N position rows of the 2N + 2 are taken out of every
    interval LU by block; the condensed solves equal LAPACK's on the sparse route's
    matrix, and a short branch equals SuperLU's (points, iterations, multipliers)."""
    scene = fsicas.Scene(mstar=1.0, modes=6)             # 14 states: 56-row intervals
    model = build_model(scene)
    hopf = critical_velocity(scene, model)
    eq = flutter_problem(scene, model, hopf.ustar / 2)
    make = lambda solver: C.cycle_from_hopf(eq, hopf.point, dp=1e-3, settings=(
        C.CollocationSettings(ntst=8, ncol=4, linear_solver=solver)))
    prob = make("condensed")
    rng = np.random.default_rng(4)
    X = prob.X0 * (1 + 1e-3 * rng.standard_normal(prob.X0.size))
    tau = rng.standard_normal(X.size)
    A = prob.bordered_jacobian(X, tau)
    lu = factorize(A)
    assert A.J.kinematic.positions.tolist() == [6, 7, 8, 9, 10, 11]
    assert A.J.kinematic.velocities.tolist() == [0, 1, 2, 3, 4, 5]
    assert isinstance(A.J.intervals, KinematicLU)
    dense = append_row(C.CycleProblem.jacobian(prob, X), tau).toarray()
    b = rng.standard_normal((X.size, 2))
    assert np.max(np.abs(lu.solve(b) - np.linalg.solve(dense, b))) < \
        1e-10 * np.max(np.abs(np.linalg.solve(dense, b)))
    settings = C.ContinuationSettings(ds=0.05, ds_max=0.1, max_steps=4)
    a, c = (C.continuation(make(s), settings=settings) for s in ("sparse", "condensed"))
    assert len(a) == len(c) == 5 and np.array_equal(a.iterations, c.iterations)
    assert np.max(np.abs(a.x - c.x)) < 1e-10 * np.max(np.abs(a.x))
    for mu_a, mu_c in zip(a.eigenvalues, c.eigenvalues):   # conjugates in either order
        distance = np.abs(mu_a[:, None] - mu_c[None, :])
        assert max(distance.min(axis=0).max(), distance.min(axis=1).max()) < 1e-9
