"""Control of the flow-quadrature error near the wall (fsicas.model.accuracy.adequate_model,
CycleSettings.quadrature_tol), against references on fixed fine rules: the same
computation with more nodes, never the controlled code's own estimate."""
import numpy as np
import pytest

import continuation as C
import fsicas
from fsicas.cycles import CycleSettings, cycle_branch
from fsicas.cycles.gauge import PolynomialExtrema
from fsicas.cycles.impacting_collocation import (CollocationImpactSettings,
                                                 impacting_collocation_problem)
from fsicas.linear.hopf import critical_velocity
from fsicas.model import build_model
from fsicas.model.accuracy import QUADRATURE_TOL, adequate_model, relative_error
from fsicas.scene import MAX_QUAD_NODES

#: M* = 1, N = 4 (28 nodes by default), contact-free; eps/H = 1e-3
SCENE = fsicas.Scene(mstar=1.0, zeta=0.01, modes=4)
#: the fixed fine rule of the references: 16x the default nodes
FINE = 16 * SCENE.n_quad


def _bent(model, steady, gap_left):
    """The steady state with the tip pushed by mode 1 to ``gap_left`` of H*/2 from the wall."""
    x, n = steady.x.copy(), model.n_modes
    x[n] += (1 - gap_left) * model.scene.hstar / 2 / model.tip.phi[0, 1]
    return x


@pytest.fixture(scope="module")
def wall_states():
    scene = SCENE.replace(ustar=6.5)
    model = build_model(scene)
    st = fsicas.steady_state(scene, model)
    return model, st, {g: _bent(model, st, g) for g in (0.5, 0.01)}


def test_adequate_model_raises_the_nodes_near_the_wall_only(wall_states):
    """Far from the wall (tip gap H*/4) the model itself is adequate; at a tip gap of
    1 % of H*/2 the nodes are doubled, and the returned model's F is within tol of F on
    a rule of 4x its nodes (an independent, fixed rule), where the default's is not."""
    model, st, x = wall_states
    far, error = adequate_model(model, x[0.5][None], st.p)
    assert far is model and error < 1e-12
    near, error = adequate_model(model, x[0.01][None], st.p)
    assert near.scene.n_quad > model.scene.n_quad and near.scene.modes == model.n_modes
    assert error <= QUADRATURE_TOL
    reference = build_model(SCENE.replace(quad_nodes=4 * near.scene.n_quad))
    true = lambda m: relative_error(np.array(reference.rhs(x[0.01], st.p)),
                                    np.array(m.rhs(x[0.01], st.p)))
    assert true(near) <= QUADRATURE_TOL < 1e-3 * true(model)
    assert adequate_model(model, x[0.01][None], st.p)[0] is near          # built once


def test_adequate_model_warns_at_the_node_cap(wall_states):
    """Doubling 1200 nodes would pass the cap: the model on the cap is returned, with a
    warning and the estimate of the 1200 nodes."""
    model, st, x = wall_states
    start = build_model(model.scene.replace(quad_nodes=1200))
    with pytest.warns(RuntimeWarning, match="MAX_QUAD_NODES"):
        capped, error = adequate_model(start, x[0.01][None], st.p, tol=1e-30)
    assert capped.scene.n_quad == MAX_QUAD_NODES and error > 1e-30


def test_settings_validate_the_tolerance():
    assert CycleSettings(quadrature_tol=None).quadrature_tol is None
    with pytest.raises(ValueError, match="quadrature_tol"):
        CycleSettings(quadrature_tol=0.0)


def _branch(quad_nodes, tol, hopf):
    """The branch on a uniform mesh (``adapt_every = 0``: every run solves the same
    discrete problem, so only the quadrature tells them apart)."""
    return cycle_branch(SCENE.replace(quad_nodes=quad_nodes), hopf=hopf,
                        settings=CycleSettings(adapt_every=0, quadrature_tol=tol))


def _reference_amplitude(point, model) -> float:
    """Tip half-amplitude of the cycle at ``point``'s pressure drop on ``model``: the
    cycle integrated from the point's state, corrected at that Π by collocation on the
    branch's uniform mesh (NTST = 20, NCOL = 4)."""
    settings = CollocationImpactSettings(ntst=20, ncol=4, mesh_passes=0, adapt_every=0)
    problem = impacting_collocation_problem(model.scene, point.state, point.period,
                                            point.pressure_drop, model=model, settings=settings)
    fixed_pi = np.zeros(problem.X0.size)
    fixed_pi[-1] = 1.0
    X = C.correct(problem, problem.X0, fixed_pi, C.NewtonSettings(tol=1e-10)).X
    y_min, y_max = PolynomialExtrema(model).tip(problem, X)
    return (y_max - y_min) / 2


def test_controlled_branch_matches_the_fine_rule_at_the_wall():
    """N = 4: with the default 28 nodes the first-contact U* is 7.3e-5 off the fine rule
    (448 nodes) and the amplitude of the last point before contact (gap 2.8 eps) 2.9e-4;
    with the control both are within 1e-6 (measured 2e-13 and 1.6e-7: that point, where
    the error first exceeded tol, is computed on 112 nodes), the nodes rising along the
    branch."""
    hopf = critical_velocity(SCENE, build_model(SCENE))
    fine_model = build_model(SCENE.replace(quad_nodes=FINE))
    reference = _branch(FINE, None, hopf)
    rel = lambda a, b: abs(a / b - 1)
    for tol, within in ((None, False), (QUADRATURE_TOL, True)):
        branch = _branch(None, tol, hopf)
        near = branch.points[-1]
        assert branch.status == "contact" and near.gap_ratio < 5
        errors = (rel(branch.contact.ustar, reference.contact.ustar),
                  rel(near.tip_amplitude, _reference_amplitude(near, fine_model)))
        if within:
            assert max(errors) < 1e-6, errors
            nodes = branch.column("quadrature_nodes")
            assert nodes[0] == SCENE.n_quad and np.all(np.diff(nodes) >= 0) and nodes[-1] > nodes[0]
        else:
            assert min(errors) > 1e-5, errors
