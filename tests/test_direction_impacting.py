"""Impacting cycles of reversed flow (U* < 0; docs/cycles.md, "Reversed flow"): the speed
bounds and direction of the continuation against the closed-form steady pressure drop,
the refusals, each route's cycle against a settled time integration at the same U*, and
``fsicas lco --direction reverse --through-contact``."""
import json
from types import SimpleNamespace

import numpy as np
import pytest

from fsicas.cli import main
from fsicas.cli.cycles import COARSE_MESH
from fsicas.cycles import StartCycle, impacting_cycles
from fsicas.cycles.impacting import ImpactSettings, cycle_from_trajectory
from fsicas.cycles.impacting_collocation import CollocationImpactSettings
from fsicas.linear.adapter import PI_SCALE, speed_window
from fsicas.model import build_model
from fsicas.model.contact import gaps
from fsicas.scene import Scene
from fsicas.timedomain.integrators import Settings
from fsicas.timedomain.run import run_case

#: the contact law of the impacting branches (docs/cycles.md)
IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)
#: reversed flow flutters first at low friction (f = 0.02, M* = 1: a subcritical Hopf
#: point near U* = -0.41; the paper's f = 0.14 diverges first)
REVERSED = dict(mstar=1.0, friction=0.02, modes=4)


def _closed_form_pi(scene, ustar):
    """Π = Δp/(M* PI_SCALE) of the straight symmetric channel's steady state,
    Δp = M* U*|U*| ((K0 + KL)/2 + 2 f/H*) (docs/model.md)."""
    dp = scene.mstar * ustar * abs(ustar) * ((scene.k0 + scene.kl) / 2
                                             + 2 * scene.friction / scene.hstar)
    return dp / (scene.mstar * PI_SCALE)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_speed_window_bounds_and_direction_follow_the_flow(sign):
    """The Π bounds of the speeds [0.3, 2] are those of the closed-form steady states at
    U* = ±0.3 and ±2 in increasing order, [0, 2] starts at Π = 0, and ``direction`` = +1
    (towards larger |U*|) is an increasing Π for forward flow, a decreasing one for
    reversed flow."""
    scene = Scene(ustar=sign * 1.0, **REVERSED)
    model = build_model(scene)
    (lo, hi), way = speed_window(scene, model, 0.3, 2.0, 1)
    ends = sorted(_closed_form_pi(scene, sign * u) for u in (0.3, 2.0))
    assert lo == pytest.approx(ends[0], rel=1e-12) and hi == pytest.approx(ends[1], rel=1e-12)
    assert way == sign and speed_window(scene, model, 0.3, 2.0, -1)[1] == -sign
    (lo, hi), _ = speed_window(scene, model, 0.0, 2.0)
    assert (lo, hi) == ((0.0, hi) if sign > 0 else (lo, 0.0))


def test_reversed_impacting_cycles_refuse_signed_bounds_and_a_forward_start():
    """The bounds are speeds (a negative ustar_max is refused, naming both), and a start
    cycle whose pressure drop belongs to the other direction is refused, both before
    any integration."""
    scene = Scene(ustar=-0.6, **REVERSED, **IMPACT)
    start = StartCycle(np.zeros(scene.modes * 2 + 2), 4.0, 0.5)
    with pytest.raises(ValueError, match="ustar_min and ustar_max are the speeds"):
        impacting_cycles(scene, start, ustar_max=-3.0)
    for method in ("collocation", "shooting"):
        with pytest.raises(ValueError, match="other flow direction"):
            impacting_cycles(scene, start, method=method)


