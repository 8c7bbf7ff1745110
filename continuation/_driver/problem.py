"""The continued-problem interface.

A problem is a curve ``G(X) = 0``, ``G: R^(m+1) -> R^m``, whose unknowns
``X`` end with the free parameters (the last one is *the* continuation
parameter: direction and fold test refer to it). PALC only uses
``residual``, ``jacobian`` and ``X0``; the driver additionally asks the
problem to ``monitor`` points (eigenvalues or multipliers, test functions), name the
``events`` between two monitored points, give a smooth ``test_function`` to
locate them, ``describe`` the located point and, optionally, cap the next step
(``step_limit``). Equilibria and their curves (``_equilibria``) and periodic orbits
(``_cycles``) implement it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp

from .._casadi.symbolic import bound
from .._linalg.sparse import append_row


@dataclass(frozen=True)
class PointInfo:
    """What the driver records at one point besides ``X``."""

    eigenvalues: np.ndarray
    tests: dict = field(default_factory=dict)
    counts: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Description:
    """A located special point: refined ``X``, status, precision, data."""

    X: np.ndarray
    status: str
    precision: float
    data: dict
    message: str = ""


class Problem:
    """Base class: a curve ``G(X) = 0``, ``X = (Y, p_free)``, compiled by CasADi.

    A subclass names its ``kind`` and its ``builder``; the system is built once per
    VectorField ``vf`` and bound to the parameters ``p0`` (the free ones taken from ``X``)
    and the data ``D``.
    """

    kind = "abstract"
    #: ``builder(vf) -> CompiledSystem`` of the problem's system
    builder = None
    #: event kinds detected by a coarse criterion and dropped when their smooth
    #: test function shows no sign change on re-evaluation
    verified_kinds: tuple = ()
    #: ``monitor`` and the test functions use the factors ``lu`` of
    #: ``[G_X(X); tau^T]`` (branch-point test); when False, ``Step.lu`` may be the
    #: factors of a nearby matrix (the corrector's last one)
    monitor_uses_lu = True

    def __init__(self, vf, free: tuple, X0, p0, D=()):
        self.vf = vf
        self.free = tuple(free)
        self.free_idx = tuple(vf.par_index(f) for f in self.free)
        self.X0 = np.array(X0, dtype=float)
        self.system = bound(vf, self.kind, p0, D, self.free, type(self).builder)
        if self.X0.size != self.system.n_unknowns:
            raise ValueError(f"X0 has size {self.X0.size}, the {self.kind} system has "
                             f"{self.system.n_unknowns} unknowns")

    # -- what PALC needs --------------------------------------------------------
    def residual(self, X) -> np.ndarray:
        """``G(X)``."""
        return self.system.residual(X)

    def jacobian(self, X) -> sp.csc_matrix:
        """Exact sparse ``G_X`` of shape ``(m, m+1)``."""
        return self.system.jacobian(X)

    def bordered_jacobian(self, X, rows):
        """``[G_X; rows]``, the square matrix PALC solves with: a sparse matrix here; a
        problem with structure may return any object with ``@`` and ``factorize()`` (whose
        result has ``solve(b)``)."""
        return append_row(self.jacobian(X), np.asarray(rows, dtype=float))

    # -- state and parameters -----------------------------------------------------
    def state(self, X) -> np.ndarray:
        """The state of size ``vf.n`` that the branch records for the point ``X``
        (default: the first ``vf.n`` unknowns)."""
        return np.asarray(X[: self.vf.n], dtype=float)

    def params(self, X) -> np.ndarray:
        """Full parameter vector ``p`` at ``X`` (free ones taken from ``X``)."""
        return self.system.params(X)

    def par_dict(self, X) -> dict:
        """``{name: value}`` of all parameters at ``X``."""
        return dict(zip(self.vf.par_names, map(float, self.params(X))))

    def frame(self, X) -> np.ndarray:
        """Indices of the components of ``X`` that keep their meaning when the problem is
        restarted (default: the free parameters)."""
        return np.arange(len(X) - len(self.free), len(X))

    def restart(self, X):
        """``(new_problem, X_new)`` when the augmented system should be rebuilt at
        ``X`` (e.g. reference vectors drifted), else None (default: never). The branch
        goes on from ``X_new`` corrected on the new problem, with a fresh tangent. A
        third entry ``carry(tau) -> tau_new`` (the tangent in the new unknowns, e.g.
        interpolated onto a new mesh) makes the restart continuous: the branch goes on
        from ``X_new`` along the carried tangent with no correction of its own (the next
        step's corrector corrects), and the last point's monitor values stand for it."""
        return None

    def start_row(self) -> np.ndarray:
        """Row ``e`` of the start corrector ``e . (X - X0) = 0`` (default: the
        continuation parameter is fixed). Branch switching onto a bifurcating branch
        fixes the amplitude along the critical direction instead."""
        e = np.zeros(self.X0.size)
        e[-1] = 1.0
        return e

    def accept(self, X) -> None:
        """Called by the iterator at every accepted point; problems with data that
        follows the branch (the phase reference of a cycle) refresh it here."""

    def columns(self, X) -> dict:
        """Problem-specific scalar columns recorded per point (default none)."""
        return {}

    # -- detection hooks (overridden) -----------------------------------------------
    def monitor(self, X, tau, lu, settings) -> PointInfo:
        """Eigenvalues (or multipliers) and test functions at ``X`` (``lu`` factors
        ``[G_X; tau^T]``; default: the branch-point test only)."""
        return PointInfo(np.zeros(0, dtype=complex), {"bp": _det_sign(lu)})

    def step_limit(self, a: PointInfo, b: PointInfo, ds: float, settings) -> float | None:
        """The longest next step after the step ``ds`` from ``a`` to ``b``, or None (no
        limit, the default)."""
        return None

    def events(self, a: PointInfo, b: PointInfo) -> list:
        """Kinds of special points between two monitored points."""
        return [k for k in a.tests if k in b.tests and a.tests[k] * b.tests[k] < 0] + \
            [k for k in a.counts if k in b.counts and a.counts[k] != b.counts[k]]

    def crossings(self, kind, a: PointInfo, b: PointInfo) -> int:
        """How many points of ``kind`` lie between ``a`` and ``b`` at least (from their
        counts); more than one makes the driver split the step until each part holds one."""
        return 1

    def test_function(self, kind, X_a, info_a, X_b, info_b, settings) -> Callable | None:
        """Smooth ``f(X, tau, lu)`` vanishing at the event, or None (bisection)."""
        if kind == "bp":
            return _bp_function(self, X_a)
        return None

    def describe(self, kind, X, tau, settings) -> Description:
        """Refine and characterize a located point (default: as located)."""
        return Description(X, "converged", 0.0, {})


def _det_sign(lu) -> float:
    """Sign of ``det`` of a matrix from its SuperLU factors ``Pr A Pc = L U``."""
    if lu is None:
        return 0.0
    d = lu.U.diagonal()
    return float(np.prod(np.sign(d)) * _parity(lu.perm_r) * _parity(lu.perm_c))


def _parity(perm) -> int:
    """Sign of a permutation, ``(-1)^(n - cycles)``, cycles counted by pointer
    doubling (each index learns the smallest index of its cycle)."""
    perm = np.asarray(perm)
    label, jump = np.arange(perm.size), perm.copy()
    for _ in range(max(1, int(np.ceil(np.log2(max(perm.size, 2)))))):
        label = np.minimum(label, label[jump])
        jump = jump[jump]
    cycles = int(np.sum(label == np.arange(perm.size)))
    return -1 if (perm.size - cycles) % 2 else 1


def _bp_function(problem, X_a):
    """Smooth branch-point test ``g = 1 / (phi^T A^{-1} psi)``, ``A = [G_X; tau^T]``.

    ``phi, psi`` approximate the right/left singular vectors of ``A`` at the
    bracket start, so ``g`` changes sign through zero exactly where ``A`` is
    singular (a simple branch point) and has no pole nearby.
    """
    state = {}

    def g(X, tau, lu):
        if "phi" not in state:
            state["phi"], state["psi"] = null_vectors(lu, X.size)
        return 1.0 / float(state["phi"] @ lu.solve(state["psi"]))

    return g


def null_vectors(lu, n: int, iterations: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Approximate right and left null vectors of a nearly singular matrix from its
    factors ``lu`` by inverse iteration (random starts, fixed seed)."""
    rng = np.random.default_rng(0)
    phi, psi = rng.standard_normal(n), rng.standard_normal(n)
    for _ in range(iterations):
        phi = lu.solve(phi)
        phi /= np.linalg.norm(phi)
        psi = lu.solve(psi, trans="T")
        psi /= np.linalg.norm(psi)
    return phi, psi
