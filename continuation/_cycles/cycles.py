"""Periodic orbits of ``M(x, p) xdot = F(x, p)`` continued in one parameter.

A cycle is "just another problem": ``X = (U, T, p)`` with ``U`` the node
values of the collocation polynomial (see ``collocation``), ``G`` the
collocation equations ``M(u) u' = T F(u)`` plus the integral phase condition
``int <u, v'> dt = 0``. The reference ``v`` is the last accepted cycle
(refreshed through ``Problem.accept``). ``G`` and its sparse Jacobian are evaluated
by pointwise blocks (``blocks``, ``CollocationSettings.jacobian = 'blocks'``) or by
CasADi AD of the whole discretised residual (``'graph'``). Floquet multipliers and
the detection of special cycles: ``periodic``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Mapping

import numpy as np

from . import blocks
from . import condensed
from . import collocation as colloc
from . import floquet
from .condensed import CollocationJacobian
from .mesh import equidistribute, error_indicator
from .periodic import PeriodicProblem
from .._casadi.symbolic import bound
from .._casadi.vectorfield import VectorField
from .._driver.problem import Description
from .settings import CollocationSettings, kernel_backend


class CycleProblem(PeriodicProblem):
    """Branch of periodic orbits by orthogonal collocation.

    Parameters
    ----------
    F : casadi.Function ``(x, p) -> F`` or a VectorField.
    orbit : initial guess, a callable ``t -> x`` on ``t in [0, 1)`` (one
        period, vectorized or not) or an array ``(m, n)`` of equally spaced
        samples over one period (interpolated periodically).
    period : initial guess of ``T``.
    params : ``{name: value}`` of all parameters; active : continuation parameter, or
        a tuple of free parameters (the last is the continuation parameter; a curve of
        cycles needs one more equation, :class:`CycleCurveProblem`).
    M : casadi.Function ``(x, p) -> M`` or None (identity).
    settings : :class:`CollocationSettings` (NTST, NCOL, Floquet method, adaptation).
    mesh : ``NTST + 1`` increasing times from 0 to 1 (default uniform).
    """

    #: ``refine(problem, X) -> VectorField | None``, asked at every accepted point X
    #: before the re-mesh: a field returned (the same equations with the same unknowns
    #: and parameters, e.g. on a finer discretization of their integrals) continues the
    #: branch from X on it (:meth:`on_field`, a restart). Kept by the restarted problems;
    #: None (default): never asked.
    refine = None

    def __init__(self, F, orbit, period: float, params: Mapping[str, float], active: str,
                 *, M=None, settings: CollocationSettings | None = None, mesh=None):
        settings = CollocationSettings() if settings is None else settings
        p0 = self._setup(F, M, params, active, period, settings, CollocationSettings)
        vf, self.ntst, self.ncol = self.vf, settings.ntst, settings.ncol
        self.mesh = _check_mesh(mesh, self.ntst)
        self._accepted = 0
        self._last_jacobian = None
        U = sample_orbit(orbit, colloc.node_times(self.mesh, self.ncol), vf.n)
        self.X0 = np.concatenate([U, [float(period)], p0[list(self.free_idx)]])
        D = np.concatenate([np.diff(self.mesh), self._phase(U)])
        kind, build = _collocation_system(settings)
        self.system = bound(vf, kind, p0, D, self.free, build)
        self.condensed = _condensed_solver(settings, self.system.compiled)

    # -- unknowns ------------------------------------------------------------------
    @property
    def n_nodes(self) -> int:
        return self.ntst * self.ncol

    def nodes(self, X) -> np.ndarray:
        """Node values ``(NTST NCOL, n)`` at times :meth:`times`."""
        return np.asarray(X[: self.n_nodes * self.vf.n]).reshape(self.n_nodes, self.vf.n)

    def times(self) -> np.ndarray:
        """Normalized times of the nodes in ``[0, 1)``."""
        return colloc.node_times(self.mesh, self.ncol)

    def period(self, X) -> float:
        return float(X[self.n_nodes * self.vf.n])

    def state(self, X) -> np.ndarray:
        """``u(0)``, the cycle's point at ``t = 0``."""
        return np.asarray(X[: self.vf.n], dtype=float)

    def _phase(self, U) -> np.ndarray:
        return colloc.phase_coefficients(U, self.vf.n, self.ntst, self.ncol)

    def accept(self, X) -> None:
        """Phase reference <- the accepted cycle."""
        self._accepted += 1
        self.system.D = np.concatenate([np.diff(self.mesh),
                                        self._phase(X[: self.n_nodes * self.vf.n])])

    def columns(self, X) -> dict:
        u = self.nodes(X)
        return {"period": self.period(X),
                "amplitude": float(np.max(np.ptp(u, axis=0))),
                "max_norm": float(np.max(np.linalg.norm(u, axis=1))),
                "error_estimate": self.error_estimate(X)}

    # -- mesh ------------------------------------------------------------------------
    def error_estimate(self, X) -> float:
        """A-posteriori indicator ``max_i h_i^(NCOL+1) |u^(NCOL+1)|_i`` (``mesh``)."""
        return error_indicator(X[: self.n_nodes * self.vf.n], self.mesh, self.ncol,
                               self.vf.n)

    def describe(self, kind, X, tau, settings) -> Description:
        """As for every periodic problem, plus ``data['mesh']``: the point's own mesh (an
        adapted branch re-meshes as it goes; :meth:`at` rebuilds the point's problem)."""
        found = super().describe(kind, X, tau, settings)
        found.data["mesh"] = [float(t) for t in self.mesh]
        return found

    def at(self, point) -> tuple["CycleProblem", np.ndarray]:
        """``(problem, X)`` of a special ``point`` of this problem's branch: the same
        field, free parameters and settings on the point's mesh (``point.data['mesh']``,
        this problem's where absent), and the point's unknowns ``point.data['X']``."""
        X = np.asarray(point.data["X"], dtype=float)
        mesh = np.asarray(point.data.get("mesh", self.mesh), dtype=float)
        n, rows = self.vf.n, (len(mesh) - 1) * self.ncol * self.vf.n
        if X.size != rows + 1 + len(self.free):
            raise ValueError(f"the point's unknowns ({X.size}) do not fit its mesh of "
                             f"{len(mesh) - 1} intervals")
        params = dict(zip(self.vf.par_names, map(float, self.params(X))))
        orbit = lambda t: colloc.evaluate(X[:rows], mesh, self.ncol, n, t)  # noqa: E731
        new = CycleProblem(self.vf, orbit, float(X[rows]), params, self.free,
                           settings=replace(self.settings, ntst=len(mesh) - 1), mesh=mesh)
        new.refine = self.refine
        return new, X.copy()

    def remesh(self, X, ntst: int | None = None):
        """``(problem, X_new)`` on a mesh equidistributing the error of ``X`` (same
        ``NTST`` unless given); node values are the old polynomial at the new nodes."""
        ntst = self.ntst if ntst is None else int(ntst)
        mesh = equidistribute(X[: self.n_nodes * self.vf.n], self.mesh, self.ncol,
                              self.vf.n, ntst)
        return self._rebuilt(X, self.vf, replace(self.settings, ntst=ntst), mesh)

    def on_field(self, vf: VectorField, X):
        """``(problem, X_new)``: the cycle ``X`` on the field ``vf`` (same state size and
        parameter names), same mesh and node values; the points counted towards the next
        re-mesh carry over (the mesh is the same)."""
        if not (isinstance(vf, VectorField) and vf.n == self.vf.n
                and vf.par_names == self.vf.par_names):
            raise ValueError(f"the field must be a VectorField of {self.vf.n} states and "
                             f"parameters {self.vf.par_names}")
        new, X_new = self._rebuilt(X, vf, self.settings, self.mesh)
        new._accepted = self._accepted
        return new, X_new

    def _rebuilt(self, X, vf, settings, mesh):
        """The cycle ``X`` (its polynomial at the new nodes) as a problem on ``vf``,
        ``settings`` and ``mesh``, keeping ``refine``; and its unknowns."""
        new = CycleProblem(vf, lambda t: self.evaluate(X, t), self.period(X), self.par_dict(X),
                           self.free, settings=settings, mesh=mesh)
        new.refine = self.refine
        return new, new.X0.copy()

    def restart(self, X):
        """On the field ``refine`` returns at X, if any; else re-mesh every
        ``settings.adapt_every`` accepted points (0: never), continuously as AUTO-07p
        adapts its mesh: the branch goes on from the cycle's polynomial at the new nodes
        along the tangent's (``carried``), and the next step's corrector corrects it."""
        vf = None if self.refine is None else self.refine(self, X)
        if vf is not None:
            return self.on_field(vf, X)
        every = self.settings.adapt_every
        if every and self._accepted >= every:
            new, X_new = self.remesh(X)
            return new, X_new, lambda tau: self.carried(tau, new)
        return None

    def carried(self, tau, new: "CycleProblem") -> np.ndarray:
        """The tangent ``tau`` of this problem's unknowns in those of ``new`` (same field
        and free parameters, another mesh): its node part is its polynomial at the new
        nodes, ``T`` and ``p`` are kept; unit length."""
        N = self.n_nodes * self.vf.n
        nodes = colloc.evaluate(tau[:N], self.mesh, self.ncol, self.vf.n, new.times())
        out = np.concatenate([nodes.ravel(), tau[N:]])
        return out / np.linalg.norm(out)

    def frame(self, X) -> np.ndarray:
        """Only ``T`` and ``p`` keep their meaning across a re-mesh."""
        return np.arange(self.n_nodes * self.vf.n, len(X))

    # -- Jacobians and Floquet multipliers ---------------------------------------------------
    @property
    def monitor_uses_lu(self) -> bool:
        """Condensed: the tangent is solved on fresh factors at the point, whose interval
        maps the multipliers reuse (refining it on the corrector's factors would leave
        the interval factorizations to do once more); sparse: refined on them."""
        return self.condensed

    def jacobian(self, X):
        """``G_X`` (sparse); the last one is kept for the multipliers at the same ``X``."""
        J = super().jacobian(X)
        self._last_jacobian = (np.array(X), J)
        return J

    def interval_jacobian(self, X) -> CollocationJacobian:
        """``G_X`` by dense interval blocks (``condensed``; 'blocks' Jacobian only),
        kept like :meth:`jacobian`."""
        s = self.system
        J = s.compiled.interval_jacobian(X[: s.compiled.n_state], s.params(X), s.D, s.free_idx)
        self._last_jacobian = (np.array(X), J)
        return J

    def bordered_jacobian(self, X, rows):
        """``[G_X; rows]``: structured and solved by condensation when
        ``self.condensed``, else sparse."""
        if self.condensed:
            return self.interval_jacobian(X).bordered(rows)
        return super().bordered_jacobian(X, rows)

    def transfer_matrices(self, X, full: bool = False) -> np.ndarray:
        """Condensed ``A_i`` with ``v_{i+1} = A_i v_i`` at the mesh points (``full``:
        the maps from ``v_i`` to all nodes of interval ``i``). Reuses the Jacobian
        of the tangent at the same ``X`` (its phase row may predate ``accept``; only
        the interval blocks are used)."""
        last = self._last_jacobian
        if last is not None and np.array_equal(last[0], X):
            J = last[1]
        else:
            J = self.interval_jacobian(X) if self.condensed else CycleProblem.jacobian(self, X)
        if isinstance(J, CollocationJacobian):
            if J.maps is None:                  # a singular interval: LAPACK says so
                return floquet.block_transfer_matrices(J.blocks, self.vf.n, full)
            n = self.vf.n
            return -(J.maps[:, :, :n] if full else J.maps[:, -n:, :n])
        return floquet.transfer_matrices(J, self.vf.n, self.ntst, self.ncol, full)

    def evaluate(self, X, t) -> np.ndarray:
        """Collocation polynomial at times ``t`` in ``[0, 1)``, shape ``(len(t), n)``."""
        return colloc.evaluate(X[: self.n_nodes * self.vf.n], self.mesh, self.ncol,
                               self.vf.n, t)

    def extrema(self, X, A) -> tuple[np.ndarray, np.ndarray]:
        """``(min_t, max_t)`` over the cycle of each row of ``A u(t)``, exact for the
        collocation polynomial (``A``: m x n; see ``collocation.extrema``)."""
        return colloc.extrema(X[: self.n_nodes * self.vf.n], self.mesh, self.ncol,
                              self.vf.n, np.atleast_2d(A))

    def multipliers(self, X) -> np.ndarray:
        """Floquet multipliers sorted by decreasing modulus (kept for the last ``X``)."""
        method = self.settings.floquet
        return self.floquet_multipliers(X, "schur" if method == "auto" else method)


