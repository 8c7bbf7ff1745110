"""The conditions of cycles with one more equation (``cycle_curves``): one scalar ``g(X)``
each, its gradient, and the codimension-two tests of its curves.

A collocated cycle ``X = (U, T, p_free)`` with ``k`` free parameters satisfies the
``m`` collocation and phase equations ``G(X) = 0`` (``cycles``). One more scalar
equation ``g(X) = 0`` (a :class:`Condition`) makes, with one free parameter, a square
system that *locates* a special cycle by Newton (:func:`locate_cycle`) and, with two,
a curve of such cycles continued by the same PALC (:class:`CycleCurveProblem`):

* :class:`Extremum` (an event boundary, e.g. grazing): ``min_{t, j} (A u(t))_j + b_j
  = level``. At a minimum inside an interval, ``d/dt (A u)_j = 0``, so (envelope
  theorem) ``g_X`` is ``a_j`` times the Lagrange weights of the minimizer's interval
  at its local time: exact and sparse.
* :class:`CycleFold` (LPC) and :class:`PeriodDoubling` (PD), minimally extended
  (bordering, as MATCONT): with ``A(X)`` the square matrix that is singular at the
  point, ``[[A, b], [c^T, 0]] (v, g) = (0, 1)`` defines ``g``, zero exactly where
  ``A`` is singular, and ``g_X = -w^T A_X v`` with ``(w, g)`` from the transposed
  system. For the fold ``A = G_(U, T)`` (the tangent of a one-parameter branch has
  no parameter component there); for period doubling ``A`` is the collocation
  Jacobian ``G_U`` with the antiperiodic wrap ``u(1) = -u(0)`` (the monodromy has
  the multiplier -1). ``w^T A_X v`` is the Hessian of ``w^T G`` in the direction
  ``v``: the difference of two Jacobians, ``(G_X(X + h v) - G_X(X - h v))^T w / 2h``
  (error ``O(h^2)``), no second derivatives compiled. The borders ``b, c`` are the
  last accepted point's ``w, v`` (``g`` is then well scaled along the curve).
* :class:`NeimarkSacker` (NS): ``|mu(X)| - 1`` of the complex multiplier ``mu(X)`` at
  which ``G_U`` with the wrap ``u(1) = mu u(0)`` is singular (``mu`` by an inner Newton
  on the same bordered test, its gradient by implicit differentiation).

Each condition also names the codimension-two points of its curves
(:attr:`Condition.crossings`, :meth:`Condition.tests`; ``cycle_curves`` detects them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from . import collocation as colloc
from . import normal_forms
from .._driver.newton import factorize
from .._driver.problem import null_vectors

if TYPE_CHECKING:
    from .cycles import CycleProblem


class Condition:
    """One scalar equation ``g(X) = 0`` on a collocated cycle (see the module)."""

    #: the kinds of the codimension-two points where a multiplier of the rest crosses
    #: +1, -1, or (a complex pair) the unit circle (module table)
    crossings = ("lpc", "pd", "ns")

    def rest(self, problem, X, mu) -> np.ndarray:
        """The Poincare multipliers ``mu`` without those the condition pins (default:
        none pinned)."""
        return mu

    #: the names of the condition's own smooth codimension-two test functions
    test_names: tuple = ()

    def test(self, problem, X, name: str) -> float:
        """The value of the test function ``name`` (one of :attr:`test_names`) at ``X``."""
        raise ValueError(f"{type(self).__name__} has no test {name!r}")

    def tests(self, problem, X) -> dict:
        """All of the condition's own test functions at ``X``."""
        return {name: self.test(problem, X, name) for name in self.test_names}

    def bind(self, problem: CycleProblem, X) -> "Condition":
        """The condition ready for ``problem`` at ``X`` (borders set); default: itself."""
        return self

    def value(self, problem: CycleProblem, X) -> float:
        """``g(X)``."""
        raise NotImplementedError

    def gradient(self, problem: CycleProblem, X) -> np.ndarray:
        """``g_X`` (one entry per unknown)."""
        raise NotImplementedError

    def accept(self, problem: CycleProblem, X) -> None:
        """Refresh data that follows the curve (borders) at an accepted point."""


