"""Poincaré returns of a run and its dense output between samples.

**Poincaré section.** Returns are the upward crossings of the tip displacement through
the reference ``y_ref`` (the mean tip displacement over the last quarter of the samples
looked at); a crossing counts only after the tip has been below ``y_ref − a/2`` since the
previous one (a = current half amplitude), so impacts and chattering do not create
spurious returns. Cycle k runs between returns k and k+1: its period ``T_k``, its tip
half-amplitude ``A_k = (max − min)/2`` and its Poincaré point ``x_k``.

**Dense output.** Between two output samples the solution is the Hermite interpolant of
the samples and their time derivatives from the equations, ``xdot = M(x)⁻¹ F(x)``: the
return time is the root of the quintic in the tip (``y, ẏ, ÿ`` at both ends; ``ẏ`` is a
state, ``ÿ`` from ``xdot``), each extremum of the tip the extremum of that quintic on the
two intervals next to the extreme sample, and the Poincaré point the cubic Hermite
interpolant of the state at the return time. Errors O(h⁶) for times and extrema and
O(h⁴) for the point in the output step h, instead of the O(h²) of linear interpolation
(return times sampled 65 times per period are within 1e-10 of the period of those
sampled 520 times).
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..model.assembly import Model, per_model

__all__ = ["poincare_returns", "Cycles", "cycles", "xdot_rows"]


def _crossings(y, y_ref) -> np.ndarray:
    """Indices k of the counted upward crossings ``y[k-1] < y_ref <= y[k]`` (module doc):
    the first candidate after each sample below ``y_ref − a/2``."""
    tail = y[3 * len(y) // 4:]
    half = 0.5 * np.ptp(tail) / 2 if tail.size else 0.0
    candidates = np.flatnonzero((y[:-1] < y_ref) & (y[1:] >= y_ref)) + 1
    below = np.flatnonzero(y < y_ref - half)
    first = np.searchsorted(candidates, below + 1)
    return np.unique(candidates[first[first < candidates.size]])


def poincare_returns(t, y, y_ref=None):
    """Return times (linear interpolation between samples) and sample indices of the
    counted upward crossings of ``y`` through ``y_ref`` (default: the mean of the last
    quarter); module docstring."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    y_ref = float(np.mean(y[3 * len(y) // 4:])) if y_ref is None else y_ref
    k = _crossings(y, y_ref)
    s = (y_ref - y[k - 1]) / (y[k] - y[k - 1])
    return t[k - 1] + s * (t[k] - t[k - 1]), k


def _hermite(y0, y1, d0, d1, a0=None, a1=None) -> np.ndarray:
    """Coefficients (ascending powers of s in [0, 1]) of the Hermite interpolant of values
    ``y``, first derivatives ``d`` and (quintic) second derivatives ``a`` at s = 0, 1, the
    derivatives already in units of s."""
    if a0 is None:
        return np.array([y0, d0, 3 * (y1 - y0) - 2 * d0 - d1, 2 * (y0 - y1) + d0 + d1])
    r0, r1, r2 = y1 - y0 - d0 - a0 / 2, d1 - d0 - a0, a1 - a0
    return np.array([y0, d0, a0 / 2, 10 * r0 - 4 * r1 + r2 / 2, -15 * r0 + 7 * r1 - r2,
                     6 * r0 - 3 * r1 + r2 / 2])


def _root(coef, level, guess) -> float:
    """The root in [0, 1] of ``poly(coef) = level`` nearest ``guess``."""
    roots = np.polynomial.polynomial.polyroots(coef - np.r_[level, np.zeros(len(coef) - 1)])
    real = roots[(np.abs(roots.imag) < 1e-9) & (roots.real > -1e-9) & (roots.real < 1 + 1e-9)].real
    return float(real[np.argmin(np.abs(real - guess))]) if real.size else guess


def _largest(coef) -> float:
    """The largest value of the polynomial on [0, 1]."""
    crit = np.polynomial.polynomial.polyroots(np.polynomial.polynomial.polyder(coef)) \
        if len(coef) > 2 else np.zeros(0)
    s = np.r_[0.0, 1.0, crit[(np.abs(crit.imag) < 1e-12) & (crit.real > 0) & (crit.real < 1)].real]
    return float(np.max(np.polynomial.polynomial.polyval(s, coef)))