@pytest.fixture(scope="module")
def reversed_cycle():
    """M* = 1, f = 0.02, N = 4, U* = -0.6 with the contact law of a wider layer (eps/H =
    0.04; at 0.01 the flow alone holds the tip 1.3 eps off the wall, docs/cycles.md): an
    IDAS run of 80 time units (about 25 s) settles (to 1e-5) on a cycle the law's layer
    holds 1.74 eps from the wall, and that cycle as ``cycle_from_trajectory`` finds it."""
    scene = Scene(ustar=-0.6, **REVERSED, **{**IMPACT, "contact_eps": 0.04})
    run = run_case(scene, t_end=80.0, perturbation=0.3,
                   settings=Settings(method="idas", rtol=1e-8, atol=1e-10, dt_out=2e-4))
    assert run.status == "success" and run.outcome.settled
    t, x = run.trajectory.t, run.trajectory.x
    state, period, swings = cycle_from_trajectory(run.model, t, x)
    last = x[t > t[-1] - period]
    y = run.model.tip_deflection(last)
    return SimpleNamespace(scene=run.scene, run=run, swings=swings, amplitude=(y.max() - y.min()) / 2,
                           gap_ratio=gaps(run.model, last).min() / scene.contact_gap,
                           start=StartCycle(state, period, run.steady.pressure_drop))


def _check_against_run(branch, r):
    """The branch's first point is the integrated cycle: U* and Δp of the run (negative),
    period and tip amplitude to 1e-5 (the run settled to 1e-5), minimal gap to 1e-3
    relative (both on the 101 points along the beam), stable, as the run found it."""
    assert r.swings == 1
    p = branch.points[0]
    assert p.ustar == pytest.approx(-0.6, abs=1e-8) and p.pressure_drop < 0
    assert p.pressure_drop == pytest.approx(r.run.steady.pressure_drop, rel=1e-9)
    assert abs(p.period / r.start.period - 1) < 1e-5
    assert abs(p.tip_amplitude / r.amplitude - 1) < 1e-5
    assert abs(p.gap_ratio / r.gap_ratio - 1) < 1e-3 and 1.5 < p.gap_ratio < 2
    assert p.stable and max(np.abs(p.nontrivial_multipliers)) < 0.5
    assert all(q.ustar < 0 for q in branch.points)


@pytest.mark.slow
def test_reversed_cycle_by_collocation_is_the_integrated_one(reversed_cycle):
    """Adaptive collocation from the integrated cycle at U* = -0.6 converges to it
    (independent route: the IDAS run) and continues to larger |U*|; on NTST = 400 (at
    eps/H = 0.01 the default 200 left the error indicator at 0.5: the flow through the
    narrow gap at the tip is sharp in time) the indicator is below the CLI's "too
    coarse" 0.1."""
    br = impacting_cycles(reversed_cycle.scene, reversed_cycle.start,
                          settings=CollocationImpactSettings(max_points=2, ntst=400))
    assert br.status == "max_points" and len(br.points) == 2
    _check_against_run(br, reversed_cycle)
    assert br.points[1].ustar < br.points[0].ustar          # towards larger speed
    assert br.max_error_estimate < COARSE_MESH


@pytest.mark.slow
def test_reversed_cycle_by_shooting_is_the_integrated_one(reversed_cycle):
    """Multiple shooting (24 segments) from the integrated cycle at U* = -0.6 converges to
    it and continues to larger |U*|."""
    br = impacting_cycles(reversed_cycle.scene, reversed_cycle.start, method="shooting",
                          settings=ImpactSettings(max_points=2, segments=24))
    assert br.status == "max_points" and len(br.points) == 2
    _check_against_run(br, reversed_cycle)
    assert br.points[1].ustar < br.points[0].ustar


@pytest.mark.slow
def test_lco_through_contact_of_reversed_flow(capsys):
    """``fsicas lco --direction reverse --through-contact``: the contact-free branch from
    the reversed Hopf point reaches the wall, and the impacting branch starts from its
    last cycle 3 eps clear of the wall, its U* negative, exit status 0."""
    code = main(["lco", "--direction", "reverse", "--ustar", "1", "--mstar", "1",
                 "--friction", "0.02", "--modes", "4", "--ustar-max", "3",
                 "--through-contact", "--impact-points", "2", "--json", "-q"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["status"] == "contact"
    assert out["contact"]["ustar"] < 0 and out["hopf"]["ustar_crit"] < 0
    imp = out["impacting"]
    assert imp["status"] == "max_points" and len(imp["points"]) == 2
    assert imp["start_ustar"] < 0 and all(p["ustar"] < 0 for p in imp["points"])
    assert imp["points"][0]["gap_ratio"] == pytest.approx(3.0, abs=0.1)
