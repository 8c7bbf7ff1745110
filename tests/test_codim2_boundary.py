"""Codimension-two points of the paper's Hopf curves (Fig. 2): the generalized Hopf points
against a dense scan of l1 of the one-parameter onset along the boundary (the
independent route), a double Hopf point met from both of its branches."""
import warnings

import numpy as np
import pytest

from fsicas import build_model
from fsicas.linear.codim2 import codim_two_points
from fsicas.linear.hopf import first_onset
from fsicas.paper import PAPER_SCENE


def _scan_zeros(model, mstars) -> list:
    """M* where l1 of the onset changes sign while its frequency stays on one curve
    (a jump of omega is a mode switch, not a Bautin point), by linear interpolation."""
    onsets = [first_onset(PAPER_SCENE.replace(mstar=m), model) for m in mstars]
    l1 = np.array([o.l1 for o in onsets])
    omega = np.array([o.omega for o in onsets])
    zeros = []
    for i in np.flatnonzero(l1[:-1] * l1[1:] < 0):
        if abs(omega[i + 1] - omega[i]) < 0.05 * omega[i]:
            zeros.append(mstars[i] - l1[i] * (mstars[i + 1] - mstars[i]) / (l1[i + 1] - l1[i]))
    return zeros


@pytest.mark.slow     # 15 s: the Hopf curve with l1 at every point, and the scan
def test_bautin_points_of_the_boundary_match_the_scan_of_l1():
    """The Hopf curve through the onset at M* = 0.5 (subcritical, l1 > 0) meets l1 = 0 on
    the boundary at M* ~ 0.25 (below it the onset is subcritical) and ~ 0.77 (the end of
    the subcritical stretch that begins at the mode switch near M* = 0.41); its other
    Bautin points lie on the curve where it is not the lowest onset."""
    model = build_model(PAPER_SCENE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        onset = first_onset(PAPER_SCENE.replace(mstar=0.5), model)
        assert onset.kind == "flutter" and onset.l1 > 0
        points = codim_two_points(PAPER_SCENE, model, onset, (np.log10(0.2), 0.0),
                                  kinds=("gh",))
        scan = _scan_zeros(model, np.geomspace(0.22, 0.95, 60))
    on = [p for p in points if p.on_boundary]
    assert len(on) == len(scan) == 2
    for p, m in zip(on, scan):
        assert p.mstar == pytest.approx(m, rel=2e-4)
        assert p.l2 < 0       # the fold-of-cycles curve lies on the subcritical side
    assert any(not p.on_boundary for p in points)


@pytest.mark.slow     # 15 s: the Hopf curve with the eigenvalues at every point
def test_a_double_hopf_point_met_from_both_branches():
    """The Hopf curve through the onset at M* = 1.2 folds and crosses itself at M* ~ 1.59
    (above the boundary there): met along either branch, the point is the same and its
    coefficients swap roles (``omega1 <-> omega2``, ``p11 <-> p22``, ``p12 <-> p21``),
    computed from the other pair's eigenvectors each time."""
    model = build_model(PAPER_SCENE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        onset = first_onset(PAPER_SCENE.replace(mstar=1.2), model)
        points = codim_two_points(PAPER_SCENE, model, onset, (0.0, np.log10(2.0)),
                                  kinds=("hh",))
    a, b = points
    assert (a.mstar, a.ustar) == pytest.approx((b.mstar, b.ustar), rel=1e-8)
    assert not a.on_boundary
    swap = {"omega1": "omega2", "p11": "p22", "p12": "p21", "theta": "delta"}
    for k, other in {**swap, **{v: k for k, v in swap.items()}}.items():
        assert a.data[k] == pytest.approx(b.data[other], rel=1e-7)
    assert a.data["simple"] and b.data["simple"]
    assert a.data["stable_torus"] == b.data["stable_torus"]
