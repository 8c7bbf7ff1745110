"""The Hopf system of the flutter field (MX, state-dependent mass, matrix-free mass
action): its structured Jacobian against CasADi AD of its own residual."""
import casadi as ca
import numpy as np
import pytest

import fsicas
from continuation._equilibria.systems import hopf_system
from fsicas.linear.adapter import flutter_field


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
