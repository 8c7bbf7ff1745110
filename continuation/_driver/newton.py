"""Newton's method on square sparse systems, with its outcome as data."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .settings import NewtonSettings
from .._linalg.sparse import PatternCache

@dataclass(frozen=True)
class NewtonResult:
    """Outcome of one Newton solve: never raises for non-convergence."""

    X: np.ndarray
    converged: bool
    iterations: int
    residual: float
    message: str
    #: factors of the last Jacobian used (None when they stopped contracting)
    lu: object = field(default=None, repr=False, compare=False)
    #: Jacobians factorized (the iterations not counted here were chord steps)
    jacobians: int = 0

    @property
    def effort(self) -> int:
        """Newton iterations the solve is worth, for step control: the Newton steps and
        one for the run of chord steps, if any (a solve takes at most one such run, and
        it does the work of the Newton step it replaces). Equals ``iterations`` for
        Newton's method."""
        return self.jacobians + (self.iterations > self.jacobians)


class LU:
    """SuperLU factors of ``A[:, q]``, solving with ``A`` (``q`` a column ordering).

    Exposes ``solve(b, trans)``, ``U``, ``perm_r`` and ``perm_c`` (the column
    permutation of ``A`` itself) like ``scipy``'s ``SuperLU``."""

    def __init__(self, lu, q):
        self.lu, self.q = lu, q
        self.perm_r = lu.perm_r
        self.perm_c = np.empty_like(lu.perm_c)
        self.perm_c[q] = lu.perm_c

    @property
    def U(self) -> sp.csc_matrix:
        """The upper factor (a copy, built on request: most factors are only solved with)."""
        return self.lu.U

    def solve(self, b, trans: str = "N") -> np.ndarray:
        if trans != "N":
            return self.lu.solve(b[self.q], trans=trans)
        y = self.lu.solve(b)
        x = np.empty_like(y)
        x[self.q] = y
        return x


@dataclass(frozen=True)
class _Ordering:
    """A column ordering ``q`` of a sparsity pattern and the pattern of ``A[:, q]``
    (``gather``: positions of the nonzeros of ``A`` in it)."""

    q: np.ndarray
    permuted_indptr: np.ndarray
    permuted_indices: np.ndarray
    gather: np.ndarray

    @classmethod
    def of(cls, A: sp.csc_matrix, q: np.ndarray) -> "_Ordering":
        """The ordering ``q`` of the pattern of ``A``."""
        counts = np.diff(A.indptr)[q]
        indptr = np.concatenate([[0], np.cumsum(counts)]).astype(A.indptr.dtype)
        gather = np.concatenate([np.arange(A.indptr[j], A.indptr[j + 1]) for j in q]) \
            if A.nnz else np.zeros(0, dtype=int)
        return cls(q, indptr, A.indices[gather].copy(), gather)

    def permuted(self, A: sp.csc_matrix) -> sp.csc_matrix:
        """``A[:, q]`` from the stored pattern (one gather of the values)."""
        return sp.csc_matrix((A.data[self.gather], self.permuted_indices,
                              self.permuted_indptr), shape=A.shape)


#: column orderings of recent sparsity patterns
_orderings = PatternCache(kept=8)


def factorize(A: sp.spmatrix):
    """Sparse LU of ``A`` or ``None`` when it is exactly singular.

    The fill-reducing ``MMD_AT_PLUS_A`` column ordering depends only on the
    sparsity pattern: it is computed at the first factorization of a pattern and
    reused (columns permuted by a stored gather, ``NATURAL`` order), which halves
    the cost of the corrector's repeated factorizations (4000 unknowns: 6 -> 3 ms).
    A structured matrix that has its own ``factorize()`` (``_cycles.condensed``) uses it.
    """
    if hasattr(A, "factorize"):
        return A.factorize()
    A = A if isinstance(A, sp.csc_matrix) else sp.csc_matrix(A)
    known = _orderings.get(A)
    try:
        if known is None:
            lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A")
            _orderings.put(A, _Ordering.of(A, np.argsort(lu.perm_c)))
            return LU(lu, np.arange(A.shape[1]))
        return LU(spla.splu(known.permuted(A), permc_spec="NATURAL"), known.q)
    except RuntimeError:
        return None


def solve(A: sp.spmatrix, b: np.ndarray, lu=None):
    """``(x, lu)`` with ``A x = b``: by iterative refinement on the factors ``lu``
    of a nearby matrix when that converges fast (the Jacobian one Newton update
    away), else by a fresh factorization (returned as ``lu``); ``(None, None)``
    when ``A`` is singular."""
    if lu is not None:
        x = refine(lu, A, b)
        if x is not None:
            return x, lu
    lu = factorize(A)
    return (None, None) if lu is None else (lu.solve(b), lu)