def _collocation_system(settings: CollocationSettings) -> tuple:
    """``(kind, builder)`` of the collocation system for ``settings.jacobian``:
    'blocks' (pointwise kernel, NumPy assembly) or 'graph' (whole-graph CasADi AD)."""
    ntst, ncol = settings.ntst, settings.ncol
    if settings.jacobian == "graph":
        return f"collocation_{ntst}_{ncol}", colloc.builder(ntst, ncol)
    backend = kernel_backend(settings.backend)
    return f"collocation_blocks_{ntst}_{ncol}_{backend}", blocks.builder(ntst, ncol, backend)


def _condensed_solver(settings: CollocationSettings, system) -> bool:
    """Whether the Newton systems are solved by condensation (``settings.linear_solver``;
    'auto': where that pays, ``condensed.condensed_pays``)."""
    if settings.linear_solver == "auto":
        return settings.jacobian == "blocks" and condensed.condensed_pays(
            system.kernel.n * settings.ncol, system.fill(), system.band is not None)
    return settings.linear_solver == "condensed"


def _check_mesh(mesh, ntst) -> np.ndarray:
    if mesh is None:
        return np.linspace(0.0, 1.0, ntst + 1)
    m = np.array(mesh, dtype=float).ravel()
    if m.size != ntst + 1 or m[0] != 0.0 or m[-1] != 1.0 or not np.all(np.diff(m) > 0):
        raise ValueError(f"mesh must be {ntst + 1} increasing times from 0 to 1, got {mesh!r}")
    return m


def sample_orbit(orbit, t, n) -> np.ndarray:
    """Guess values at the node times, flattened node by node."""
    if callable(orbit):
        try:
            u = np.asarray(orbit(t), dtype=float)
            u = u if u.shape == (t.size, n) else u.T
        except (TypeError, ValueError):
            u = None
        if u is None or u.shape != (t.size, n):
            u = np.array([np.asarray(orbit(s), dtype=float).ravel() for s in t])
    else:
        samples = np.asarray(orbit, dtype=float)
        if samples.ndim != 2 or samples.shape[1] != n or samples.shape[0] < 2:
            raise ValueError(f"orbit must be a callable or an array (m, {n}), got shape "
                             f"{samples.shape}")
        ts = np.arange(samples.shape[0]) / samples.shape[0]
        u = np.column_stack([np.interp(t, ts, samples[:, j], period=1.0) for j in range(n)])
    if u.shape != (t.size, n) or not np.all(np.isfinite(u)):
        raise ValueError(f"orbit must give finite states of size {n}")
    return u.ravel()
