"""Curves of special cycles of the flutter model in (M*, U*): the grazing curve against
time integration and against the branch's own located first contact, the fold-of-cycles
curve against the Hopf analysis (it ends on the Hopf curve where l1 = 0), the CLI."""

import json

import numpy as np
import pytest

from fsicas import Scene
from fsicas.cycles.collocation import continue_cycles
from fsicas.cycles.curves import CurveSettings, curve_seeds, fold_curves, grazing_curve
from fsicas.linear.hopf import hopf_points
from fsicas.linear.steady import steady_state
from fsicas.model import build_model
from fsicas.model.contact import gaps
from fsicas.timedomain.integrators import Settings, simulate

SCENE = Scene(mstar=1.0, modes=10)


@pytest.fixture(scope="module")
def grazing():
    model = build_model(SCENE)
    run = continue_cycles(SCENE, model)
    curve = grazing_curve(SCENE, run=run, settings=CurveSettings(mstar_min=0.9, mstar_max=1.1,
                                                                 max_points=8))
    return model, run, curve


def test_grazing_curve_passes_through_the_branch_first_contact(grazing):
    """The curve (Newton on the cycle with min gap = eps, continued in M*) against the
    branch's first contact (a user event located on the U* branch by Illinois)."""
    _, run, curve = grazing
    (contact,) = run.branch.special("contact")
    assert curve.seed.mstar == pytest.approx(1.0, rel=1e-12)
    assert curve.seed.ustar == pytest.approx(contact.record["ustar"], rel=1e-8)
    assert np.all(np.abs(curve.column("gap_ratio") - 1) < 1e-8)
    m = curve.column("mstar")
    assert m.min() < 0.95 and m.max() > 1.05 and np.all(np.diff(m) > 0)
    assert curve.status == ("bound", "bound")


def _settled_min_gap(model, state, ustar, period, periods=40, last=4):
    """min gap / eps over the last periods of an IDAS integration of the contact-free
    model at U* from ``state``; 0 when the gap closed (past grazing the beam closes it
    within a few periods, and so it does with the paper's contact law, k* = 1e6)."""
    st = steady_state(model.scene.replace(ustar=ustar), model)
    traj = simulate(model, st, periods * period, x0=state,
                    settings=Settings(rtol=1e-9, atol=1e-11, dt_out=period / 400,
                                      chunk=periods * period))
    if traj.gap_closed:
        return 0.0
    assert traj.status == "success", traj.message
    tail = traj.t >= traj.t[-1] - last * period
    return gaps(model, traj.x[tail]).min() / SCENE.contact_gap


def _crossing_check(scene, point):
    """min gap / eps of integrations from a curve point's state at 0.995 and 1.005 times
    its U* (at its M*)."""
    model = build_model(scene.replace(mstar=point.mstar))
    return [_settled_min_gap(model, point.state, f * point.ustar, point.period)
            for f in (0.995, 1.005)]


def test_integration_just_below_the_curve_stays_off_the_wall_and_just_above_reaches_it(
        grazing):
    """At the curve's last point (M* = 1.1, continued from the seed at M* = 1)."""
    _, _, curve = grazing
    point = curve.points[-1]
    assert point.mstar > 1.05
    below, above = _crossing_check(SCENE, point)
    assert below > 1.0 > above


@pytest.mark.slow
@pytest.mark.parametrize("mstar", [0.3, 3.0])
def test_grazing_curve_against_integration_at_other_mass_ratios(mstar):
    scene = SCENE.replace(mstar=mstar)
    curve = grazing_curve(scene, settings=CurveSettings(mstar_min=mstar / 1.2,
                                                        mstar_max=mstar * 1.2, max_points=4))
    point = curve.points[-1]
    assert point.mstar != pytest.approx(mstar, rel=1e-3)
    below, above = _crossing_check(scene, point)
    assert below > 1.0 > above


def _nearest_hopf(scene, mstar, ustar):
    points = hopf_points(scene.replace(mstar=mstar), ustar_max=1.5 * ustar)
    return min(points, key=lambda h: abs(h.ustar - ustar), default=None)


@pytest.mark.slow
def test_fold_curve_ends_on_the_hopf_curve():
    """Subcritical flutter at M* = 0.6: the fold curve, continued in M* from the cycle
    fold refined by Newton on its minimally extended system, ends both ways where its
    cycles shrink to zero, i.e. on the Hopf curve (U* to 1e-2 relative of a Hopf point
    located independently there). At the upper end l1 vanishes (a generalized Hopf
    point); the lower end is another generalized Hopf point (M* = 0.3199, l2 = +466:
    tests/test_bautin_folds.py), near where the Hopf curve turns back in M* (no Hopf
    point nearby 2 % below that M*)."""
    scene = Scene(mstar=0.6, modes=10)
    (fold,) = fold_curves(scene, settings=CurveSettings(mstar_min=0.2, mstar_max=2.0))
    assert fold.status == ("stopped", "stopped")
    low, high = sorted((fold.points[0], fold.points[-1]), key=lambda p: p.mstar)
    for end in (low, high):
        assert end.ustar == pytest.approx(_nearest_hopf(scene, end.mstar, end.ustar).ustar,
                                          rel=1e-2)
    assert abs(_nearest_hopf(scene, high.mstar, high.ustar).l1) < 0.05
    below = _nearest_hopf(scene, 0.98 * low.mstar, low.ustar)
    assert below is None or abs(below.ustar - low.ustar) > 0.05 * low.ustar


def test_seeds_one_per_piece_of_the_boundary():
    assert curve_seeds([0.4, 1.75, 40.0], 0.1, 10.0) == pytest.approx(
        [0.2, np.sqrt(0.4 * 1.75), np.sqrt(17.5)])
    with pytest.raises(ValueError, match="mstar_min"):
        CurveSettings(mstar_min=2.0, mstar_max=1.0)


def test_cli_grazing(capsys, tmp_path):
    from fsicas.cli import main
    code = main(["grazing", "--mstar", "0.95:1.05:3", "--seeds", "1", "--max-points", "3",
                 "--json", "--plot", str(tmp_path / "curves.png")])
    printed = capsys.readouterr()
    out = json.loads(printed.out)
    # a log (stderr not a terminal) is told of each finished seed by default
    assert "fsicas grazing [" in printed.err and "seed 1/1, the cycle branch at M* = 1:" in printed.err
    assert code == 0 and set(out) >= {"grazing", "fold", "hopf", "seeds", "meta"}
    assert any(p["mstar"] == pytest.approx(1.0) for p in out["grazing"])
    assert all(p["gap_ratio"] == pytest.approx(1.0, abs=1e-8) for p in out["grazing"])
    assert {"mstar", "ustar", "l1"} <= set(out["hopf"][0])
    assert (tmp_path / "curves.png").stat().st_size > 0
    for bad, option in ((["--seeds", "5"], "--seeds"), (["--ntst", "1"], "--ntst"),
                        (["--workers", "0"], "--workers"), (["--ustar-max", "-1"], "--ustar-max")):
        code = main(["grazing", "--mstar", "0.5:2:3", "--json", *bad])
        assert code == 2 and option in json.loads(capsys.readouterr().out)["error"]
