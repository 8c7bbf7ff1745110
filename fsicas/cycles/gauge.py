"""Physical quantities of a cycle on the adapter's field, for both routes.

A cycle problem of :mod:`continuation` on ``flutter_field`` has unknowns
``X = (profile, 100 T, Π)``. Per point the gauge reports:

- ``ustar``: (Q1 + Q2)/H* of the *steady state at the same pressure drop* (time
  integration holds Δp at the steady value of the requested U*, so a cycle "at U*" is
  the cycle at that Δp), by Newton warm-started from the last point;
- ``pressure_drop`` Δp = 100 M* Π, the period in units of T, the Floquet multipliers and
  stability (all non-trivial multipliers, those of the Poincare map, inside the unit
  circle), the state at phase 0;
- from the profile, by the route: the tip half-amplitude (max − min of y(x_ref, t))/2 and
  the minimal gap min_{x,t} h_c(x, t) with its ratio to eps (:mod:`fsicas.model.contact`);
- ``quadrature_error``: the relative error of the equations over the cycle from the flow
  quadrature, against a rule of twice the nodes (:mod:`fsicas.model.accuracy`), and
  ``quadrature_nodes``, the nodes of the model it was computed on (``scene.n_quad``).

:class:`PolynomialGauge` measures a collocated cycle on its polynomial.
"""
from __future__ import annotations

import time
import warnings

import numpy as np

import continuation as C

from ..linear.adapter import LOG_M, PI, PI_SCALE, TIME_SCALE, steady_ustar
from ..model import contact
from ..model.accuracy import adequate_model, quadrature_error
from ..model.patch import penetration

__all__ = ["Gauge", "PolynomialExtrema", "PolynomialGauge", "PERIOD_COLUMN", "model_parameters",
           "quadrature_controlled"]

PERIOD_COLUMN = "cycle_period"
"""Branch column of the period in units of T (the library's ``period`` is in T/100)."""


class Gauge:
    """Common measures of cycle unknowns X; the routes add amplitude and gap. ``eps``:
    the contact distance of the analysed scene (``scene.contact_gap``)."""

    def __init__(self, model, x_eq, eps: float):
        self.model = model
        self.eps = eps
        self.x_eq = np.asarray(x_eq, dtype=float)
        #: the largest quadrature error measured, with its states and parameters
        self.worst = (0.0, None, None)
        self._kept = {}

    def common(self, problem, X) -> dict:
        """U*, Δp, period, multipliers, stability and state at X."""
        p = problem.params(X)
        mu, rest = problem.multipliers(X), problem.section_multipliers(X)
        mstar = 10 ** p[problem.vf.par_index(LOG_M)]
        return {"ustar": self.ustar(problem, X), "mstar": float(mstar),
                "pressure_drop": float(p[problem.vf.par_index(PI)] * PI_SCALE * mstar),
                PERIOD_COLUMN: problem.period(X) / TIME_SCALE, "multipliers": mu,
                "stable": bool(np.all(np.abs(rest) < 1.0)), "state": problem.state(X).copy(),
                "quadrature_error": self.quadrature_error(problem, X),
                "quadrature_nodes": self.model.scene.n_quad}

    def ustar(self, problem, X) -> float:
        """U* of the steady state at the pressure drop of X (Newton from the last one)."""
        ustar, self.x_eq = steady_ustar(problem.vf, problem.params(X), self.x_eq,
                                        self.model.scene.hstar)
        return ustar

    def quadrature_error(self, problem, X) -> float:
        """:func:`fsicas.model.accuracy.quadrature_error` over the cycle (kept for the
        last X; the largest so far in :attr:`worst`)."""
        def compute():
            states, p = self.states(problem, X), model_parameters(self.model, problem, X)
            error = quadrature_error(self.model, states, p)
            if error > self.worst[0]:
                self.worst = (error, states, p)
            return error
        return self.kept("quadrature_error", problem, X, compute)

    @staticmethod
    def states(problem, X) -> np.ndarray:
        """States (rows) of the cycle X: the nodes of a collocation problem, the segment
        starts of a shooting problem."""
        return problem.nodes(X) if hasattr(problem, "nodes") else problem.points(X)

    def kept(self, name: str, problem, X, compute):
        """``compute()``, kept under ``name`` for the last (problem, X): the record and
        the hooks of one point share it."""
        data, last = np.asarray(X).tobytes(), self._kept.get(name)
        if last is None or last[0] is not problem or last[1] != data:
            last = self._kept[name] = (problem, data, compute())
        return last[2]

    def tip(self, x) -> np.ndarray:
        """Deflection y(x_ref) of states x (rows) at the model's reference point."""
        return self.model.tip_deflection(x)

    def impact_measures(self, x, weights, p) -> dict:
        """``peak_force``: the largest total impact load (at the model's parameters ``p``)
        over the samples ``x`` in units
        of the reference force of Fig. 9 (:func:`fsicas.model.contact.reference_force`);
        ``flow_reduction``: 1 - the time mean of Q1 + Q2 (quadrature ``weights`` of the
        samples) over the steady flow at the same pressure drop (call after
        :meth:`common`, which finds that steady state)."""
        total = penetration(self.model, x, p).load
        flow = np.asarray(x)[:, -2:].sum(axis=1)
        mean = float(np.dot(weights, flow) / np.sum(weights))
        return {"peak_force": float(total.max() / contact.reference_force(self.model)),
                "flow_reduction": 1.0 - mean / float(self.x_eq[-2:].sum())}

    def min_gap(self, x) -> np.ndarray:
        """``min_{x, c} h_c(x)`` of each state (row): :func:`fsicas.model.contact.gaps`."""
        return contact.gaps(self.model, x).min(axis=(1, 2))


