"""Fold-of-cycles curves from the generalized Hopf points of the paper's boundary (Fig. 2),
against independent routes: the fold of a one-parameter cycle branch in U* at fixed M*
(located on the arclength by the turn of its tangent, no fold condition) must lie on the
curve, and a curve that leaves one Bautin point and shrinks back onto the Hopf curve must
end at another Bautin point (l1 = 0 on the Hopf curve)."""
import warnings

import numpy as np
import pytest

from fsicas import build_model
from fsicas.cycles.bautin import fold_curves_from_bautin
from fsicas.cycles.collocation import continue_cycles
from fsicas.cycles.curves import CurveSettings
from fsicas.linear.codim2 import codim_two_points
from fsicas.linear.hopf import first_onset
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
    assert [round(f.bautin.mstar, 4) for f in found] == [0.2529, 0.7718]
    assert all(f.bautin.l2 < 0 for f in found)
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
