"""``fsicas diagram`` on small scenes: its special points against a direct eigenvalue
scan of the steady states (an independent route: no continuation), its tree file, its
figure and the inputs it refuses."""

import json

import numpy as np
import pytest
from scipy.optimize import brentq

from fsicas import Scene
from fsicas.cli import main
from fsicas.linear.stability import eigenvalues
from fsicas.linear.steady import steady_state
from fsicas.model import build_model


def _run(capsys, *argv):
    code = main(["diagram", *argv, "--json"])
    printed = capsys.readouterr()
    return code, json.loads(printed.out), printed.err


def _crossing(scene, f, lo, hi):
    """The U* in (lo, hi) where ``f(eigenvalues)`` of the steady state changes sign."""
    model = build_model(scene)
    g = lambda u: f(eigenvalues(model, steady_state(scene.replace(ustar=u), model)))  # noqa: E731
    return brentq(g, lo, hi, xtol=1e-12)


def test_flutter_scene_diagram(capsys, tmp_path):
    """N = 3, M* = 1: one Hopf point (the rightmost eigenvalue's real part crosses 0 there,
    found by the scan to 1e-7) and the cycles born there, stable (supercritical)."""
    out, plot = tmp_path / "tree.json", tmp_path / "diagram.png"
    code, result, err = _run(capsys, "--modes", "3", "--ustar-max", "8", "--max-points", "20",
                             "--ntst", "10", "--out", str(out), "--plot", str(plot))
    assert code == 0 and result["status"] == "ok"
    assert "fsicas diagram [" in err and "the diagram up to U* = 8" in err
    steady, cycles = result["branches"]
    assert (steady["kind"], steady["born"], cycles["kind"], cycles["born"]) == \
        ("steady", "start", "cycle", "hopf")
    (hopf,) = steady["special"]
    scan = _crossing(Scene(modes=3), lambda ev: ev.real.max(), 5.0, 5.5)
    assert hopf["label"] == "H" and abs(hopf["ustar"] - scan) < 1e-7
    assert cycles["parent"] == 0 and cycles["ustar_range"][0] > hopf["ustar"]
    tree = json.loads(out.read_text())
    assert "meta" in tree and len(tree["branches"]) == 2
    assert all(tree["branches"][1]["stable"]) and len(tree["branches"][1]["tip"]) == 20
    assert plot.stat().st_size > 0


def test_divergence_bubble_between_two_pitchforks(capsys):
    """H* = 0.2, KL = 0, M* = 30, N = 3: a real eigenvalue crosses 0 at two U* (the scan's
    sign changes of det J); the deflected states join the two branch points in one closed
    branch, found once although it is reached four times."""
    code, result, _ = _run(capsys, "--modes", "3", "--hstar", "0.2", "--kl", "0", "--mstar",
                           "30", "--ustar-max", "3", "--max-points", "10", "--ntst", "10",
                           "--depth", "1")
    assert code == 0
    scene = Scene(modes=3, hstar=0.2, kl=0.0, mstar=30.0)
    det = lambda ev: float(np.prod(ev).real)  # noqa: E731
    low, high = _crossing(scene, det, 1.2, 1.45), _crossing(scene, det, 1.5, 1.8)
    steady = result["branches"][0]
    bps = [p["ustar"] for p in steady["special"] if p["kind"] == "bp"]
    assert np.allclose(bps, [low, high], rtol=0, atol=1e-7)
    bubbles = [b for b in result["branches"] if b["born"] == "bp"]
    assert len(bubbles) == 1 and bubbles[0]["message"].startswith("closed")
    assert np.allclose(bubbles[0]["ustar_range"], [low, high], rtol=0, atol=1e-6)
    assert sum(s["reason"].startswith("retraces") for s in result["skipped"]) >= 3


@pytest.mark.parametrize("argv, named", [
    (["--depth", "9"], "--depth"), (["--ntst", "1"], "--ntst"), (["--ncol", "1"], "--ncol"),
    (["--max-points", "1"], "--max-points"), (["--mstar", "0:1:3"], "--mstar"),
    (["--mstar", "1,1"], "--mstar"), (["--contact"], "--contact"),
    (["--ustar-max", "0.1"], "--ustar-max")])
def test_bad_inputs_are_refused_before_work(capsys, argv, named):
    code = main(["diagram", "--modes", "3", *argv, "--json"])
    printed = capsys.readouterr()
    assert code == 2 and named in json.loads(printed.out)["error"]


def test_an_existing_file_that_is_no_result_is_not_overwritten(capsys, tmp_path):
    notes = tmp_path / "notes.json"
    notes.write_text("my notes")
    code = main(["diagram", "--modes", "3", "--out", str(notes), "--json"])
    assert code == 2 and "notes.json" in json.loads(capsys.readouterr().out)["error"]
    assert notes.read_text() == "my notes"


