"""Outcome of a run: decay, limit cycle, contact, impacting limit cycle, or unsettled.

**Poincaré section.** Returns are the upward crossings of the tip displacement through
the reference ``y_ref`` (the mean tip displacement over the last quarter of the samples),
located by linear interpolation between output samples; a crossing counts only after
the tip has been below ``y_ref − a/2`` since the previous one (a = current half
amplitude), so impacts and chattering do not create spurious returns. Cycle k runs
between returns k and k+1: its period ``T_k``, its tip half-amplitude
``A_k = (max − min)/2`` and its Poincaré point ``x_k`` (state interpolated at the return).

**Criteria** (:class:`Criteria`, defaults in brackets):

- *contact*: a gap falls to the contact distance ``eps = (eps/H) H*/2`` (the onset of the
  regularized impact force) at one of the 101 check points, at an output sample. With
  contact off the run stops there (paper, Fig. 4); with contact on it goes on.
- *limit cycle*: the last ``cycles`` [4] cycles agree: relative changes of period and of
  amplitude between successive cycles, and the distance between successive Poincaré
  points relative to the cycle's size, all below ``tol`` [1e-3] (impacting cycles:
  ``tol_impacting`` [2e-2], since chattering cycles are only nearly periodic). The
  largest of these changes is reported as ``convergence``.
- *decay*: the last ``cycles`` cycle amplitudes decrease monotonically and the last one
  is below ``decay_ratio`` [0.1] times the first cycle's amplitude; or the deviation from
  the steady state is below ``floor`` [1e-9 of the gap] over the whole last chunk.
- otherwise *unsettled* (or *contact* if contact happened but no impacting cycle settled).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import scipy.interpolate
import scipy.optimize

from ..model.contact import GAP_POINTS, contact_load, gaps, reference_force
from .integrators import Trajectory
from ..model.assembly import Model

__all__ = ["Criteria", "Outcome", "OutcomeKind", "classify", "Monitor", "poincare_returns"]

#: What a run did (module docstring): "decay" back to the steady state; "lco" a settled
#: limit cycle without contact; "impacting_lco" a settled cycle with wall contact;
#: "contact" a gap reached the contact distance but no impacting cycle settled (or the
#: contact-free run stopped there); "unsettled" none of these by the end of the run.
OutcomeKind = Literal["decay", "lco", "impacting_lco", "contact", "unsettled"]


@dataclass(frozen=True)
class Criteria:
    """Thresholds of the classification (module docstring)."""

    cycles: int = 4
    tol: float = 1e-3
    tol_impacting: float = 2e-2
    decay_ratio: float = 0.1
    floor: float = 1e-9
    stop_on_contact: bool | None = None   # None: stop on contact iff the scene has no contact

    def __post_init__(self):
        if not (isinstance(self.cycles, int) and self.cycles >= 2):
            raise ValueError(f"cycles must be an integer >= 2, got {self.cycles!r}")
        for name in ("tol", "tol_impacting", "decay_ratio", "floor"):
            if not 0 < getattr(self, name) < 1:
                raise ValueError(f"{name} must lie in (0, 1), got {getattr(self, name)}")


@dataclass(frozen=True)
class Outcome:
    """Classification and measured quantities of one run (None where not applicable).

    Forces are totals over the beam ``∫ F_i dx`` normalized by ``F0 = m f1² H`` (m = 1
    the beam mass, f1 = w1/2π, H = H*/2). ``impacts_per_cycle``: separate contact
    intervals per settled cycle (chattering). ``mean_flow_reduction``:
    ``1 − mean(Q1+Q2)/(Q1+Q2)_steady`` over the settled cycles.
    """

    outcome: OutcomeKind
    period: float | None = None
    frequency: float | None = None
    tip_amplitude: float | None = None
    convergence: float | None = None
    cycles: int = 0
    contact: bool = False
    first_contact_time: float | None = None
    first_contact_position: float | None = None
    contact_positions: list = field(default_factory=list)
    max_impact_force: float | None = None
    impacts_per_cycle: float | None = None
    mean_flow_reduction: float | None = None
    t_settled: float | None = None

    def to_json(self) -> dict:
        return {k: (float(v) if isinstance(v, np.floating) else v) for k, v in self.__dict__.items()}


def poincare_returns(t, y, y_ref=None):
    """Return times (interpolated) and sample indices of upward crossings (module doc)."""
    t, y = np.asarray(t), np.asarray(y)
    tail = y[3 * len(y) // 4:]
    y_ref = float(np.mean(tail)) if y_ref is None else y_ref
    half = 0.5 * (tail.max() - tail.min()) / 2 if tail.size else 0.0
    armed, times, index = False, [], []
    below = y < y_ref - half
    for k in range(1, len(y)):
        if below[k - 1]:
            armed = True
        if armed and y[k - 1] < y_ref <= y[k]:
            s = (y_ref - y[k - 1]) / (y[k] - y[k - 1])
            times.append(t[k - 1] + s * (t[k] - t[k - 1]))
            index.append(k)
            armed = False
    return np.array(times), np.array(index, dtype=int)


def _cycles(t, X, model):
    """Periods, amplitudes, Poincaré points and return indices of the complete cycles."""
    y = model.tip_deflection(X)
    times, idx = poincare_returns(t, y)
    if times.size < 2:
        return None
    w = (times - t[idx - 1]) / (t[idx] - t[idx - 1])
    points = X[idx - 1] + w[:, None] * (X[idx] - X[idx - 1])
    amps = np.array([(_peak(y[a:b]) + _peak(-y[a:b])) / 2 for a, b in zip(idx[:-1], idx[1:])])
    size = np.ptp(X[idx[-2]:idx[-1]], axis=0).max() if idx.size else 1.0
    return np.diff(times), amps, points, idx, times, size


def _peak(y) -> float:
    """Largest value of the samples, refined by a parabola through the top three."""
    k = int(np.argmax(y))
    if 0 < k < len(y) - 1:
        a, b, c = y[k - 1], y[k], y[k + 1]
        denom = a - 2 * b + c
        if denom < 0:
            return float(b - (a - c) ** 2 / (8 * denom))
    return float(y[k])


def _settled(cyc, m, tol):
    """Largest relative change over the last m cycles, or None if too few cycles."""
    periods, amps, points, _, _, size = cyc
    if periods.size < m + 1:
        return None
    p, a, x = periods[-m - 1:], amps[-m - 1:], points[-m - 2:]
    size = size or 1.0
    changes = [np.max(np.abs(np.diff(p))) / p[-1], np.max(np.abs(np.diff(a))) / max(a[-1], 1e-300),
               np.max(np.abs(np.diff(x, axis=0))) / size]
    return float(max(changes))


def _decayed(cyc, crit, X, x_ref, gap):
    if np.max(np.abs(X[-max(len(X) // 8, 1):] - x_ref)) < crit.floor * gap:
        return True
    if cyc is None:
        return False
    amps = cyc[1]
    if amps.size < crit.cycles + 1:
        return False
    last = amps[-crit.cycles - 1:]
    return bool(np.all(np.diff(last) < 0) and last[-1] < crit.decay_ratio * amps[0])


def _first_contact(t, X, model):
    """(sample index, time, position) of the first contact, or None.

    The samples give the interval; the time is then located inside it (event location):
    the root of ``min_x h(x, t) − eps`` on the cubic through the samples ``k−3 .. k``
    (Lagrange interpolation of the state, error O(dt_out⁴)), by Brent's method.
    """
    eps = model.scene.contact_gap
    h = gaps(model, X)
    touch = h.min(axis=(1, 2)) <= eps
    if not touch.any():
        return None
    k = int(np.argmax(touch))
    if k == 0:
        return 0, float(t[0]), float(GAP_POINTS[np.argmin(h[0].min(axis=0))])
    state = scipy.interpolate.BarycentricInterpolator(t[max(0, k - 3):k + 1], X[max(0, k - 3):k + 1])
    smallest = lambda s: gaps(model, state(s))[0].min(axis=0)
    tc = scipy.optimize.brentq(lambda s: smallest(s).min() - eps, t[k - 1], t[k],
                               xtol=1e-14 * max(1.0, abs(t[k])))
    return k, float(tc), float(GAP_POINTS[np.argmin(smallest(tc))])


def classify(traj: Trajectory, steady, criteria: Criteria = Criteria()) -> Outcome:
    """Classify a trajectory and measure its cycle (module docstring)."""
    return _classify(traj.t, traj.x, traj.model, steady, criteria, final=True,
                     closed=traj.gap_closed)


def _classify(t, X, model, steady, crit, final, closed=False):
    scene = model.scene
    gap = scene.hstar / 2
    contact = _first_contact(t, X, model)
    if contact is None and closed:
        # the gap went from > eps to 0 between the last sample and the solver failure
        h = gaps(model, X[-1:])[0]
        contact = len(t) - 1, float(t[-1]), float(GAP_POINTS[np.argmin(h.min(axis=0))])
    stop_on_contact = (not scene.contact) if crit.stop_on_contact is None else crit.stop_on_contact
    info = {}
    if contact is not None:
        info = dict(contact=True, first_contact_time=contact[1], first_contact_position=contact[2],
                    contact_positions=[contact[2]])
        if stop_on_contact:
            return Outcome("contact", **info)
    cyc = _cycles(t, X, model)
    tol = crit.tol_impacting if contact is not None else crit.tol
    change = _settled(cyc, crit.cycles, tol) if cyc is not None else None
    if _decayed(cyc, crit, X, steady.x, gap):
        return Outcome("decay", **info)
    if change is not None and change < tol:
        kind = "impacting_lco" if contact is not None else "lco"
        return _measure(kind, t, X, model, steady, cyc, crit.cycles, change, info)
    if not final:
        return None
    if contact is not None:
        return Outcome("contact", **info)
    return Outcome("unsettled", convergence=change)


def _measure(kind, t, X, model, steady, cyc, m, change, info):
    periods, amps, _, idx, times, _ = cyc
    a, b = idx[-m - 1], idx[-1]
    T = float(np.mean(periods[-m:]))
    Qs = steady.x[-2:].sum()
    flow = X[a:b, -2:].sum(axis=1)
    reduction = 1.0 - float(np.trapezoid(flow, t[a:b]) / (t[b - 1] - t[a]) / Qs)
    out = dict(period=T, frequency=2 * np.pi / T, tip_amplitude=float(amps[-1]), convergence=change,
               cycles=int(periods.size), mean_flow_reduction=reduction, t_settled=float(times[-1]))
    if info.get("contact"):
        out.update(_impacts(t[a:b], X[a:b], model, m))
    return Outcome(kind, **{**info, **out})


def _impacts(t, X, model, m):
    """Impact force, contact positions and chattering count over the settled cycles."""
    density, total = contact_load(model, X)
    on = total > 0
    starts = np.flatnonzero(on & ~np.r_[False, on[:-1]])
    ends = np.flatnonzero(on & ~np.r_[on[1:], False])
    positions = sorted({round(float(GAP_POINTS[np.argmax(density[a:b + 1].max(axis=0))]), 3)
                        for a, b in zip(starts, ends)})
    return dict(max_impact_force=float(total.max() / reference_force(model)),
                impacts_per_cycle=starts.size / m, contact_positions=positions)


class Monitor:
    """Stop rule for :func:`fsicas.timedomain.integrators.simulate`: classifies after each chunk
    (``contact_only``: stops only at contact, for contact-free runs kept to t_end)."""

    def __init__(self, model: Model, steady, criteria: Criteria = Criteria(), contact_only: bool = False):
        self.model, self.steady, self.criteria = model, steady, criteria
        self.contact_only = contact_only

    def __call__(self, t, X) -> OutcomeKind | None:
        if self.contact_only:   # run to t_end, but a contact-free run still ends at contact
            return "contact" if _first_contact(t, X, self.model) is not None else None
        out = _classify(t, X, self.model, self.steady, self.criteria, final=False)
        return None if out is None else out.outcome
