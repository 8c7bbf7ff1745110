"""Mode switches of the flutter boundary located on their defining equations.

The envelope of the traced Hopf curves (:mod:`fsicas.linear.boundary`) brackets each
switch between curve samples. Here each one is solved for, with every evaluation an
exact Hopf point (Newton on the Hopf system, :func:`continuation.hopf_point`), not an
interpolation of the samples:

- a **crossing** of two Hopf curves (a double-Hopf point: the same steady state has two
  imaginary pairs, U*_c is continuous, the frequency jumps) is the root in log10 M* of
  ``U*_a(M*) - U*_b(M*)``, the onsets of the two curves at that M* (Brent's method);
- a **fold** of a curve in M* (the window of instability between its two Hopf points
  closes, U*_c jumps) is the extremum of log10 M* along the curve, parametrized by the
  pressure drop Π near the fold: log10 M*(Π) is the Hopf point at fixed Π with log10 M*
  free (bounded Brent search); the U* above it is the exact onset of the next curve
  there.

A switch whose solve fails keeps its bracketed value (``located = False``).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy.optimize import brentq, minimize_scalar

import continuation as C

from .adapter import LOG_M, PI, TIME_SCALE, flutter_field
from .curves import onset_on_curve

__all__ = ["locate_switch"]

#: log10 M* half-widths tried for the bracket of a crossing around its bracketed
#: position (the smallest where both curves exist and their onsets change order)
CROSSING_BRACKETS = (1e-3, 3e-3, 1e-2)


def locate_switch(scene, model, curves, switch):
    """``switch`` (a ``ModeSwitch`` bracketed on the traced curves) located on its
    defining equation (module docstring)."""
    try:
        if abs(switch.ustar_below - switch.ustar_above) <= 1e-6 * switch.ustar_above:
            return _crossing(scene, model, curves, switch)
        return _fold(scene, model, curves, switch)
    except (ValueError, RuntimeError):
        return switch


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
    u_above, w_above = _onset(scene, model, curves, switch.branch_above, lm)
    return replace(switch, mstar=10 ** lm, ustar_below=float(point.x[-2:].sum() / scene.hstar),
                   ustar_above=u_above, omega_below=float(point.data["omega"]) * TIME_SCALE,
                   omega_above=w_above, located=True)


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
