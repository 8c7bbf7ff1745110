"""The contact law: exact kink and its smooth (softplus) variant."""
import casadi as ca
import numpy as np
import pytest

from fsicas import Scene, build_model, steady_state
from fsicas.model.contact import ramp
from fsicas.timedomain.integrators import Settings, simulate

SCENE = Scene(mstar=1.0, ustar=7.0, zeta=0.01, modes=6, contact=True, contact_stiffness=1e7,
              contact_eps=1e-2)


def test_softplus_ramp_bounds():
    v = np.linspace(-1e-3, 1e-3, 2001)
    exact = np.array(ca.evalf(ramp(ca.DM(v), 0.0))).ravel()
    smooth = np.array(ca.evalf(ramp(ca.DM(v), 0.1 * 1e-4))).ravel()
    assert np.array_equal(exact, np.maximum(0, v))
    width = 1e-5
    assert np.all(smooth >= exact) and np.max(smooth - exact) == pytest.approx(width * np.log(2), rel=1e-12)
    far = np.abs(v) > 10 * width
    assert np.all(smooth[far] - exact[far] <= width * np.exp(-10) * 1.0001)


def test_smoothing_validated():
    with pytest.raises(ValueError, match="contact_smoothing"):
        SCENE.replace(contact_smoothing=-0.1)


def tip_states(model, steady, offsets):
    """States bent in mode 1 so the gap at the outermost contact node is eps + offset."""
    n = model.n_modes
    eps = model.scene.contact_gap
    phi_end = np.max(model.contact_basis.phi[0])
    out = []
    for d in offsets:
        x = steady.x.copy()
        x[n] = (model.scene.hstar / 2 - eps - d) / phi_end
        out.append(x)
    return out


def test_both_laws_have_a_continuous_jacobian_at_first_contact():
    """Across first contact at the tip, dF_r1/dq1 of the impact load changes by less the
    closer the states: the softplus is smooth, and the exact law's kink is integrated
    exactly (the load ``∫ k max(0, g) phi`` is C^1 in the state, its patch growing from
    zero length). A pointwise rule would jump by a node's penalty stiffness
    k w1² w phi_1(x)²; the scale here is that of a cell, k w1² Δ phi_1(1)². The flow's
    own part (k* = 0) is subtracted."""
    jumps, scale = {}, {}
    for smoothing in (0.0, 0.05):
        scene = SCENE.replace(contact_smoothing=smoothing)
        model = build_model(scene)
        steady = steady_state(scene, model)
        free = steady.p.copy()
        free[model.index("contact_stiffness")] = 0.0       # the flow's part, to subtract
        n = model.n_modes
        for offset in (1e-9, 1e-10):
            states = tip_states(model, steady, [-offset * scene.contact_gap, offset * scene.contact_gap])
            J = [np.array(model.jac_rhs(x, steady.p))[0, n] - np.array(model.jac_rhs(x, free))[0, n]
                 for x in states]
            jumps[smoothing, offset] = abs(J[0] - J[1])
        cell = np.min(np.diff(model.impact_rule.x))
        scale[smoothing] = (scene.contact_stiffness * model.basis.omega[0] ** 2 * cell
                            * np.max(model.contact_basis.phi[0]) ** 2)
    for smoothing in (0.0, 0.05):
        assert jumps[smoothing, 1e-9] < 1e-5 * scale[smoothing]
        assert jumps[smoothing, 1e-10] < 0.15 * jumps[smoothing, 1e-9]


def test_smooth_trajectory_converges_to_the_exact_one():
    model0 = build_model(SCENE)
    steady = steady_state(SCENE, model0)
    settings = Settings(rtol=1e-9, atol=1e-11, dt_out=1e-4, chunk=0.5)
    ref = simulate(model0, steady, 2.2, settings=settings)
    assert ref.status == "success"
    errors = []
    for smoothing in (0.1, 0.01):
        scene = SCENE.replace(contact_smoothing=smoothing)
        model = build_model(scene)
        tr = simulate(model, steady_state(scene, model), 2.2, settings=settings)
        errors.append(np.max(np.abs(tr.tip - ref.tip)))
    assert errors[1] < errors[0] / 3      # the smooth law converges to the kink as width -> 0
    assert errors[1] < 1e-2 * SCENE.hstar / 2


def test_ramp_numpy_equals_casadi():
    """The one contact law serves NumPy (gauges, energy) and CasADi (the model) alike."""
    v = np.linspace(-1e-3, 1e-3, 2001)
    for width in (0.0, 1e-5):
        symbolic = np.array(ca.evalf(ramp(ca.DM(v), width))).ravel()
        assert np.allclose(ramp(v, width), symbolic, rtol=1e-15, atol=1e-20)
