"""Pseudo-arclength continuation as a step iterator.

From a point ``X_k`` with unit tangent ``tau_k`` (``G_X(X_k) tau_k = 0``):

* predictor ``X^0 = X_k + ds tau_k``;
* corrector: Newton on the bordered system
  ``G(X) = 0``, ``tau_k . (X - X^0) = 0`` with the matrix
  ``[G_X(X); tau_k^T]`` (``Problem.bordered_jacobian``) factorized by SuperLU, or by the
  problem's own structured solver (collocated cycles: condensation), its factors kept
  for chord steps while they contract (``newton.newton``);
* tangent: ``[G_X(X_{k+1}); tau_k^T] t = e_{m+1}``, ``tau_{k+1} = t / |t|``
  (so ``tau_{k+1} . tau_k > 0``: orientation is kept), or the secant, on fresh factors
  at ``X_{k+1}`` when the monitor uses them (``Problem.monitor_uses_lu``: the
  branch-point test; condensed collocated cycles, whose Floquet maps come with them),
  else by refinement on the corrector's last factors;
* step control: ``ds <- min(grow ds, ds_max)`` after at most
  ``easy_iterations`` Newton iterations (a run of chord steps counts as one,
  ``NewtonResult.effort``); on failure ``ds <- shrink ds`` and
  retry; below ``ds_min`` the run stops with status ``'failed'`` and the last
  residual in the message.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .newton import NewtonResult, factorize, newton, solve
from .settings import PALC, ContinuationSettings


@dataclass(frozen=True)
class Step:
    """One converged point: ``X``, its tangent and how it was reached."""

    X: np.ndarray
    tau: np.ndarray
    ds: float
    iterations: int
    residual: float
    lu: object = field(repr=False, compare=False, default=None)


def correct(problem, X_pred: np.ndarray, tau: np.ndarray, settings) -> NewtonResult:
    """Newton on ``G(X) = 0, tau . (X - X_pred) = 0`` from ``X_pred``."""
    X_pred = np.array(X_pred, dtype=float)

    def H(X):
        return np.append(problem.residual(X), tau @ (X - X_pred))

    return newton(H, lambda X: problem.bordered_jacobian(X, tau), X_pred, settings)


def tangent(problem, X: np.ndarray, tau_ref: np.ndarray, lu=None):
    """Unit tangent with ``tau . tau_ref > 0`` and the LU of ``[G_X; tau_ref^T]``.

    With ``lu`` (factors of a nearby matrix, e.g. the corrector's last one, as
    AUTO reuses it) the tangent is solved by refinement on them when that
    converges to round-off, and the returned factors are those ``lu``."""
    rhs = np.zeros(X.size)
    rhs[-1] = 1.0
    t, lu = solve(problem.bordered_jacobian(X, tau_ref), rhs, lu)
    if t is None:
        return None, None
    return t / np.linalg.norm(t), lu


def _turn(a, b) -> float:
    """The angle between two unit tangents."""
    return float(np.arccos(np.clip(np.dot(a, b), -1.0, 1.0)))


class ContinuationIterator:
    """Iterate PALC steps; ``status``/``message`` tell why it stopped.

    ``status`` is ``'running'`` while iterating, then one of ``'max_steps'``,
    ``'bound'`` (a parameter left ``settings.bounds``), ``'failed'`` (corrector
    failed at ``ds_min``, or the start point did not converge).
    ``tau_ref`` (optional) orients the first tangent (``tau . tau_ref > 0``)
    instead of ``settings.direction``; used when a curve is restarted.
    """

    def __init__(self, problem, algorithm: PALC, settings: ContinuationSettings,
                 tau_ref: np.ndarray | None = None, origin: Step | None = None):
        self.problem, self.algorithm, self.settings = problem, algorithm, settings
        self.tau_ref = None if tau_ref is None else np.asarray(tau_ref, dtype=float)
        #: a first step taken as it is (a continuous restart), instead of correcting X0
        self.origin = origin
        self.status, self.message, self.failure = "running", "", {}
        self.stats = {"steps": 0, "newton_iterations": 0, "rejected_steps": 0,
                      "time_steps": 0.0}
        self.ds = settings.ds
        #: a cap on the next step only (``ds`` itself, the step control's, is kept)
        self.cap = np.inf

    def __iter__(self):
        step = self.start()
        if step is None:
            return
        yield step
        for _ in range(self.settings.max_steps):
            t0 = time.perf_counter()
            step = self.advance(step)
            self.stats["time_steps"] += time.perf_counter() - t0
            if step is None:
                return
            yield step
        self._stop("max_steps", f"reached max_steps = {self.settings.max_steps}")

    # ------------------------------------------------------------------------
    def start(self) -> Step | None:
        """Correct ``X0`` at fixed parameter and orient the first tangent (or take
        ``origin`` as it is)."""
        prob, X0 = self.problem, self.problem.X0
        if self.origin is not None:
            prob.accept(self.origin.X)
            return self.origin
        e = prob.start_row()
        res = correct(prob, X0, e, self.settings.newton)
        if not res.converged:
            return self._fail("start point did not converge: " + res.message, res, 0.0)
        if self.tau_ref is not None:
            tau, lu = tangent(prob, res.X, self.tau_ref)
        else:
            tau, lu = tangent(prob, res.X, e)
        if tau is None:
            return self._fail("singular Jacobian at the start point (start at a "
                              "fold or branch point?)", res, 0.0)
        if self.tau_ref is None:
            tau = self.settings.direction * tau
        if prob.monitor_uses_lu and self.settings.detect:     # the monitor's factors
            lu = factorize(prob.bordered_jacobian(res.X, tau))
        prob.accept(res.X)
        self.stats["newton_iterations"] += res.iterations
        return Step(res.X, tau, 0.0, res.iterations, res.residual, lu)

    def advance(self, step: Step) -> Step | None:
        """One PALC step with retries at smaller ``ds``; ``None`` when stopping."""
        s = self.settings
        cap, self.cap = self.cap, np.inf
        while True:
            ds = min(self.ds, cap)
            res = correct(self.problem, step.X + ds * step.tau, step.tau, s.newton)
            self.stats["newton_iterations"] += res.iterations
            new = self._accept(step, res, ds) if res.converged else None
            turn = _turn(step.tau, new.tau) if new is not None else 0.0
            if new is not None and not (s.max_turn and turn > s.max_turn):
                break
            self.stats["rejected_steps"] += 1
            why = res.message if new is None else \
                f"the tangent turned by {turn:.3g} rad > max_turn = {s.max_turn:.3g}"
            if ds * s.step_shrink < s.ds_min:
                return self._fail(f"corrector failed at ds = {ds:.3e} (ds_min = "
                                  f"{s.ds_min:.1e}): {why}", res, ds)
            self.ds = cap = ds * s.step_shrink
        if self._out_of_bounds(new.X):
            return None
        self.stats["steps"] += 1
        self.problem.accept(new.X)
        if res.effort <= s.easy_iterations:
            self.ds = min(self.ds * s.step_grow, s.ds_max)
        return new

    def _accept(self, step: Step, res: NewtonResult, ds: float) -> Step | None:
        if self.algorithm.tangent == "secant":
            tau = res.X - step.X
            tau = tau / np.linalg.norm(tau)
            lu = factorize(self.problem.bordered_jacobian(res.X, tau))
        else:
            # the factors at X: for the monitor (a branch-point test, a cycle's
            # condensed Floquet maps); else the corrector's are refined on
            exact = self.problem.monitor_uses_lu and self.settings.detect
            tau, lu = tangent(self.problem, res.X, step.tau, None if exact else res.lu)
        if tau is None or lu is None:
            return None
        return Step(res.X, tau, ds, res.iterations, res.residual, lu)

    def _out_of_bounds(self, X) -> bool:
        values = self.problem.par_dict(X)
        for name, (lo, hi) in self.settings.bounds.items():
            if not lo <= values[name] <= hi:
                self._stop("bound", f"parameter {name} = {values[name]:.6g} left "
                                    f"[{lo:.6g}, {hi:.6g}]")
                return True
        return False

    def _stop(self, status: str, message: str) -> None:
        if self.status == "running":
            self.status, self.message = status, message

    def _fail(self, message: str, res: NewtonResult, ds: float):
        self._stop("failed", message)
        self.failure = {"residual": float(res.residual), "iterations": int(res.iterations),
                        "ds": float(ds), "X": np.array(res.X)}
        return None
