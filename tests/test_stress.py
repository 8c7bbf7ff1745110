"""Stress tests: every run ends in success or a clear, reported failure — never NaN."""
from typing import get_args

import numpy as np
import pytest

from fsicas import Profile, build_model, steady_state
from fsicas.timedomain.outcome import OutcomeKind
from fsicas.timedomain.returns import poincare_returns
from fsicas.linear.hopf import critical_velocity
from fsicas.timedomain.run import run_case
from fsicas.timedomain.integrators import Settings, eigenvector_state, simulate

OUTCOMES = set(get_args(OutcomeKind))


def check_clear(run):
    """Success, or a failure with a message; finite samples; a defined outcome."""
    tr = run.trajectory
    assert np.all(np.isfinite(tr.x)) and np.all(np.isfinite(tr.t))
    assert run.outcome.outcome in OUTCOMES
    assert tr.status == "success" or (tr.status == "failed" and clear_failure(tr))
    return tr


#: What a failed run's message must say: where it failed and, for a closed gap, which
#: contact parameters to raise.
FAILURE_STARTS = ("a gap closed (h_c", "the time integration failed after t = ",
                  "the state is not finite at t = ")


def clear_failure(tr) -> bool:
    """The message says what failed and where; a closed gap names the contact law's
    parameters and what to do with them."""
    if not tr.message.startswith(FAILURE_STARTS):
        return False
    return not tr.gap_closed or ("contact_stiffness" in tr.message and "contact_eps" in tr.message)


@pytest.mark.parametrize("k", [1e4, 1e6, 1e8])
def test_contact_stiffness_range(k, damped_scene_u7, impact_settings):
    """eps/H = 1e-2, U* = 7: a soft law (1e4) cannot stop the tip before the gap closes
    (energy estimate in docs/simulate.md); the stiff one (1e8) must hold the impacts."""
    scene = damped_scene_u7.replace(contact=True, contact_stiffness=k, contact_eps=1e-2)
    tr = check_clear(run_case(scene, 3.0, settings=impact_settings))
    if k == 1e4:
        assert tr.status == "failed" and tr.gap_closed
    if k == 1e8:
        assert tr.status == "success"


@pytest.mark.parametrize("eps", [1e-2, 1e-3, 1e-4])
def test_contact_regularization_range(eps, damped_scene_u7, impact_settings):
    scene = damped_scene_u7.replace(contact=True, contact_stiffness=1e8, contact_eps=eps)
    run = run_case(scene, 3.0, settings=impact_settings)
    tr = check_clear(run)
    assert run.outcome.contact          # contact is reached (and reported) in every case
    if tr.status == "failed":
        assert tr.gap_closed and "contact_stiffness" in tr.message


def test_asymmetric_channel(damped_scene_u6_5):
    scene = damped_scene_u6_5.replace(channel1=Profile.constant(0.055), channel2=Profile.constant(0.045))
    run = run_case(scene, 10.0, settings=Settings(rtol=1e-8, atol=1e-10))
    check_clear(run)
    assert run.trajectory.status == "success"
    assert abs(run.model.deflection(run.steady.x, [1.0])[0]) > 1e-5   # statically bent
    assert run.outcome.outcome in {"lco", "contact", "unsettled"}


def test_reversed_mean_flow(damped_scene_u7):
    run = run_case(damped_scene_u7.replace(ustar=-6.5), 5.0, settings=Settings(rtol=1e-8, atol=1e-10))
    tr = check_clear(run)
    assert tr.x[0, -2:].sum() < 0                                      # flow from x = 1 to 0
    assert tr.status == "success"


@pytest.mark.parametrize("mstar", [0.05, 1.0, 50.0])
def test_mass_ratio_range(mstar, damped_scene_u7):
    """At 1.2 U*_c(M*) every run grows (no decay) and ends clearly."""
    scene = damped_scene_u7.replace(mstar=mstar)
    onset = critical_velocity(scene, build_model(scene), ustar_max=40.0)
    assert onset is not None
    u_c = onset.ustar
    run = run_case(scene.replace(ustar=1.2 * u_c), 10.0,
                   settings=Settings(rtol=1e-8, atol=1e-10), model=None)
    check_clear(run)
    assert run.outcome.outcome in {"lco", "contact"}


@pytest.mark.slow
def test_long_run_without_drift(damped_scene_u6_5):
    """>= 500 periods of the U* = 6.5 cycle: period, amplitude and mean flow do not drift."""
    run = run_case(damped_scene_u6_5, 70.0, settings=Settings(rtol=1e-9, atol=1e-11),
                   stop_early=False)
    tr = check_clear(run)
    times, idx = poincare_returns(tr.t, tr.tip)
    periods = np.diff(times)
    assert periods.size >= 500
    amp = np.array([np.ptp(tr.tip[a:b]) / 2 for a, b in zip(idx[:-1], idx[1:])])
    early, late = slice(100, 150), slice(-50, None)
    assert np.mean(periods[late]) == pytest.approx(np.mean(periods[early]), rel=1e-5)
    assert np.mean(amp[late]) == pytest.approx(np.mean(amp[early]), rel=1e-4)


@pytest.mark.slow
def test_many_modes_n80_linear_growth(damped_scene_u7):
    """N = 80 (IDAS): early growth still matches the leading eigenvalue."""
    from fsicas.linear.stability import eigenvalues
    scene = damped_scene_u7.replace(modes=80)
    model = build_model(scene)
    steady = steady_state(scene, model)
    x0, lam = eigenvector_state(model, steady, 1e-6)
    tr = simulate(model, steady, 0.6, x0=x0, settings=Settings(method="idas", rtol=1e-9, atol=1e-14,
                                                               dt_out=2e-4, chunk=0.2))
    assert tr.status == "success", tr.message
    y = tr.tip - model.deflection(steady.x, [1.0])[0]
    k = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:]) & (y[1:-1] > 0)) + 1
    rate = np.polyfit(tr.t[k], np.log(y[k]), 1)[0]
    assert rate == pytest.approx(lam.real, rel=1e-2)
    assert lam == pytest.approx(eigenvalues(model, steady)[0], rel=1e-10)