@per_model
def _xdot_function(model: Model) -> ca.Function:
    """``xdot = M(x, p)⁻¹ F(x, p)``."""
    x = ca.MX.sym("x", model.n_state)
    p = ca.MX.sym("p", len(model.parameter_names))
    return ca.Function("xdot", [x, p], [ca.solve(model.mass(x, p), model.rhs(x, p))])


def xdot_rows(model: Model, X, p, pressure_drop=None) -> np.ndarray:
    """``xdot = M⁻¹F`` at the states ``X`` (rows), at parameters ``p``, with one pressure
    drop per row when ``pressure_drop`` is given (a scheduled run), in one mapped call."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    P = np.tile(np.asarray(p, dtype=float)[:, None], (1, len(X)))
    if pressure_drop is not None:
        P[model.index("pressure_drop")] = pressure_drop
    return np.array(_xdot_function(model).map(len(X))(X.T, P)).T


@dataclass(frozen=True)
class Cycles:
    """Cycles of a window of samples: returns (sample index of the sample after each,
    dense-output time, Poincaré point), per-cycle periods and amplitudes, and the size
    of the last cycle (largest peak-to-peak of a state component)."""

    index: np.ndarray
    times: np.ndarray
    points: np.ndarray
    periods: np.ndarray
    amplitudes: np.ndarray
    size: float


def cycles(t, X, model, xdot, y_ref=None) -> Cycles | None:
    """The returns and cycles of the samples (module docstring), None if < 2 returns;
    ``xdot(indices)``: the time derivatives at those samples."""
    y, v = model.tip_deflection(X), model.tip_velocity(X)
    y_ref = float(np.mean(y[3 * len(y) // 4:])) if y_ref is None else y_ref
    k = _crossings(y, y_ref)
    if k.size < 2:
        return None
    D = xdot(np.r_[k - 1, k])                          # xdot at both ends of each crossing
    d0, d1 = D[:k.size], D[k.size:]
    a0, a1 = model.tip_velocity(d0), model.tip_velocity(d1)   # tip accelerations
    times, points = np.empty(k.size), np.empty((k.size, X.shape[1]))
    for j, kk in enumerate(k):
        h = t[kk] - t[kk - 1]
        coef = _hermite(y[kk - 1], y[kk], h * v[kk - 1], h * v[kk], h * h * a0[j], h * h * a1[j])
        s = _root(coef, y_ref, (y_ref - y[kk - 1]) / (y[kk] - y[kk - 1]))
        times[j] = t[kk - 1] + s * h
        points[j] = np.polynomial.polynomial.polyval(
            s, _hermite(X[kk - 1], X[kk], h * d0[j], h * d1[j]))
    peaks = [(a + int(np.argmax(sign * y[a:b])), sign) for a, b in zip(k[:-1], k[1:]) for sign in (1, -1)]
    near = np.unique(np.clip([j + o for j, _ in peaks for o in (-1, 0, 1)], 0, len(y) - 1))
    acc = dict(zip(near, model.tip_velocity(xdot(near))))
    extreme = np.array([_extremum(t, y, v, acc, j, sign) for j, sign in peaks]).reshape(-1, 2)
    amps = (extreme[:, 0] - extreme[:, 1]) / 2
    size = float(np.ptp(X[k[-2]:k[-1]], axis=0).max()) or 1.0
    return Cycles(k, times, points, np.diff(times), amps, size)


def _extremum(t, y, v, acc, j, sign) -> float:
    """The extreme value of the tip near its extreme sample ``j`` (``sign`` 1: largest,
    -1: smallest), on the quintic Hermite interpolant (values y, derivatives v,
    accelerations ``acc[index]``) of the two intervals next to it."""
    best = sign * y[j]
    for lo in (j - 1, j):
        if 0 <= lo and lo + 1 < len(y):
            h = t[lo + 1] - t[lo]
            coef = _hermite(y[lo], y[lo + 1], h * v[lo], h * v[lo + 1], h * h * acc[lo], h * h * acc[lo + 1])
            best = max(best, _largest(sign * coef))
    return sign * best
