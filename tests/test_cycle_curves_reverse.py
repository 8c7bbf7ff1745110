"""Curves of cycles for reversed flow (U* < 0): the grazing curve against a direct cycle
continuation to first contact at one of its M*, and the curves' "lowest U*" read in speed
(against the mirror image of forward curves)."""

import numpy as np
import pytest

from fsicas import Scene
from fsicas.cycles.collocation import continue_cycles
from fsicas.cycles.curves import (CurveMap, CurvePoint, CurveSettings, CycleCurve,
                                  expected_outcomes, grazing_curve, lowest_ustar)

#: A reversed flow leaving the channel as a jet at the root (k0 = 1) and entering at the
#: tip (kl = 0.5): at M* = 0.1 (N = 6) it diverges at U* = -1.31, and its first Hopf point,
#: where the cycles are born, is at U* = -8.24.
REVERSED = Scene(mstar=0.1, ustar=-1.0, hstar=0.1, friction=0.14, k0=1.0, kl=0.5, zeta=0.01,
                 modes=6)


def _first_contact(run) -> float:
    contacts = [sp for sp in run.branch.special("contact") if sp.status == "converged"]
    assert contacts, run.branch.message
    return contacts[0].record["ustar"]


@pytest.mark.slow     # 2-3 min: two cycle branches to the wall and the curve
def test_reversed_grazing_curve_against_a_direct_continuation_to_first_contact():
    """The curve (Newton on the cycle with min gap = eps, continued in log10 M* and a
    negative Π) passes through the branch's first contact at its seed and, at its last
    point's M*, through the first contact of a cycle branch continued there from its own
    Hopf point (a user event located on the U* branch)."""
    run = continue_cycles(REVERSED, ustar_max=20)
    curve = grazing_curve(REVERSED, run=run, ustar_max=20,
                          settings=CurveSettings(mstar_min=0.09, mstar_max=0.115, max_points=6))
    assert curve.seed.ustar == pytest.approx(_first_contact(run), rel=1e-8)
    u = curve.column("ustar")
    assert np.all(u < 0) and np.all(np.abs(curve.column("gap_ratio") - 1) < 1e-8)
    point = max(curve.points, key=lambda p: abs(np.log(p.mstar / REVERSED.mstar)))
    assert abs(np.log(point.mstar / REVERSED.mstar)) > 0.05
    direct = continue_cycles(REVERSED.replace(mstar=point.mstar), ustar_max=20)
    # each is a collocation on its own mesh (NTST = 20): measured 8.8e-5 apart; the direct
    # first contact moves by 5.4e-5 with NTST = 40, and at NTST = 40 curve and direct
    # branch agree to 1.6e-5 (at the curve's end M* = 0.1138): the mesh's error
    assert point.ustar == pytest.approx(_first_contact(direct), rel=2e-4)


def _curve(ustars, mstars) -> CycleCurve:
    points = [CurvePoint(m, u, 1.0, 0.1, 1.0, True) for u, m in zip(ustars, mstars)]
    return CycleCurve("grazing", points[0], points, ("bound", "bound"), "", 0.0)


def test_lowest_speed_and_expected_outcomes_of_reversed_curves_mirror_forward_ones():
    """Reversed curves are read in speed: the mirror image (U* -> -U*) of forward
    curves gives the mirrored lowest U* and the same expected outcomes."""
    m = np.array([0.5, 1.0, 2.0])
    forward = [_curve([6.0, 7.0, 9.0], m), _curve([8.0, 6.5, 8.5], m)]
    mirrored = [_curve(-c.column("ustar"), m) for c in forward]
    floor = np.array([5.0, 6.8, 5.0])
    assert lowest_ustar(forward, m, floor) == pytest.approx([6.0, 7.0, 8.5])
    assert lowest_ustar(mirrored, m, -floor) == pytest.approx([-6.0, -7.0, -8.5])
    u = np.array([4.0, 6.9, 8.0, 9.0])
    ms = np.array([0.5, 1.0, 2.0, 2.0])
    ahead = expected_outcomes(CurveMap(forward, [], [], [], 0.0), lambda q: np.full(q.shape, 5.0),
                              u, ms)
    back = expected_outcomes(CurveMap(mirrored, [], [], [], 0.0), lambda q: np.full(q.shape, -5.0),
                             -u, ms)
    assert ahead == back == ["decay", "contact", "lco", "contact"]