def quadrature_controlled(compute, model, tol: float | None):
    """``compute(model) -> (branch, gauge)`` once, and once more on the adequate model
    (:func:`fsicas.model.accuracy.adequate_model`) of the worst cycle its gauge measured
    when that cycle's quadrature error exceeds ``tol`` (None: never); a warning if the
    error still exceeds it. Returns the branch."""
    branch, gauge = compute(model)
    if tol is not None and gauge.worst[0] > tol:
        branch, gauge = compute(adequate_model(model, *gauge.worst[1:], tol)[0])
    if tol is not None and gauge.worst[0] > tol:
        warnings.warn(f"quadrature error {gauge.worst[0]:.2g} on {gauge.model.scene.n_quad} "
                      f"nodes exceeds quadrature_tol {tol:g}", RuntimeWarning, stacklevel=3)
    return branch


def model_parameters(model, problem, X) -> np.ndarray:
    """The model's parameter vector p at the adapter's parameters of X (Δp = 100 M* Π,
    M* = 10^log10_mstar, the rest by name: :mod:`fsicas.linear.adapter`)."""
    value = problem.par_dict(X)
    mstar = 10 ** value.pop(LOG_M)
    return model.parameters(pressure_drop=value.pop(PI) * PI_SCALE * mstar, mstar=mstar, **value)


class PolynomialExtrema:
    """Tip extremes and the minimal gap of a collocated cycle, exact for its polynomial
    (``continuation.CycleProblem.extrema``): the tip ``y(x_ref, t)`` and the gaps
    ``h_c(x_j, t) = H_c(x_j) + s_c y(x_j, t)`` at ``GAP_POINTS``, both walls."""

    def __init__(self, model):
        n = model.n_modes
        rows = lambda phi: np.hstack([np.zeros((phi.shape[1], n)), phi.T,
                                      np.zeros((phi.shape[1], 2))])
        self._tip_row = rows(model.probe.phi[:, 1:])
        phi = model.basis_at(contact.GAP_POINTS).phi
        self._gap_rows = np.vstack([s * rows(phi) for s in contact.WALL_SIGNS])
        self._walls = np.concatenate([wall(contact.GAP_POINTS) for wall in model.scene.walls])

    def tip(self, problem, X) -> tuple[float, float]:
        """``(min_t y(x_ref, t), max_t y(x_ref, t))``."""
        low, high = problem.extrema(X, self._tip_row)
        return float(low[0]), float(high[0])

    def gap_condition(self, level: float) -> C.Extremum:
        """``min_{t, x_j, c} h_c(x_j, t) = level`` as a condition on the cycle."""
        return C.Extremum(self._gap_rows, self._walls, level)

    def min_gap(self, problem, X) -> float:
        """``min_{t, x_j, c} h_c(x_j, t)``."""
        return self.gap_condition(0.0).value(problem, X)


class PolynomialGauge(Gauge):
    """Measures of collocation unknowns X = (nodes, 100 T, Π) on the polynomial: the
    extrema exact (:class:`fsicas.cycles.gauge.PolynomialExtrema`), the contact
    intervals counted on ``samples`` points per mesh interval (dense at the impacts)."""

    def __init__(self, model, x_eq, eps: float, samples: int):
        super().__init__(model, x_eq, eps)
        self.samples, self.t_last = samples, time.perf_counter()
        self._extrema = PolynomialExtrema(model)

    def record(self, problem, X) -> dict:
        """The columns of one branch point (the fields of :class:`CollocatedImpactPoint`)."""
        mesh = problem.mesh
        t = (mesh[:-1, None] + np.diff(mesh)[:, None] * np.arange(self.samples)
             / self.samples).ravel()
        x = problem.evaluate(X, t)
        inside = self.min_gap(x) < self.eps
        impacts = int(np.sum(inside & ~np.roll(inside, 1))) if not inside.all() else 1
        y_min, y_max = self._extrema.tip(problem, X)
        lowest = self._extrema.min_gap(problem, X)
        common = self.common(problem, X)
        now = time.perf_counter()
        wall, self.t_last = now - self.t_last, now
        weights = np.repeat(np.diff(mesh), self.samples)          # the samples' time steps
        return {**common, "tip_amplitude": (y_max - y_min) / 2,
                "min_gap": lowest, "gap_ratio": lowest / self.eps, "impacts": impacts,
                "ntst": problem.ntst, "ncol": problem.ncol, "wall_time": wall,
                **self.impact_measures(x, weights, model_parameters(self.model, problem, X))}
