"""Gauss–Legendre quadrature on [0, 1]: ``∫_0^1 g dx ≈ Σ_j w_j g(x_j)``.

A product of two clamped–free modes n, m ≤ N is integrated to round-off with about
2N + 10 nodes (measured in ``tests/test_quadrature.py``); the model's integrands carry
extra smooth factors (1/h, u|u|), so the default is ``2N + 20``.
"""
from __future__ import annotations

import numpy as np
from numpy.polynomial.legendre import leggauss

__all__ = ["gauss_legendre", "composite_gauss_legendre"]


def gauss_legendre(n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the n-point Gauss–Legendre rule mapped to [0, 1]."""
    if int(n_nodes) != n_nodes or n_nodes < 1:
        raise ValueError(f"quad_nodes must be a positive integer, got {n_nodes!r}")
    xi, w = leggauss(int(n_nodes))
    return 0.5 * (xi + 1.0), 0.5 * w




def composite_gauss_legendre(n_intervals: int, points: int) -> tuple[np.ndarray, np.ndarray]:
    """``points``-point Gauss–Legendre on each of ``n_intervals`` equal intervals of [0, 1].

    For piecewise-polynomial integrands (FE modes) aligned with the intervals this is
    exact up to degree 2 points - 1 per interval, where one global rule converges slowly.
    """
    x, w = gauss_legendre(points)
    left = np.arange(n_intervals)[:, None] / n_intervals
    return (left + x / n_intervals).ravel(), np.tile(w / n_intervals, n_intervals)