@dataclass(frozen=True)
class Extremum(Condition):
    """``min_{t, j} (rows u(t))_j + offset_j - level = 0``: the cycle's least value of
    the affine functions ``rows u + offset`` (``rows``: m x n) reaches ``level``."""

    rows: np.ndarray
    offset: np.ndarray | float = 0.0
    level: float = 0.0

    def _minimum(self, problem, X):
        rows = np.atleast_2d(np.asarray(self.rows, dtype=float))
        offset = np.broadcast_to(np.asarray(self.offset, dtype=float), rows.shape[:1])
        U = X[: problem.n_nodes * problem.vf.n]
        shifted = np.hstack([rows, offset[:, None]])
        with_one = np.hstack([U.reshape(problem.n_nodes, -1),
                              np.ones((problem.n_nodes, 1))]).ravel()
        value, i, s, j = colloc.minimizer(with_one, problem.mesh, problem.ncol,
                                          problem.vf.n + 1, shifted)
        return value, i, s, rows[j]

    def value(self, problem, X) -> float:
        return self._minimum(problem, X)[0] - float(self.level)

    def gradient(self, problem, X) -> np.ndarray:
        _, i, s, a = self._minimum(problem, X)
        n, ncol = problem.vf.n, problem.ncol
        L, _ = colloc.lagrange(np.linspace(0.0, 1.0, ncol + 1), s)
        row = np.zeros(len(X))
        for l, weight in enumerate(L[0]):
            node = (i * ncol + l) % problem.n_nodes
            row[node * n: (node + 1) * n] += weight * a
        return row


class _Bordered(Condition):
    """A bordered singularity test of the square matrix ``self.matrix(problem, J)``."""

    def __init__(self):
        self.b = self.c = None
        self._last = None           # (X, (v, w, g)) of the last solve: residual and
        #                             Jacobian of one Newton iterate share it

    def matrix(self, problem, J) -> sp.csc_matrix:
        raise NotImplementedError

    def pairs(self, problem, X, v, w) -> list:
        """``[(w_k, d_k)]`` with ``w^T A_X v = sum_k (d/dh) G_X(X + h d_k)^T w_k``: the
        Hessians of ``w_k^T G`` in the directions ``d_k`` (both zero-padded)."""
        raise NotImplementedError

    def bind(self, problem, X) -> "_Bordered":
        bound = type(self)()
        A = self.matrix(problem, problem.cycle_jacobian(X))
        bound.c, bound.b = matrix_null_vectors(A)
        return bound

    def _solved(self, problem, X):
        """``(v, w, g)`` at ``X`` (kept for the last ``X``)."""
        if self._last is None or not np.array_equal(self._last[0], X):
            self._last = (np.array(X), self._solve(problem, problem.cycle_jacobian(X)))
        return self._last[1]

    def _solve(self, problem, J):
        v, w, g = bordered_solve(self.matrix(problem, J), self.b, self.c)
        return v, w, float(g)

    def value(self, problem, X) -> float:
        return self._solved(problem, X)[2]

    def null_vector(self, problem, X) -> np.ndarray:
        """The unit direction ``A(X)`` nearly annihilates (exactly at the point): the
        bordered system's ``v`` (of a fold: the ``(U, T)`` direction of the turn)."""
        v = self._solved(problem, X)[0]
        return v / np.linalg.norm(v)

    def gradient(self, problem, X) -> np.ndarray:
        v, w, _ = self._solved(problem, X)
        out = np.zeros(len(X))
        for weights, d in self.pairs(problem, X, v, w):
            H = jacobian_derivative(problem.cycle_jacobian, X, d)
            out -= H.T @ padded(weights, H.shape[0])
        return out

    def accept(self, problem, X) -> None:
        v, w, _ = self._solved(problem, X)
        self.c, self.b = v / np.linalg.norm(v), w / np.linalg.norm(w)
        self._last = None                                   # g changed with the borders


class CycleFold(_Bordered):
    """Fold of cycles (LPC): ``G_(U, T)`` singular."""

    crossings = ("r1", "lppd", "lpns")
    test_names = ("cpc",)

    def rest(self, problem, X, mu) -> np.ndarray:
        return np.delete(mu, np.argmin(np.abs(mu - 1.0)))

    def test(self, problem, X, name: str) -> float:
        """``cpc``: ``a = w^T G_YY[v, v]`` with the bordered ``v, w`` (unit borders), zero
        at a cusp of cycles."""
        v, w, _ = self._solved(problem, X)
        return normal_forms.fold_coefficient(problem, X, v, w)

    def matrix(self, problem, J) -> sp.csc_matrix:
        return J[:, : J.shape[0]]

    def pairs(self, problem, X, v, w) -> list:
        return [(w, padded(v, len(X)))]


