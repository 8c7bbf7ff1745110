"""Mesh adaptation of collocated cycles by equidistribution (as in AUTO).

On interval ``i`` the collocation polynomial has a constant ``NCOL``-th
derivative ``D_i = u^(m)`` (``m = NCOL``). Its jumps estimate the next one,

    u^(m+1) ~ 2 (D_{i+1} - D_i) / (h_i + h_{i+1})      (at the interface i | i+1),

and the local error of interval ``i`` behaves like ``h_i^(m+1) |u^(m+1)|``. The
new mesh equidistributes ``int |u^(m+1)|^(1/(m+1)) dt`` (piecewise constant density,
the average of the two interface values of each interval, plus a small floor) so
that every interval carries the same error. The per-solution a-posteriori error
indicator is ``max_i h_i^(m+1) |u^(m+1)|_i``; it follows the true error of the
node values (it is not a bound: the constant of the local error is not included).
"""

from __future__ import annotations

from math import factorial

import numpy as np

from .collocation import interval_nodes


def highest_derivative(U, mesh: np.ndarray, ncol: int, n: int) -> np.ndarray:
    """``(ntst, n)``: the constant ``NCOL``-th derivative on each interval."""
    s = np.linspace(0.0, 1.0, ncol + 1)
    c = np.array([factorial(ncol) / np.prod([s[l] - s[k] for k in range(ncol + 1) if k != l])
                  for l in range(ncol + 1)])
    h = np.diff(mesh)
    nodes = interval_nodes(U, n, len(h), ncol)
    return np.einsum("l,ilj->ij", c, nodes) / h[:, None] ** ncol


def next_derivative(U, mesh, ncol, n) -> np.ndarray:
    """``|u^(m+1)|`` per interval (max over components), periodic mesh."""
    D, h = highest_derivative(U, mesh, ncol, n), np.diff(mesh)
    jump = np.max(np.abs(np.roll(D, -1, axis=0) - D), axis=1) * 2 / (h + np.roll(h, -1))
    return 0.5 * (jump + np.roll(jump, 1))


def error_indicator(U, mesh, ncol, n) -> float:
    """``max_i h_i^(NCOL+1) |u^(NCOL+1)|_i``."""
    return float(np.max(np.diff(mesh) ** (ncol + 1) * next_derivative(U, mesh, ncol, n)))


#: the uniform share of the equidistributed density (of its mean), so no interval grows
#: without bound where the solution is smooth
FLOOR = 0.05


def equidistribute(U, mesh, ncol, n, ntst_new: int, floor: float = FLOOR) -> np.ndarray:
    """New mesh of ``ntst_new`` intervals with equal shares of
    ``int (|u^(m+1)| ^ (1/(m+1)) + floor * mean) dt``."""
    h = np.diff(mesh)
    rho = next_derivative(U, mesh, ncol, n) ** (1.0 / (ncol + 1))
    rho = rho + floor * max(float(np.sum(rho * h)), 1e-300)
    cum = np.concatenate([[0.0], np.cumsum(rho * h)])
    new = np.interp(np.linspace(0.0, cum[-1], ntst_new + 1), cum, mesh)
    new[0], new[-1] = 0.0, 1.0
    return new
