"""The contact patch, located on the modal sum and integrated where it is.

The impact load of wall c is ``k max(0, g_c)``, ``g_c(x) = eps - h_c(x)``, on the patch
where ``g_c > 0``: 5e-4 to 2e-3 of L long for the laws of Figs. 6-9, so a fixed grid
of step 1e-2 cannot integrate it (the trapezoid rule on 101 points gave the tip's
penetration a weight of dx/2: forces 10-20x too large). The gap is a modal sum, known
at every x, so here:

* ``[0, 1]`` is cut into ``cells = max(100, 4N)`` equal cells (shorter than a quarter
  wavelength of mode N, so ``g_c`` has at most one maximum in a cell), and on each cell
  ``g_c`` is the Chebyshev interpolant of degree ``DEGREE`` at its Chebyshev points
  (error ``(beta_N dx/2)^12 / (2^11 12!)``, below 1e-14 of the deflection);
* a cell can reach ``g_c > 0`` only if an end value exceeds ``-margin``, where the margin
  bounds how far ``g_c`` rises above its chord in a cell (``dx^2/8 max|g_c''|``, from
  ``max_x |phi_n''|`` and the wall's own chord error): other cells are skipped, exactly;
* on a candidate cell the maximum of the interpolant is found by golden section, the
  patch ends ``g_c = 0`` by bisection (to 1e-13 of the cell), and ``∫ g_c`` over the
  patch from the interpolant's antiderivative: exact up to the interpolation error.

:func:`penetration` gives per state the total load ``∫ k max(0, eps - h_c) dx`` (both
walls), the deepest penetration ``max_{x,c} (eps - h_c)`` and where it is. The exact law
``max(0, .)`` is integrated, also when the scene smooths it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import chebyshev as cheb

from . import contact
from .assembly import Model, per_model

__all__ = ["DEGREE", "Penetration", "penetration", "patch_cells", "contact_intervals"]

DEGREE = 11
"""Degree of the Chebyshev interpolant of the gap on one cell."""
_ROWS = 20000               # states per block (memory: rows x 2 walls x cells x points)
_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class Penetration:
    """Per state (rows): ``load`` = ``∫ k max(0, eps - h_c) dx`` summed over both walls;
    ``depth`` = ``max_{x, c} (eps - h_c(x))`` (> 0 in contact; exact where it can be
    positive, the largest value on the cell ends elsewhere); ``position`` its x."""

    load: np.ndarray
    depth: np.ndarray
    position: np.ndarray


@dataclass(frozen=True, eq=False)
class _Cells:
    """The cells of a model: ends ``x`` (cells + 1), the Chebyshev points ``t`` (in
    [-1, 1]) and the modes there ``phi`` (N, cells, points), the modes at the ends
    ``phi_ends`` (N, cells + 1), the walls at both (2, ...), the map from point values
    to Chebyshev coefficients, the curvature bound of each mode and each wall's chord
    error per cell."""

    x: np.ndarray
    t: np.ndarray
    phi: np.ndarray
    phi_ends: np.ndarray
    walls: np.ndarray
    walls_ends: np.ndarray
    to_coefficients: np.ndarray
    curvature: np.ndarray
    wall_rise: np.ndarray

    @property
    def width(self) -> float:
        return float(self.x[1] - self.x[0])


@per_model
def patch_cells(model: Model) -> _Cells:
    """The cells of ``model`` (module docstring), built once per model."""
    count = max(100, 4 * model.n_modes)
    ends = np.linspace(0.0, 1.0, count + 1)
    t = np.cos(np.pi * (np.arange(DEGREE + 1) + 0.5) / (DEGREE + 1))[::-1]
    width = 1.0 / count
    points = (ends[:-1, None] + (t[None, :] + 1.0) * width / 2).ravel()
    inner, at_ends = model.basis_at(points), model.basis_at(ends)
    walls = np.array([w(points) for w in model.scene.walls]).reshape(2, count, -1)
    walls_ends = np.array([w(ends) for w in model.scene.walls])
    chord = walls_ends[:, :-1, None] + (walls_ends[:, 1:, None] - walls_ends[:, :-1, None]) \
        * (t + 1.0) / 2
    curvature = 1.1 * np.maximum(np.abs(inner.ddphi).max(axis=1), np.abs(at_ends.ddphi).max(axis=1))
    return _Cells(ends, t, inner.phi.reshape(model.n_modes, count, -1), at_ends.phi, walls,
                  walls_ends, np.linalg.inv(cheb.chebvander(t, DEGREE)), curvature,
                  np.maximum(chord - walls, 0.0).max(axis=2))


def penetration(model: Model, X, p) -> Penetration:
    """The load, deepest penetration and its position of the states ``X`` (rows), both
    walls, under the contact law of the parameter vector ``p``
    (:func:`fsicas.model.contact.law`; module docstring)."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    k, eps = contact.law(model, p)
    parts = [_block(model, X[i:i + _ROWS], k, eps) for i in range(0, len(X), _ROWS)]
    if not parts:
        return Penetration(np.zeros(0), np.zeros(0), np.zeros(0))
    return Penetration(*(np.concatenate([p[k] for p in parts]) for k in range(3)))