class PeriodDoubling(_Bordered):
    """Period doubling: the antiperiodic collocation Jacobian ``G_U`` (wrap
    ``u_(NTST, 0) = -u_(0, 0)``) singular, i.e. a Floquet multiplier at -1."""

    crossings = ("lppd", "r2", "pdns")
    test_names = ("gpd",)

    def test(self, problem, X, name: str) -> float:
        """``gpd``: the doubled cycles' cubic coefficient ``c``, zero at a generalized
        period doubling (``normal_forms``)."""
        v, w, _ = self._solved(problem, X)
        return normal_forms.flip_coefficient(problem, X, v, w)

    def rest(self, problem, X, mu) -> np.ndarray:
        return np.delete(mu, np.argmin(np.abs(mu + 1.0)))

    def matrix(self, problem, J) -> sp.csc_matrix:
        return _twisted(problem, J, -1.0)[0]

    def pairs(self, problem, X, v, w) -> list:
        return _twisted_pairs(problem, X, v, w, -1.0)


class NeimarkSacker(Condition):
    """Neimark-Sacker (torus bifurcation): a complex pair of multipliers on the unit
    circle, ``g(X) = |mu(X)| - 1``.

    ``mu(X)`` is the multiplier of the discretized variational equation: the root of
    the bordered ``g(X, mu)`` of ``A(mu)``, the collocation Jacobian ``G_U`` with the
    wrap ``u(1) = mu u(0)`` (complex, analytic in ``mu``), found by Newton in ``mu``
    from the last root (``g_mu = -w^T A_mu v``). Then ``mu_X = -g_X / g_mu`` with
    ``g_X = -w^T A_X v`` by the Jacobian differences of the fold, in real and imaginary
    parts, and ``d|mu| = Re(conj(mu) mu_X) / |mu|``. The borders are the conjugates of
    the last ``v, w`` (``c^T v = |v|^2``: a complex vector's ``v^T v`` may vanish).
    ``multiplier``: the start (default: the problem's complex multiplier nearest the unit
    circle, upper half-plane)."""

    crossings = ("lpns", "pdns", "nsns")
    test_names = ("r3", "r4", "ch")

    def __init__(self, multiplier: complex | None = None):
        self.multiplier = None if multiplier is None else complex(multiplier)
        self.b = self.c = None
        self._last = None           # (X, (mu, v, w, g_mu)) of the last root

    def bind(self, problem, X) -> "NeimarkSacker":
        mu = self.multiplier if self.multiplier is not None else _complex_nearest_circle(
            problem.multipliers(X))
        bound = NeimarkSacker(mu)
        A, _ = _twisted(problem, problem.cycle_jacobian(X), mu)
        bound.c, bound.b = map(np.conj, matrix_null_vectors(A))   # c^T v = |v|^2
        return bound

    def _root(self, problem, X):
        """``(mu, v, w, g_mu)`` at ``X`` (kept for the last ``X``)."""
        if self._last is not None and np.array_equal(self._last[0], X):
            return self._last[1]
        J, mu = problem.cycle_jacobian(X), self.multiplier
        last = np.inf
        for _ in range(30):
            A, A_mu = _twisted(problem, J, mu)
            v, w, g = bordered_solve(A, self.b, self.c)
            g_mu = -(w @ (A_mu @ v))
            with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
                step = g / g_mu
            if not np.isfinite(step):
                raise np.linalg.LinAlgError("no multiplier near the unit circle: the test "
                                            "does not depend on mu here")
            mu -= step
            # converged, or stalled at the round-off of a stiff Jacobian (5e-13 on a
            # flutter cycle near a double Hopf point, where 1e-13 is never reached)
            if abs(step) <= 1e-13 * abs(mu) or last <= abs(step) <= 1e-10 * abs(mu):
                break
            last = abs(step)
        else:
            raise np.linalg.LinAlgError("no multiplier near the unit circle: Newton in mu "
                                        "did not converge")
        self._last = (np.array(X), (mu, v, w, g_mu))
        return self._last[1]

    def value(self, problem, X) -> float:
        return abs(self._root(problem, X)[0]) - 1.0

    def multiplier_at(self, problem, X) -> complex:
        """``mu(X)``, the discretized multiplier the condition follows."""
        return complex(self._root(problem, X)[0])

    def rest(self, problem, X, mu) -> np.ndarray:
        m = self.multiplier_at(problem, X)
        first = int(np.argmin(np.abs(mu - m)))
        second = np.abs(mu - np.conj(m))
        second[first] = np.inf
        return np.delete(mu, [first, int(np.argmin(second))])

    def test(self, problem, X, name: str) -> float:
        """``r3``, ``r4``: ``cos theta + 1/2`` and ``cos theta`` of ``mu = |mu| e^{i
        theta}``, zero at the 1:3 and 1:4 resonances; ``ch``: the first Lyapunov
        coefficient of the torus bifurcation, zero at a Chenciner point
        (``normal_forms``; only it costs Jacobians)."""
        mu, v, w, _ = self._root(problem, X)
        if name == "ch":
            return normal_forms.torus_coefficient(
                problem, X, mu, v, w, lambda J, nu: _twisted(problem, J, nu)[0])
        return mu.real / abs(mu) + (0.5 if name == "r3" else 0.0)

    def gradient(self, problem, X) -> np.ndarray:
        mu, v, w, g_mu = self._root(problem, X)
        g_X = np.zeros(len(X), dtype=complex)
        for weights, d in _twisted_pairs(problem, X, v, w, mu):
            for part, factor in ((d.real, 1.0), (d.imag, 1j)):
                H = jacobian_derivative(problem.cycle_jacobian, X, part)
                g_X -= factor * (H.T @ padded(weights, H.shape[0]))
        mu_X = -g_X / g_mu
        return np.real(np.conj(mu) * mu_X) / abs(mu)

    def accept(self, problem, X) -> None:
        mu, v, w, _ = self._root(problem, X)
        self.multiplier = mu
        self.c, self.b = np.conj(v / np.linalg.norm(v)), np.conj(w / np.linalg.norm(w))
        self._last = None


