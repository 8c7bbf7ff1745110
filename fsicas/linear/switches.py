"""Mode switches of the stability boundary: found on the traced curves, located on their
defining equations.

:func:`find_switches` scans the envelope of the traced curves (:class:`Envelope`) on 801
points of log10 M* and bisects each change of the lowest piece between curve samples.
Each one is then solved for (:func:`located_switches`), with every evaluation an exact
onset (Newton on the Hopf system, :func:`continuation.hopf_point`, or a divergence solved
in U*), not an interpolation of the samples:

- a **crossing** of two curves (a double-Hopf point: the same steady state has two
  imaginary pairs; or a Hopf and a divergence curve; U*_c is continuous, the frequency
  jumps) is the root in log10 M* of
  ``U*_a(M*) - U*_b(M*)``, the onsets of the two curves at that M* (Brent's method);
- a **fold** of a curve in M* (the window of instability between its two Hopf points
  closes, U*_c jumps) is the extremum of log10 M* along the curve, parametrized by the
  pressure drop Π near the fold: log10 M*(Π) is the Hopf point at fixed Π with log10 M*
  free (bounded Brent search); the U* above it is the exact onset of the lowest curve
  just past it.

A switch whose solve fails keeps its bracketed value (``located = False``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq, minimize_scalar

import continuation as C

from .adapter import LOG_M, PI, TIME_SCALE, flutter_field
from .curves import Envelope, onset_on_curve

__all__ = ["ModeSwitch", "find_switches", "locate_switch", "located_switches",
           "MAX_CELL_CHANGES", "FOLD_STEP", "SAME_SWITCH_RTOL"]

#: log10 M* half-widths tried for the bracket of a crossing around its bracketed
#: position (the smallest where both curves exist and their onsets change order)
CROSSING_BRACKETS = (1e-3, 3e-3, 1e-2)


@dataclass(frozen=True)
class ModeSwitch:
    """Where the lowest Hopf branch changes with M*: at a crossing of two Hopf curves
    (a double-Hopf point: ustar_below = ustar_above, the frequency jumps) or at a fold of
    a curve in M* (the boundary itself jumps from ustar_below to ustar_above)."""

    mstar: float
    ustar_below: float
    ustar_above: float
    branch_below: int
    branch_above: int
    omega_below: float
    omega_above: float
    #: solved on its defining equation (:mod:`fsicas.linear.switches`), else bracketed
    #: on the traced curves
    located: bool = False


def find_switches(curves, lo: float, hi: float) -> list[ModeSwitch]:
    """Every change of the lowest piece on [lo, hi] (log10 M*), scanned on a fine grid of
    the traced curves (no new solves) and bisected to round-off in log10 M*."""
    out, envelope = [], Envelope(curves)
    grid = np.linspace(lo, hi, 801)
    lowest = [envelope.lowest(lm) for lm in grid]
    for k in range(len(grid) - 1):
        a, b = lowest[k], lowest[k + 1]
        if a is not None and b is not None and a[2] != b[2]:
            out += _cell_switches(envelope, a[2], b[2], grid[k], grid[k + 1])
    return out


def _cell_switches(envelope, piece: int, end: int, lo: float, hi: float) -> list[ModeSwitch]:
    """The switches inside one grid cell [lo, hi] from ``piece`` (lowest at lo) to
    ``end`` (lowest at hi), one after the other: a change to another trace of the same
    branch (two pieces overlapping: same U* and frequency) is no switch, but the cell is
    searched on from there."""
    out = []
    for _ in range(MAX_CELL_CHANGES):
        lo, hi_k = _switch_bracket(envelope, piece, lo, hi)
        ua, wa, _ = envelope.lowest(lo)
        ub, wb, above = envelope.lowest(hi_k)
        if abs(ua - ub) > 1e-2 * abs(ub) or abs(wa - wb) > 1e-2 * max(wa, wb):
            out.append(ModeSwitch(float(10 ** (0.5 * (lo + hi_k))), float(ua), float(ub),
                                  piece, above, float(wa), float(wb)))
        if above == end:
            break
        piece, lo = above, hi_k
    return out


#: Changes of the lowest piece searched inside one grid cell of the switch scan.
MAX_CELL_CHANGES = 8


def _switch_bracket(envelope, piece: int, lo: float, hi: float) -> tuple[float, float]:
    """Bisect [lo, hi] (``piece`` lowest at lo, not at hi) to where the lowest piece
    changes: a crossing of two Hopf curves, or the fold in M* that ends ``piece``."""
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lowest = envelope.lowest(mid)
        if lowest is not None and lowest[2] == piece:
            lo = mid
        else:
            hi = mid
    return lo, hi


def located_switches(scene, model, curves, lo: float, hi: float) -> list[ModeSwitch]:
    """The switches of :func:`find_switches` on [lo, hi] (log10 M*), each located
    (:func:`locate_switch`), those of one branch dropped, and one of each found twice
    (two traces of one curve bracket the same fold: same M* and U* to
    :data:`SAME_SWITCH_RTOL`; a fold's U* is solved to about 1e-8)."""
    out = []
    for switch in find_switches(curves, lo, hi):
        sw = locate_switch(scene, model, curves, switch)
        if sw is not None and not any(_same_switch(sw, o) for o in out):
            out.append(sw)
    return sorted(out, key=lambda sw: sw.mstar)


def _same_switch(a: ModeSwitch, b: ModeSwitch) -> bool:
    close = lambda x, y: abs(x - y) <= SAME_SWITCH_RTOL * max(abs(x), abs(y))
    return a.located and b.located and close(a.mstar, b.mstar) and \
        close(a.ustar_below, b.ustar_below) and close(a.ustar_above, b.ustar_above)


def locate_switch(scene, model, curves, switch):
    """``switch`` (a ``ModeSwitch`` bracketed on the traced curves) located on its
    defining equation (module docstring); None when its two pieces are the same branch
    (two traces of one curve whose interpolations differ, e.g. near a fold: their exact
    onsets at the switch agree to 1e-8)."""
    try:
        if _same_branch(scene, model, curves, switch):
            return None
        if abs(switch.ustar_below - switch.ustar_above) <= 1e-6 * abs(switch.ustar_above):
            return _crossing(scene, model, curves, switch)
        return _fold(scene, model, curves, switch)
    except (ValueError, RuntimeError):
        return switch


def _same_branch(scene, model, curves, switch) -> bool:
    lm = math.log10(switch.mstar)
    try:
        (ua, wa), (ub, wb) = (_onset(scene, model, curves, piece, lm)
                              for piece in (switch.branch_below, switch.branch_above))
    except ValueError:
        return False
    return abs(ua - ub) <= 1e-8 * abs(ub) and abs(wa - wb) <= 1e-8 * max(wa, wb, 1.0)


def _curve_of(curves, piece):
    return next(c for c in curves if piece in set(c.pieces.tolist()))


def _onset(scene, model, curves, piece, log_m) -> tuple[float, float]:
    """(U*, omega) of the onset of ``piece`` at log10 M* = log_m, solved from the curve's
    interpolated guess (:func:`fsicas.linear.curves.onset_on_curve`; ValueError if none)."""
    h = onset_on_curve(scene, model, _curve_of(curves, piece), piece, log_m)
    if h is None:
        raise ValueError(f"no onset on piece {piece} at log10 M* = {log_m}")
    return float(h.ustar), float(h.omega)


def _crossing(scene, model, curves, switch):
    a, b = switch.branch_below, switch.branch_above
    onset = lambda piece, lm: _onset(scene, model, curves, piece, lm)
    gap = lambda lm: onset(a, lm)[0] - onset(b, lm)[0]
    lm0 = math.log10(switch.mstar)
    lm = brentq(gap, *_sign_change(gap, lm0), xtol=1e-11, rtol=1e-12)
    (ua, wa), (ub, wb) = onset(a, lm), onset(b, lm)
    return replace(switch, mstar=10 ** lm, ustar_below=ua, ustar_above=ub, omega_below=wa,
                   omega_above=wb, located=True)


def _sign_change(gap, lm0) -> tuple[float, float]:
    """The narrowest of :data:`CROSSING_BRACKETS` around ``lm0`` where ``gap`` changes sign."""
    for half in CROSSING_BRACKETS:
        try:
            if gap(lm0 - half) * gap(lm0 + half) < 0:
                return lm0 - half, lm0 + half
        except ValueError:
            continue
    raise ValueError("no bracket of the crossing")


def _fold(scene, model, curves, switch):
    curve = _curve_of(curves, switch.branch_below)
    if curve.kind != "flutter":
        raise ValueError("a divergence curve ends where no divergence is bracketed: its end "
                         "stays bracketed")
    names = flutter_field(model).par_names
    lm_s, pi_s = curve.params[:, names.index(LOG_M)], curve.params[:, names.index(PI)]
    j = _turning_sample(curve, switch.branch_below, math.log10(switch.mstar))
    if not 0 < j < len(lm_s) - 1:
        raise ValueError("the fold is at an end of the traced curve")
    sign = 1.0 if lm_s[j] >= max(lm_s[j - 1], lm_s[j + 1]) else -1.0
    lo, hi = sorted((pi_s[j - 1], pi_s[j + 1]))
    rows = j - 1 + np.argsort(pi_s[j - 1:j + 2])          # the three samples, by Π
    at = lambda pi: _hopf_at_pressure(model, curve, rows, pi)
    best = minimize_scalar(lambda pi: -sign * at(pi)[0], bounds=(lo, hi), method="bounded",
                           options={"xatol": 1e-8 * max(abs(hi), 1.0)})
    lm, point = at(best.x)
    piece, u_above, w_above = _beyond(scene, model, curves, lm, sign)
    return replace(switch, mstar=10 ** lm, ustar_below=float(point.x[-2:].sum() / scene.hstar),
                   ustar_above=u_above, omega_below=float(point.data["omega"]) * TIME_SCALE,
                   omega_above=w_above, branch_above=piece, located=True)


def _beyond(scene, model, curves, lm: float, sign: float) -> tuple[int, float, float]:
    """(piece, U*, omega) of the lowest curve just past a fold at
    log10 M* = lm (on the side ``sign``): the exact onset at the fold's M* (or, if that
    piece starts past it, just past it). No trace of the fold's two pieces reaches past
    it (their samples are exact Hopf points), whichever trace bracketed it."""
    past = lm + sign * FOLD_STEP
    found = [x for c in curves for x in c.crossings(past)]
    if not found:
        raise ValueError("no curve past the fold")
    piece = min(found, key=lambda c: abs(c[0]))[2]
    try:
        return (piece, *_onset(scene, model, curves, piece, lm))
    except ValueError:
        return (piece, *_onset(scene, model, curves, piece, past))


#: Relative distance below which two located switches are one.
SAME_SWITCH_RTOL = 1e-6
#: Distance in decades of M* past a fold where the next curve is taken.
FOLD_STEP = 1e-9


def _turning_sample(curve, piece, log_m) -> int:
    """The sample of ``curve`` where ``piece`` ends nearest to log10 M* = log_m."""
    lm = np.log10(curve.mstar)
    segments = np.flatnonzero(curve.pieces == piece)
    ends = np.concatenate([segments, segments + 1])
    return int(min(ends, key=lambda i: abs(lm[i] - log_m)))


def _hopf_at_pressure(model, curve, rows, pi):
    """(log10 M*, point) of the Hopf point at fixed Π = ``pi`` with log10 M* free, from
    the curve samples ``rows`` (sorted by Π) interpolated at ``pi``."""
    vf = flutter_field(model)
    pis = curve.params[rows, vf.par_names.index(PI)]
    w = lambda a: np.array([np.interp(pi, pis, a[rows, k]) for k in range(a.shape[1])])
    x, params = w(curve.states), w(curve.params)
    omega = float(np.interp(pi, pis, curve.omega[rows])) / TIME_SCALE
    values = dict(zip(vf.par_names, params))
    values[PI] = float(pi)
    point = C.hopf_point(C.EquilibriumProblem(vf, x, values, LOG_M), x, omega)
    if point.status != "converged":
        raise ValueError(f"the Hopf point at Π = {pi} did not converge")
    return float(point.params[LOG_M]), point
