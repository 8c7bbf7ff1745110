"""Quadrature control of time integration: a contact-free cycle near a wall, and an
impacting run, are repeated on enough nodes, and then agree with a fixed fine rule."""
from dataclasses import replace

import numpy as np
import pytest

from fsicas.model.accuracy import IMPACT_QUADRATURE_TOL
from fsicas.timedomain.impact_map import MAP_SCENE
from fsicas.timedomain.integrators import Settings
from fsicas.timedomain.run import run_case

SETTINGS = Settings(rtol=1e-9, atol=1e-11, dt_out=2e-3, chunk=1.0)


@pytest.fixture(scope="module")
def near_wall():
    """M* = 3, U* = 9.35 (1.17 U*_c), N = 10: a contact-free cycle whose closest approach
    is 40 eps; on the default 40 nodes its quadrature error is 6e-6."""
    return MAP_SCENE.replace(mstar=3.0, ustar=9.35)


def test_cycle_near_the_wall_is_repeated_on_enough_nodes(near_wall):
    plain = run_case(near_wall, 30.0, settings=SETTINGS, quadrature_tol=None)
    controlled = run_case(near_wall, 30.0, settings=SETTINGS)
    fine = run_case(near_wall.replace(quad_nodes=160), 30.0, settings=SETTINGS, quadrature_tol=None)
    assert {plain.outcome.outcome, controlled.outcome.outcome, fine.outcome.outcome} == {"lco"}
    assert plain.model.scene.n_quad == 40 and plain.quadrature_error > 1e-6
    assert controlled.model.scene.n_quad > 40 and controlled.quadrature_error <= 1e-8
    assert controlled.to_json()["quadrature_nodes"] == controlled.model.scene.n_quad
    # against the fixed fine rule: the controlled amplitude to 1e-8, the plain one 1e-6 off
    reference = fine.outcome.tip_amplitude
    assert abs(controlled.outcome.tip_amplitude / reference - 1) < 1e-8
    assert abs(plain.outcome.tip_amplitude / reference - 1) > 1e-6


def test_decay_is_not_repeated(near_wall):
    run = run_case(near_wall.replace(ustar=6.0), 30.0, settings=SETTINGS)
    assert run.outcome.outcome == "decay" and run.model.scene.n_quad == 40


def test_quadrature_tol_is_checked(near_wall):
    with pytest.raises(ValueError, match="quadrature_tol"):
        run_case(near_wall, 1.0, quadrature_tol=2.0)


def test_auto_tolerance_follows_the_settling_tolerance(near_wall):
    """'auto': the settling tolerance (1e-5 at rtol 1e-8): the M* = 3 cycle's error of
    6e-6 is then below it and the run stays on the default nodes; at rtol 1e-9 it is not."""
    loose = run_case(near_wall, 30.0, settings=Settings(rtol=1e-8, atol=1e-10, dt_out=2e-3, chunk=1.0))
    assert loose.outcome.outcome == "lco" and loose.model.scene.n_quad == 40
    assert 1e-6 < loose.quadrature_error < 1e-5


IMPACTING = MAP_SCENE.replace(mstar=1.0, ustar=8.5, modes=4, contact=True, contact_stiffness=1e8,
                              contact_eps=1e-2)
IMPACT_SETTINGS = Settings(method="idas", rtol=1e-8, atol=1e-10, dt_out=2e-4, chunk=0.25)


@pytest.fixture(scope="module")
def impacting_runs():
    """N = 4, U* = 8.5, k* = 1e8, eps/H = 1e-2 from a large perturbation: impacts from
    t = 0.5 on; the run controlled (default), on the default 28 nodes, and on twice the
    nodes the control chose."""
    once = lambda scene, tol: run_case(scene, 0.7, settings=IMPACT_SETTINGS, perturbation=0.3,
                                       stop_early=False, quadrature_tol=tol)
    controlled = once(IMPACTING, "auto")
    fine = IMPACTING.replace(quad_nodes=2 * controlled.model.scene.n_quad)
    return controlled, once(IMPACTING, None), once(fine, None)


def test_impacting_run_is_repeated_on_enough_nodes(impacting_runs):
    """The control applies to runs with the contact law (IMPACT_QUADRATURE_TOL): the
    controlled run (112 nodes) has its tip within 1.5e-5 of H*/2 of that on twice its
    nodes over the run, where the default rule's was 5e-3 off."""
    controlled, plain, fine = impacting_runs
    assert controlled.outcome.contact
    assert controlled.quadrature_tol == pytest.approx(IMPACT_QUADRATURE_TOL)
    assert controlled.model.scene.n_quad > 28 >= plain.model.scene.n_quad
    assert controlled.quadrature_error <= IMPACT_QUADRATURE_TOL < plain.quadrature_error
    assert controlled.status == "success" and controlled.warnings == []
    scale = IMPACTING.hstar / 2
    error = lambda run: np.max(np.abs(run.trajectory.tip - fine.trajectory.tip)) / scale
    assert error(controlled) < 5e-5 and error(controlled) < 1e-2 * error(plain)   # 1.5e-5, 5e-3


def test_estimate_above_its_tolerance_is_not_success(impacting_runs):
    """A run held to a tolerance its estimate exceeds says "unconverged", with a warning."""
    _, plain, _ = impacting_runs
    assert plain.status == "success" and plain.quadrature_tol is None
    strict = replace(plain, quadrature_tol=plain.quadrature_error / 2)
    assert strict.status == "unconverged" and strict.to_json()["status"] == "unconverged"
    assert "exceeds its tolerance" in strict.warnings[0] and strict.to_json()["warnings"]


def test_a_run_not_repeated_says_its_estimate(impacting_runs):
    """``repeat=False``: the run on the scene's nodes, judged against the tolerance (the
    same trajectory as the plain run, now "unconverged" with its warning)."""
    _, plain, _ = impacting_runs
    judged = run_case(IMPACTING, 0.7, settings=IMPACT_SETTINGS, perturbation=0.3,
                      stop_early=False, repeat=False)
    assert judged.model.scene.n_quad == plain.model.scene.n_quad == 28
    assert np.array_equal(judged.trajectory.x, plain.trajectory.x)
    assert judged.quadrature_tol == pytest.approx(IMPACT_QUADRATURE_TOL)
    assert judged.status == "unconverged" and "raise quad_nodes" in judged.warnings[0]