def _complex_nearest_circle(mu) -> complex:
    """The multiplier with positive imaginary part nearest the unit circle."""
    mu = np.asarray(mu, dtype=complex)
    upper = mu[mu.imag > 1e-8 * np.maximum(1.0, np.abs(mu))]
    if upper.size == 0:
        raise ValueError("NeimarkSacker needs a complex pair of multipliers; none here")
    return complex(upper[np.argmin(np.abs(np.abs(upper) - 1.0))])


def _wrap_masks(problem):
    """Rows of the last interval and columns of node 0 (in ``G_U``)."""
    n, rows = problem.vf.n, problem.n_nodes * problem.vf.n
    index = np.arange(rows)
    return index >= rows - n * problem.ncol, index < n


def _twisted(problem, J, mu):
    """``(A(mu), A_mu)``: ``G_U`` with the wrap ``u(1) = mu u(0)`` (the wrap's entries,
    last interval's rows and node 0's columns, times ``mu``) and its derivative in mu."""
    rows = problem.n_nodes * problem.vf.n
    A = sp.csc_matrix(J[:rows, :rows])
    last, wrap = _wrap_masks(problem)
    A_mu = sp.csc_matrix(sp.diags(last.astype(float)) @ A @ sp.diags(wrap.astype(float)))
    return sp.csc_matrix(A + (mu - 1.0) * A_mu), A_mu


def _twisted_pairs(problem, X, v, w, mu) -> list:
    """``[(w_k, d_k)]`` of ``w^T A(mu)_X v`` (see ``_Bordered.pairs``): the rows of the
    last interval see ``v`` with node 0 times ``mu``."""
    last, wrap = _wrap_masks(problem)
    return [(np.where(last, 0.0, w), padded(v, len(X))),
            (np.where(last, w, 0.0), padded(np.where(wrap, mu * v, v), len(X)))]


def jacobian_derivative(jacobian, X, d) -> sp.csc_matrix:
    """``(d/dh) G_X(X + h d)`` by the central difference of two Jacobians ``jacobian(X)``
    (error ``O(h^2)``): ``H^T w`` is the Hessian of ``w^T G`` in the direction ``d``."""
    h = 1e-7 * (1.0 + np.max(np.abs(X))) / max(np.max(np.abs(d)), 1e-300)
    return (jacobian(X + h * d) - jacobian(X - h * d)) / (2 * h)


def bordered_solve(A, b, c):
    """``(v, w, g)``: ``[[A, b], [c^T, 0]] (v, g) = (0, 1)`` and its transpose."""
    B = sp.bmat([[A, b[:, None]], [c[None, :], None]], format="csc")
    lu = factorize(B)
    if lu is None:
        raise np.linalg.LinAlgError("the bordered matrix is singular: borders lost")
    e = np.zeros(B.shape[0], dtype=B.dtype)
    e[-1] = 1.0
    vg, wg = lu.solve(e), lu.solve(e, trans="T")
    return vg[:-1], wg[:-1], vg[-1]


def padded(v, size) -> np.ndarray:
    """``v`` followed by zeros, ``size`` entries."""
    out = np.zeros(size, dtype=np.result_type(v, float))
    out[: v.size] = v
    return out


def matrix_null_vectors(A):
    """Approximate right and left null vectors of a nearly singular ``A`` (an exactly
    singular one is nudged first)."""
    lu = factorize(A)
    if lu is None:
        lu = factorize(A + 1e-12 * sp.eye(A.shape[0], format="csc"))
    return null_vectors(lu, A.shape[0], iterations=4)