def contact_intervals(load) -> np.ndarray:
    """The separate contact intervals of a sampled impact load (the samples where it is
    positive): rows (first, last) sample index, one per impact; several in quick
    succession are chattering."""
    on = np.asarray(load) > 0
    starts = np.flatnonzero(on & ~np.r_[False, on[:-1]])
    ends = np.flatnonzero(on & ~np.r_[on[1:], False])
    return np.c_[starts, ends]


def _block(model: Model, X: np.ndarray, k: float, eps: float) -> tuple:
    """:func:`penetration` of at most ``_ROWS`` states, law ``(k, eps)``."""
    cells, n = patch_cells(model), model.n_modes
    q = X[:, n:2 * n]
    g_ends = _excess(eps, cells.walls_ends, q @ cells.phi_ends)            # (rows, 2, cells+1)
    chord_max = np.maximum(g_ends[..., :-1], g_ends[..., 1:])
    margin = cells.width ** 2 / 8 * (np.abs(q) @ cells.curvature)[:, None, None] + cells.wall_rise
    rows, walls, index = np.nonzero(chord_max > -margin)
    depth = g_ends.max(axis=(1, 2))
    flat = g_ends.reshape(len(X), -1).argmax(axis=1)
    position = cells.x[flat % g_ends.shape[2]]
    load = np.zeros(len(X))
    if rows.size:
        y = np.einsum("rn,nrp->rp", q[rows], cells.phi[:, index])
        g = _excess(eps, cells.walls[walls, index], y, sign=np.asarray(contact.WALL_SIGNS)[walls, None])
        coef = g @ cells.to_coefficients.T                                   # (candidates, DEGREE+1)
        top, peak = _maximum(coef)
        integral = _positive_integral(coef, top, peak) * cells.width / 2
        np.add.at(load, rows, k * integral)
        x_top = cells.x[index] + (top + 1.0) * cells.width / 2
        _deepest(depth, position, rows, peak, x_top)
    return load, depth, position


def _excess(eps, walls, y, sign=None):
    """``g_c = eps - h_c = eps - H_c - s_c y`` (both walls when ``sign`` is None, y of
    shape (rows, points))."""
    if sign is None:
        return np.stack([eps - w - s * y for w, s in zip(walls, contact.WALL_SIGNS)], axis=1)
    return eps - walls - sign * y


def _deepest(depth, position, rows, peak, x_top) -> None:
    """Raise ``depth`` (and move ``position``) of each row to its candidates' maxima."""
    order = np.lexsort((peak, rows))                 # per row, the largest peak last
    last = np.r_[rows[order][1:] != rows[order][:-1], True]
    best = order[last]
    better = peak[best] >= depth[rows[best]]
    depth[rows[best][better]] = peak[best][better]
    position[rows[best][better]] = x_top[best][better]


def _maximum(coef: np.ndarray, iterations: int = 70) -> tuple[np.ndarray, np.ndarray]:
    """Golden-section maximum ``(t, value)`` on [-1, 1] of each Chebyshev series (rows
    of ``coef``), the end values included."""
    lo, hi = -np.ones(len(coef)), np.ones(len(coef))
    for _ in range(iterations):
        a, b = hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo)
        left = _value(coef, a) >= _value(coef, b)
        hi, lo = np.where(left, b, hi), np.where(left, lo, a)
    t = np.stack([-np.ones(len(coef)), (lo + hi) / 2, np.ones(len(coef))])
    values = np.stack([_value(coef, s) for s in t])
    pick = values.argmax(axis=0)
    columns = np.arange(len(coef))
    return t[pick, columns], values[pick, columns]


def _positive_integral(coef, top, peak) -> np.ndarray:
    """``∫_{-1}^{1} max(0, g) dt`` of each series with one maximum ``peak`` at ``top``:
    from the antiderivative between the roots on either side (or the ends)."""
    a = _root(coef, -np.ones(len(coef)), top)
    b = _root(coef, np.ones(len(coef)), top)
    anti = cheb.chebint(coef.T, axis=0).T
    return np.where(peak > 0, _value(anti, b) - _value(anti, a), 0.0)


def _root(coef, end, top, iterations: int = 50) -> np.ndarray:
    """The zero of each series between ``top`` (where it is positive) and ``end``; the
    end itself where the series is positive there (bisection)."""
    outside, inside = end.copy(), top.copy()
    positive_end = _value(coef, end) > 0
    for _ in range(iterations):
        mid = (outside + inside) / 2
        up = _value(coef, mid) > 0
        inside, outside = np.where(up, mid, inside), np.where(up, outside, mid)
    return np.where(positive_end, end, (outside + inside) / 2)


def _value(coef: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Each Chebyshev series (rows of ``coef``) at its own point ``t``."""
    return cheb.chebval(t, coef.T, tensor=False)
