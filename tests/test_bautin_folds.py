"""Fold-of-cycles curves from the generalized Hopf points of the paper's boundary (Fig. 2),
against independent routes: the fold of a one-parameter cycle branch in U* at fixed M*
(located on the arclength by the turn of its tangent, no fold condition) must lie on the
curve, and a curve that leaves one Bautin point and shrinks back onto the Hopf curve must
end at another Bautin point (l1 = 0 on the Hopf curve)."""
import warnings

import numpy as np
import pytest

import continuation as C
from fsicas import build_model
from fsicas.cycles.bautin import fold_curves_from_bautin, torus_curves_from_double_hopf
from fsicas.cycles.collocation import continue_cycles
from fsicas.cycles.curves import CurveSettings
from fsicas.linear.codim2 import codim_two_points
from fsicas.linear.adapter import PI, pi_of
from fsicas.linear.hopf import first_onset, flutter_problem, hopf_points
from fsicas.paper import PAPER_SCENE


@pytest.fixture(scope="module")
def folds():
    model = build_model(PAPER_SCENE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = fold_curves_from_bautin(
            PAPER_SCENE, model, settings=CurveSettings(mstar_min=0.15, mstar_max=1.0,
                                                       max_points=40))
    return model, found


def on_curve(curve, mstar) -> float:
    """U* of ``curve`` at ``mstar``: the cubic in log M* through its four nearest points."""
    lm, u = np.log(curve.column("mstar")), curve.column("ustar")
    k = np.argsort(np.abs(lm - np.log(mstar)))[:4]
    return float(np.polyval(np.polyfit(lm[k] - np.log(mstar), u[k], 3), 0.0))


@pytest.mark.slow     # 30 s the curves, 25 s the two cycle branches
def test_fold_curves_from_the_bautin_points_hold_the_folds_of_cycle_branches(folds):
    model, found = folds
    assert [round(f.point.mstar, 4) for f in found] == [0.2529, 0.7718]
    assert all(f.point.l2 < 0 for f in found)
    for f, mstar in zip(found, (0.22, 0.6)):                 # on the subcritical side
        run = continue_cycles(PAPER_SCENE.replace(mstar=mstar), model, ustar_max=20.0)
        (fold,) = [sp for sp in run.branch.special("fold") if sp.status == "converged"]
        assert on_curve(f.curve, mstar) == pytest.approx(fold.record["ustar"], rel=1e-5)


@pytest.mark.slow
def test_the_fold_curve_from_m_0_77_ends_at_the_other_bautin_point(folds):
    """It runs down to M* ~ 0.29, turns, and shrinks onto the Hopf curve at the Bautin
    point that lies above the boundary (M* ~ 0.32, l2 > 0), located on its own (l1 = 0
    on the Hopf curve)."""
    model, found = folds
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        onset = first_onset(PAPER_SCENE.replace(mstar=0.5), model)
        (other,) = [p for p in codim_two_points(PAPER_SCENE, model, onset, (-0.8, 0.0),
                                                kinds=("gh",)) if not p.on_boundary]
    assert other.l2 > 0
    end, why = found[1].curve.ends()[0]
    assert why == "hopf"              # its cycles shrank below CurveSettings.min_amplitude
    assert (end.mstar, end.ustar) == pytest.approx((other.mstar, other.ustar), rel=1e-3)
    assert found[1].curve.column("mstar").min() < 0.29


@pytest.mark.slow     # 45 s: the Hopf curve over M* 24-33, the torus curve, a cycle branch
def test_torus_curve_from_the_double_hopf_point_holds_a_branch_torus_bifurcation():
    """From the double Hopf point of the boundary at M* = 28.44: at the M* of the torus
    curve's last point, the cycle branch from the Hopf point of the same frequency,
    continued in Π with its Floquet multipliers, has its torus bifurcation (detected by
    the count of multipliers outside the unit circle, located on |mu| - 1; no
    NeimarkSacker condition) at the curve's Π."""
    model = build_model(PAPER_SCENE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (found,) = torus_curves_from_double_hopf(PAPER_SCENE, model, settings=CurveSettings(
            mstar_min=24.0, mstar_max=33.0, max_points=6))
        end = found.curve.points[-1]
        scene = PAPER_SCENE.replace(mstar=end.mstar)
        pi_end = pi_of(scene, model, end.ustar)
        hopf = min(hopf_points(scene, model, ustar_max=20.0),
                   key=lambda h: abs(h.omega - found.point.omega))
        cycle = C.cycle_from_hopf(flutter_problem(scene, model, 0.2), hopf.point, dp=1e-4,
                                  settings=C.CollocationSettings(ntst=20, ncol=4,
                                                                 floquet="product"))
        branch = C.continuation(cycle, settings=C.ContinuationSettings(
            ds=0.01, ds_max=0.05, max_steps=200, direction=cycle.hopf_direction,
            bounds={PI: (0.0, 1.05 * pi_end)}))
    assert found.point.mstar == pytest.approx(28.44, abs=5e-3) and end.mstar > 28.445
    (ns,) = [sp for sp in branch.special("ns") if sp.status == "converged"]
    assert ns.params[PI] == pytest.approx(pi_end, rel=1e-8)
