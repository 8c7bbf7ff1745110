"""Quadrature control of time integration: a contact-free cycle near a wall is repeated
on enough nodes, and its amplitude then equals that of a fixed fine rule."""
import pytest

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
