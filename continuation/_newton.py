"""Newton's method on square sparse systems, with its outcome as data."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ._settings import NewtonSettings


@dataclass(frozen=True)
class NewtonResult:
    """Outcome of one Newton solve: never raises for non-convergence."""

    X: np.ndarray
    converged: bool
    iterations: int
    residual: float
    message: str


def factorize(A: sp.spmatrix):
    """Sparse LU of ``A`` or ``None`` when it is exactly singular."""
    try:
        return spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A")
    except RuntimeError:
        return None


def newton(residual: Callable, jacobian: Callable, X0: np.ndarray,
           settings: NewtonSettings, polish: int = 0) -> NewtonResult:
    """Solve ``H(X) = 0`` by ``X <- X - H_X(X)^{-1} H(X)``.

    Converged when ``||H(X)||_inf <= tol`` or when an update was at round-off
    level (``||dX||_inf <= xtol (1 + ||X||_inf)``). Stops on a singular Jacobian, a
    non-finite or diverging residual, or after ``max_iter`` iterations; the
    last residual is always reported. ``polish`` extra iterations after
    convergence are kept while they decrease the residual (used to refine
    special points to round-off).
    """
    X = np.array(X0, dtype=float)
    r = residual(X)
    res = res0 = _norm(r)
    tiny_step = False
    for it in range(settings.max_iter + 1):
        if res <= settings.tol or (tiny_step and np.isfinite(res)):
            X, res = _polish(residual, jacobian, X, res, polish)
            how = "" if not tiny_step or res <= settings.tol else \
                f" (update below xtol; residual {res:.3e} at round-off level)"
            return NewtonResult(X, True, it, res, f"converged in {it} iterations{how}")
        if not np.isfinite(res) or res > settings.divergence * (1 + res0) \
                or it == settings.max_iter:
            break
        lu = factorize(jacobian(X))
        if lu is None:
            return NewtonResult(X, False, it, res,
                                f"singular Jacobian at iteration {it}, residual {res:.3e}")
        dX = lu.solve(r)
        X = X - dX
        tiny_step = _norm(dX) <= settings.xtol * (1.0 + _norm(X))
        r = residual(X)
        res = _norm(r)
    return NewtonResult(X, False, it, res,
                        f"Newton did not converge: residual {res:.3e} > tol "
                        f"{settings.tol:.1e} after {it} iterations")


def _norm(r: np.ndarray) -> float:
    return float(np.max(np.abs(r))) if r.size else 0.0


def _polish(residual, jacobian, X, res, iterations):
    for _ in range(iterations):
        lu = factorize(jacobian(X))
        if lu is None:
            break
        X_new = X - lu.solve(residual(X))
        res_new = _norm(residual(X_new))
        if not res_new < res:
            break
        X, res = X_new, res_new
    return X, res
