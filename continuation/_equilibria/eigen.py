"""Generalized eigenvalues and eigenvectors of ``J v = lambda M v``.

Small problems use ``scipy.linalg.eig``; large sparse ones use shift-invert
Arnoldi: with ``(J - sigma M) v = (lambda - sigma) M v`` the operator
``(J - sigma M)^{-1} M`` has eigenvalues ``mu = 1 / (lambda - sigma)``, so the
largest ``|mu|`` are the ``lambda`` closest to ``sigma``. Infinite eigenvalues
(singular ``M``) give ``beta = 0`` / ``mu = 0`` and are dropped.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._driver.settings import EigenSettings


def eigenvalues(J: sp.spmatrix, M: sp.spmatrix, settings: EigenSettings) -> np.ndarray:
    """Finite generalized eigenvalues, sorted by decreasing real part."""
    n = J.shape[0]
    if n <= settings.dense_max:
        ev = _dense(J, M)
    else:
        ev = _shift_invert(J, M, settings)
    return ev[np.lexsort((-ev.imag, -ev.real))]


def _dense(J, M) -> np.ndarray:
    Jd = J.toarray() if sp.issparse(J) else np.asarray(J)
    Md = M.toarray() if sp.issparse(M) else np.asarray(M)
    w = sla.eig(Jd, Md, right=False, homogeneous_eigvals=True)
    alpha, beta = w
    scale = np.maximum(np.abs(alpha), np.abs(beta))
    finite = np.abs(beta) > 1e-12 * np.where(scale > 0, scale, 1.0)
    return alpha[finite] / beta[finite]


def _shift_invert(J, M, settings: EigenSettings) -> np.ndarray:
    n = J.shape[0]
    lu = spla.splu(sp.csc_matrix(J - settings.sigma * M))
    op = spla.LinearOperator((n, n), matvec=lambda v: lu.solve(M @ v), dtype=float)
    k = min(settings.nev, n - 2)
    mu = spla.eigs(op, k=k, which="LM", return_eigenvectors=False,
                   tol=1e-12, ncv=min(n, max(2 * k + 1, 20)))
    mu = mu[np.abs(mu) > 1e-14 * np.max(np.abs(mu))]
    return settings.sigma + 1.0 / mu


def count_unstable(ev: np.ndarray) -> int:
    """Number of eigenvalues with positive real part."""
    return int(np.sum(ev.real > 0))


def count_complex_unstable(ev: np.ndarray, imag_tol: float) -> int:
    """Number of eigenvalues with positive real part and nonzero imaginary part."""
    return int(np.sum((ev.real > 0) & (np.abs(ev.imag) > imag_tol)))


def nearest(ev: np.ndarray, target: complex) -> complex:
    """Eigenvalue of ``ev`` closest to ``target``."""
    return complex(ev[np.argmin(np.abs(ev - target))])


def eigenvector(J, M, lam: complex, iterations: int = 3, seed: int = 0) -> np.ndarray:
    """Right eigenvector ``(J - lam M) q = 0`` by inverse iteration, ``|q| = 1``."""
    A = sp.csc_matrix(J, dtype=complex) - lam * sp.csc_matrix(M, dtype=complex)
    return _inverse_iteration(A, iterations, seed)


def left_eigenvector(J, M, lam: complex, iterations: int = 3, seed: int = 1) -> np.ndarray:
    """``phi`` with ``phi^T (J - lam M) = 0`` (no conjugation), ``|phi| = 1``."""
    A = sp.csc_matrix(J, dtype=complex) - lam * sp.csc_matrix(M, dtype=complex)
    return _inverse_iteration(sp.csc_matrix(A.T), iterations, seed)


def _inverse_iteration(A, iterations: int, seed: int) -> np.ndarray:
    n = A.shape[0]
    rng = np.random.default_rng(seed)
    q = rng.standard_normal(n) + 1j * rng.standard_normal(n)
    scale = max(abs(A).max(), 1.0)
    lu = spla.splu(sp.csc_matrix(A + 1e-15 * scale * sp.identity(n)))
    for _ in range(iterations):
        q = lu.solve(q)
        q /= np.linalg.norm(q)
    return q


def step_limit(ev_a: np.ndarray, ev_b: np.ndarray, ds: float, overshoot: float,
               imag_tol: float) -> float:
    """The largest next arclength step that, by the rate of the last step, carries no
    eigenvalue further than ``overshoot`` times its distance past the imaginary axis: at
    most ``(1 + overshoot)`` times the predicted step to its crossing.

    Each eigenvalue ``lambda_b`` of the upper half plane (``Im >= -imag_tol``: the complex
    ones with ``Im > 0`` and the real ones) at the new point is paired with the nearest
    one at the previous point ``lambda_a`` (one step ``ds`` back); when it moves towards
    the axis (``d = |Re lambda_b - Re lambda_a| > 0`` with ``|Re lambda_b| < |Re
    lambda_a|``) its crossing is predicted ``|Re lambda_b| ds / d`` ahead. An eigenvalue
    that keeps its course is crossed in one step (the count changes and the Hopf or
    branch point is located); one that would cross and cross back within a long step (a
    narrow window of instability, or of stability; a real one: a window of static
    divergence between two branch points) is met inside the window instead of jumped
    over. Motions at round-off level (``d <= 1e-10 (1 + |lambda_b|)``) are ignored;
    ``inf`` when nothing limits the step."""
    upper = lambda ev: ev[ev.imag >= -imag_tol]
    a, b = upper(ev_a), upper(ev_b)
    if not a.size or not b.size:
        return np.inf
    nearest = a[np.argmin(np.abs(b[:, None] - a[None, :]), axis=1)]
    d = np.abs(b.real - nearest.real)
    towards = (np.abs(b.real) < np.abs(nearest.real)) & (d > 1e-10 * (1 + np.abs(b)))
    if not towards.any():
        return np.inf
    return float(np.min((1 + overshoot) * np.abs(b.real[towards]) * abs(ds) / d[towards]))


def crossing_eigenvalue(ev_a, ev_b, tol):
    """The complex eigenvalue (Im > 0) whose real part changes sign from a to b.

    Each eigenvalue at b is paired with the nearest at a; among the pairs whose real parts
    have opposite signs the closest pair wins, and its midpoint is returned. Choosing the
    eigenvalue of smallest |Re| instead would pick a lightly damped bystander (e.g. an
    undamped high-frequency mode) whose real part never crosses zero.
    """
    a, b = ev_a[ev_a.imag > tol], ev_b[ev_b.imag > tol]
    if not a.size or not b.size:
        return None
    best = None
    for lam_b in b:
        lam_a = a[np.argmin(np.abs(a - lam_b))]
        if np.sign(lam_a.real) != np.sign(lam_b.real):
            if best is None or abs(lam_a - lam_b) < abs(best[0] - best[1]):
                best = (lam_a, lam_b)
    if best is None:
        both = np.concatenate([a, b])
        return both[np.argmin(np.abs(both.real))]
    return 0.5 * (best[0] + best[1])