def test_window_of_mass_ratios(capsys, tmp_path):
    """N = 3, M* in [0.5, 1]: the onset is subcritical at 0.5 and supercritical at 1; the
    generalized Hopf point between them is where l1 of the one-parameter onset (another
    route: the steady branch at fixed M*) changes sign, and the fold-of-cycles curve born
    there lies below the onset (the hysteresis: the cycles fold back before the Hopf
    point) on the subcritical side."""
    from fsicas.linear.hopf import first_onset

    out = tmp_path / "window.json"
    code, result, err = _run(capsys, "--modes", "3", "--mstar", "0.5:1:2", "--max-points", "10",
                             "--ntst", "10", "--out", str(out))
    assert code == 0 and "codimension-two points over M* in [0.5, 1]" in err
    assert [o["kind"] for o in result["onsets"]] == ["flutter", "flutter"]
    (gh,) = result["codim2"]
    assert gh["kind"] == "gh" and gh["on_boundary"] and gh["l2"] < 0
    model = build_model(Scene(modes=3))
    l1 = [first_onset(Scene(modes=3, mstar=gh["mstar"] * f), model, 20.0).l1 for f in (0.99, 1.01)]
    assert l1[0] > 0 > l1[1]
    (curve,) = json.loads(out.read_text())["curves"]
    assert curve["curve"]["kind"] == "fold" and len(curve["curve"]["points"]) >= 5
    lowest = min(curve["curve"]["points"], key=lambda p: p["mstar"])
    onset = first_onset(Scene(modes=3, mstar=lowest["mstar"]), model, 20.0)
    assert lowest["mstar"] < 0.95 * gh["mstar"] and lowest["ustar"] < onset.ustar


@pytest.mark.slow     # 30-70 s: the integration settles slowly (a real eigenvalue near 0)
def test_the_deflected_states_are_where_a_time_integration_settles(capsys, tmp_path):
    """Another route to the bubble's deflected states and their stability: integrated in
    time at U* = 1.48 from the perturbed straight state (unstable there), the beam settles
    on a static deflection; the diagram's stable deflected branch has that tip at 1.48
    (linear interpolation between its points, measured 1.2e-6 apart)."""
    from fsicas.timedomain.run import run_case

    out = tmp_path / "tree.json"
    code, result, _ = _run(capsys, "--modes", "3", "--hstar", "0.2", "--kl", "0", "--mstar",
                           "30", "--ustar-max", "3", "--max-points", "10", "--ntst", "10",
                           "--depth", "1", "--out", str(out))
    (bubble,) = [b for b in json.loads(out.read_text())["branches"] if b["born"] == "bp"]
    ustar, tip = np.array(bubble["ustar"]), np.array(bubble["tip"])
    assert all(bubble["stable"])
    run = run_case(Scene(modes=3, hstar=0.2, kl=0.0, mstar=30.0, ustar=1.48), 600.0,
                   stop_early=False, quadrature_tol=None)
    settled = run.model.tip_deflection(run.trajectory.x)
    assert np.ptp(settled[-50:]) < 1e-12 and settled[-1] > 0.01      # static, deflected
    upper = tip > 0
    order = np.argsort(ustar[upper])
    assert abs(np.interp(1.48, ustar[upper][order], tip[upper][order]) - settled[-1]) < 5e-6


def test_zero_hopf_points_where_the_hopf_curve_meets_the_divergence_curves(capsys):
    """H* = 0.2, KL = 0, N = 3, M* in [1, 30]: the steady problem depends on M* U*^2 only,
    so the divergence curves through the two branch points at M* = 30 (found by the sign
    changes of det J, no continuation) are M* U*^2 = 30 U_d^2; the zero-Hopf points on the
    Hopf curve lie on them, one on each (to 1e-6; measured 8e-11 and 5e-10)."""
    code, result, _ = _run(capsys, "--modes", "3", "--hstar", "0.2", "--kl", "0", "--mstar",
                           "1:30:2", "--max-points", "10", "--ntst", "10")
    assert code == 0 and [o["kind"] for o in result["onsets"]] == ["flutter", "divergence"]
    assert any("divergence curves are not searched" in w for w in result["warnings"])
    scene = Scene(modes=3, hstar=0.2, kl=0.0, mstar=30.0)
    det = lambda ev: float(np.prod(ev).real)  # noqa: E731
    levels = [30.0 * _crossing(scene, det, lo, hi) ** 2 for lo, hi in ((1.2, 1.45), (1.5, 1.8))]
    zh = sorted(p["mstar"] * p["ustar"] ** 2 for p in result["codim2"] if p["kind"] == "zh")
    assert len(zh) == 2 and np.allclose(zh, levels, rtol=1e-6, atol=0)