def refine(lu, A, b, max_iter: int = 8, rtol: float = 1e-13, rate: float = 0.05):
    """``x = lu^{-1} b`` corrected by ``x += lu^{-1} (b - A x)`` until the correction
    is below ``rtol ||x||``; None as soon as a correction shrinks by less than
    ``rate`` (a fresh factorization is then cheaper) or after ``max_iter``."""
    x = lu.solve(b)
    last = _norm(x)
    for _ in range(max_iter):
        dx = lu.solve(b - A @ x)
        x = x + dx
        size = _norm(dx)
        if size <= rtol * _norm(x):
            return x
        if size > rate * last:
            return None
        last = size
    return None


def newton(residual: Callable, jacobian: Callable, X0: np.ndarray,
           settings: NewtonSettings, polish: int = 0) -> NewtonResult:
    """Solve ``H(X) = 0`` by ``X <- X - A^{-1} H(X)``, ``A`` the factors of ``H_X`` at
    an iterate, kept while they contract (the chord method).

    A step whose residual shrank at least by ``settings.contraction`` keeps its factors
    for the next step (a chord step: a residual and a solve instead of a Jacobian and a
    factorization); otherwise the next step factorizes ``H_X`` at its iterate. After the
    first chord step that did not contract so, the solve goes on by Newton's method (a
    chord step that increased the residual is undone and retaken as a Newton step, not
    counted). A solve that converged on a chord step takes one more (uncounted) chord
    step when it lowers the residual: a chord step shrinks the error by the contraction
    factor, Newton's squares it, and this keeps the accuracy of Newton's last step.

    Converged when ``||H(X)||_inf <= tol`` or when an update was at round-off
    level (``||dX||_inf <= xtol (1 + ||X||_inf)``). Stops on a singular Jacobian, a
    non-finite or diverging residual, a residual or Jacobian that cannot be evaluated
    there (``LinAlgError``, e.g. an extended system's inner solve failing away from its
    point: a continuation step there is rejected and retried shorter), or after
    ``max_iter`` iterations; the last residual is always reported. ``polish`` extra
    Newton iterations after convergence are kept while they decrease the residual (used
    to refine special points to round-off).
    """
    X = np.array(X0, dtype=float)
    try:
        return _iterate(residual, jacobian, X, settings, polish)
    except np.linalg.LinAlgError as err:
        return NewtonResult(X, False, 0, np.inf, f"the system could not be evaluated: {err}")


def _iterate(residual, jacobian, X, settings, polish) -> NewtonResult:
    r = residual(X)
    res = res0 = _norm(r)
    lu, chord, jacobians = None, False, 0
    tiny_step, chords = False, settings.contraction > 0
    it = 0                                       # accepted steps
    while True:
        if res <= settings.tol or (tiny_step and np.isfinite(res)):
            if chord and lu is not None:         # as accurate as a last Newton step
                X, res = _chord_step(residual, lu, X, r, res)
            return _converged(residual, jacobian, X, res, polish, settings, it, lu, jacobians)
        if not np.isfinite(res) or res > settings.divergence * (1 + res0) \
                or it == settings.max_iter:
            break
        at_X = lu is None                        # a Newton step, else a chord step
        if at_X:
            lu, jacobians = factorize(jacobian(X)), jacobians + 1
            if lu is None:
                return NewtonResult(X, False, it, res,
                                    f"singular Jacobian at iteration {it}, residual {res:.3e}",
                                    jacobians=jacobians)
        dX = lu.solve(r)
        X_new = X - dX
        r_new = residual(X_new)
        res_new = _norm(r_new)
        if not (chords and res_new <= settings.contraction * res):
            lu = None                            # factorize at the next step
            if not at_X:
                chords = False                   # Newton from here on
                if not res_new < res:
                    continue                     # undone: retaken as a Newton step
        X, r, res, chord = X_new, r_new, res_new, not at_X
        tiny_step = _norm(dX) <= settings.xtol * (1.0 + _norm(X))
        it += 1
    return NewtonResult(X, False, it, res,
                        f"Newton did not converge: residual {res:.3e} > tol "
                        f"{settings.tol:.1e} after {it} iterations", jacobians=jacobians)


def _converged(residual, jacobian, X, res, polish, settings, it, lu, jacobians):
    """The result of a converged solve, ``polish`` Newton iterations further."""
    tiny = res > settings.tol
    X, res = _polish(residual, jacobian, X, res, polish)
    how = "" if not tiny or res <= settings.tol else \
        f" (update below xtol; residual {res:.3e} at round-off level)"
    return NewtonResult(X, True, it, res, f"converged in {it} iterations{how}", lu, jacobians)


def _chord_step(residual, lu, X, r, res):
    """One more step on the factors ``lu``, kept when it lowers the residual (not
    counted as an iteration, like ``polish``): a chord step only shrinks the error by
    the contraction factor, where Newton's last step squares it, so the iterate that met
    the tolerance is taken to the accuracy a Newton iteration would have reached."""
    X_new = X - lu.solve(r)
    res_new = _norm(residual(X_new))
    return (X_new, res_new) if res_new < res else (X, res)


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
