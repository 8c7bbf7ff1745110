"""The model as a continuation field (fsicas.linear.adapter): its matrix-free mass action
against the assembled mass matrix, and the collocation Jacobian that differentiates it
against CasADi AD of the whole discretized residual with the assembled M."""
import numpy as np
import pytest

import continuation as C
from fsicas import Scene, build_model, critical_velocity
from fsicas.linear.adapter import flutter_field
from fsicas.linear.hopf import flutter_problem


def _rel(a, b) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(a)))


@pytest.mark.parametrize("contact", [False, True])
def test_mass_action_equals_the_assembled_mass_matrix(contact):
    scene = Scene(mstar=0.7, ustar=5.0, modes=4, contact=contact, contact_stiffness=1e8,
                  contact_eps=1e-2)
    model = build_model(scene)
    vf = flutter_field(model)
    rng = np.random.default_rng(1)
    p = np.r_[1.2, np.log10(0.7), rng.random(len(vf.par_names) - 2)]
    for _ in range(5):
        x = 0.01 * rng.standard_normal(vf.n) + np.r_[np.zeros(2 * 4), 0.05, 0.05]
        v = rng.standard_normal(vf.n)
        Mv = np.asarray(vf.mass_action(x, p, v)).ravel()
        assert _rel(vf.mass(x, p) @ v, Mv) < 1e-13


def test_collocation_jacobian_with_mass_action_equals_the_graph_route():
    """N = 4, the cycle start at the first Hopf point, perturbed: the block Jacobian
    (AD of the matrix-free M v) equals AD of the discretized residual with M(x) v."""
    scene = Scene(mstar=1.0, ustar=5.0, modes=4)
    model = build_model(scene)
    hopf = critical_velocity(scene, model)
    problems = [C.cycle_from_hopf(flutter_problem(scene, model, 0.2), hopf.point, dp=1e-3,
                                  settings=C.CollocationSettings(ntst=6, ncol=3, jacobian=j))
                for j in ("graph", "blocks")]
    X = problems[0].X0 + 1e-3 * np.random.default_rng(2).standard_normal(problems[0].X0.size)
    Jg, Jb = (p.jacobian(X).toarray() for p in problems)
    assert _rel(problems[0].residual(X), problems[1].residual(X)) < 1e-12
    assert _rel(Jg, Jb) < 1e-10


@pytest.mark.parametrize("modes", [4, 10])
def test_lifted_collocation_jacobian_equals_the_graph_route_in_contact(modes):
    """The lifted kernel (batched dF/dx, d(M v)/dx, M) equals AD of the discretized
    residual on a profile pressed into the wall (gap below eps at some nodes), with the
    smoothed and with the exact contact law."""
    for smoothing in (0.1, 0.0):
        scene = Scene(mstar=1.0, ustar=5.0, modes=modes, contact=True, contact_stiffness=1e8,
                      contact_eps=1e-2, contact_smoothing=smoothing)
        model = build_model(scene)
        hopf = critical_velocity(scene, model)
        problems = [C.cycle_from_hopf(flutter_problem(scene, model, 0.2), hopf.point, dp=1e-3,
                                      settings=C.CollocationSettings(ntst=6, ncol=3, jacobian=j))
                    for j in ("graph", "blocks")]
        X = problems[0].X0.copy()
        U = X[:-2].reshape(-1, model.n_state)                # node values (r, q, Q)
        y = U[:, modes:2 * modes] @ model.basis.phi          # deflection at the nodes
        U[:, modes:2 * modes] *= (scene.hstar / 2 - 0.5 * scene.contact_gap) / np.abs(y).max()
        assert (scene.hstar / 2 - np.abs(U[:, modes:2 * modes] @ model.basis.phi)).min() \
            < scene.contact_gap
        Jg, Jb = (p.jacobian(X).toarray() for p in problems)
        assert _rel(problems[0].residual(X), problems[1].residual(X)) < 1e-12
        assert _rel(Jg, Jb) < 1e-10
