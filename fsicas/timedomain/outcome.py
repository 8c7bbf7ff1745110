"""Outcome of a run: decay, limit cycle, contact, impacting limit cycle, or unsettled.

**Poincaré section and dense output**: :mod:`fsicas.timedomain.returns`.

**Criteria** (:class:`Criteria`, defaults in brackets):

- *contact*: a gap falls to the contact distance ``eps = (eps/H) H*/2`` (the onset of the
  regularized impact force) anywhere along the beam (:func:`fsicas.model.patch.penetration`),
  at an output sample; the time is then located between the samples. With contact off the run stops there (paper,
  Fig. 4); with contact on it goes on.
- *limit cycle*: over the last ``cycles`` [4] cycles, the **remaining change** of the
  period, of the amplitude and of the Poincaré point (relative to the cycle's size) is
  below ``tol``. The remaining change extrapolates the cycle-to-cycle differences ``d_k``:
  a monotone approach with ``|d_k|`` decreasing by at most the ratio μ per cycle has
  ``|d_last| μ/(1 − μ)`` still to go (Aitken), an alternating or noisy one at most
  ``max |d_k|``, and a monotone one that does not slow down is not settled. ``tol``
  [None] defaults to ``SETTLING_PER_RTOL = 1000`` times the integrator's rtol (1e-5 at
  rtol 1e-8), within [1e-8, 1e-2]: what the samples can resolve, not a fixed 1e-3 that
  declared growing cycles settled with amplitudes low by up to 2 %. Impacting cycles:
  the largest plain change below ``tol_impacting`` [2e-2] (chattering cycles are only
  nearly periodic), between returns of the tip; at the end of a run that did not settle
  so, between every k-th return, k up to ``MAX_SWINGS`` [3] (a cycle of k tip swings:
  its period spans them; not earlier, since a slowly fading alternation of a cycle of
  one swing passes for two swings at first). The remaining change is reported as
  ``convergence``.
- *decay*: the last ``cycles`` cycle amplitudes decrease monotonically and the last one
  is below ``decay_ratio`` [0.1] times the first cycle's amplitude; or the deviation from
  the steady state is below ``floor`` [1e-9 of the gap] over the last eighth of the samples.
- at the end of a run: a contact-free cycle whose remaining change is below ``tol_end``
  [1e-2] is a limit cycle with ``settled = False`` (its ``convergence`` says how far it
  has still to go); an impacting oscillation whose cycles still differ by more than
  ``tol_impacting`` is *impacting_nonperiodic*: not periodic (quasi-periodic, chaotic or
  a long transient), measured over its last cycles like a cycle, its ``convergence``
  the largest change between them (of single tip returns); otherwise *unsettled* (or
  *contact* if contact happened but too few cycles followed to measure).

**Incremental monitoring.** :class:`Monitor` keeps what it has found (the contact scan
up to the last sample, the first cycle's amplitude, the latest period) and looks at the
last ``1.5 (cycles + 4)`` periods only (after a contact ``1.5 (MAX_SWINGS cycles + 4)``),
so a run costs O(samples), not O(samples²).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Literal

import numpy as np
import scipy.interpolate
import scipy.optimize

from ..model.assembly import Model
from ..model.contact import reference_force
from ..model.patch import contact_intervals, penetration
from .integrators import Trajectory
from .returns import Cycles, cycles, xdot_rows

__all__ = ["Criteria", "Outcome", "OutcomeKind", "OUTCOME_WORDS", "outcome_words", "classify",
           "Monitor", "SETTLING_PER_RTOL"]

#: What a run did (module docstring): "decay" back to the steady state; "lco" a limit
#: cycle without contact; "impacting_lco" a settled cycle with wall contact; "contact" a
#: gap reached the contact distance but no impacting cycle settled (or the contact-free
#: run stopped there); "impacting_nonperiodic" an impacting oscillation that is not
#: periodic by the end of the run; "unsettled" none of these by the end of the run.
OutcomeKind = Literal["decay", "lco", "impacting_lco", "impacting_nonperiodic", "contact",
                      "unsettled"]

#: What each outcome means, in words (for reports, titles and legends).
OUTCOME_WORDS = {"decay": "decays to the steady state", "lco": "limit cycle, no contact",
                 "contact": "reaches the wall", "impacting_lco": "impacting limit cycle",
                 "impacting_nonperiodic": "impacting, not periodic",
                 "unsettled": "not settled", "error": "solver failure"}


def outcome_words(kind: str) -> str:
    """An outcome (e.g. ``impacting_lco``) in words."""
    return OUTCOME_WORDS.get(kind, str(kind).replace("_", " "))


#: The default settling tolerance per unit of the integrator's rtol (module docstring).
SETTLING_PER_RTOL = 1e3
_TOL_RANGE = (1e-8, 1e-2)
#: Relative differences between cycles below ``NOISE × tol`` are noise, not a trend.
NOISE = 1e-3
#: Tip swings an impacting cycle may span at most (module docstring).
MAX_SWINGS = 3


@dataclass(frozen=True)
class Criteria:
    """Thresholds of the classification (module docstring). ``tol = None``: the default
    :meth:`settling_tol` of the run's rtol."""

    cycles: int = 4
    tol: float | None = None
    tol_impacting: float = 2e-2
    tol_end: float = 1e-2
    decay_ratio: float = 0.1
    floor: float = 1e-9
    stop_on_contact: bool | None = None   # None: stop on contact iff the scene has no contact

    def __post_init__(self):
        if not (isinstance(self.cycles, int) and self.cycles >= 2):
            raise ValueError(f"cycles must be an integer >= 2, got {self.cycles!r}")
        for name in ("tol", "tol_impacting", "tol_end", "decay_ratio", "floor"):
            value = getattr(self, name)
            if not (value is None and name == "tol") and not 0 < value < 1:
                raise ValueError(f"{name} must lie in (0, 1){' or be None' * (name == 'tol')}, "
                                 f"got {value}")

    def settling_tol(self, rtol: float) -> float:
        """``tol``, or ``SETTLING_PER_RTOL · rtol`` clipped to [1e-8, 1e-2]."""
        if self.tol is not None:
            return self.tol
        return float(min(max(SETTLING_PER_RTOL * rtol, _TOL_RANGE[0]), _TOL_RANGE[1]))


@dataclass(frozen=True)
class Outcome:
    """Classification and measured quantities of one run (None where not applicable).

    Forces are totals over the beam ``∫ F_i dx`` normalized by ``F0 = m f1² H`` (m = 1
    the beam mass, f1 = w1/2π, H = H*/2). ``impacts_per_cycle``: separate contact
    intervals per settled cycle (chattering). ``mean_flow_reduction``:
    ``1 − mean(Q1+Q2)/(Q1+Q2)_steady`` over the measured cycles. ``convergence``: the
    remaining relative change (module docstring); ``settled``: below the settling
    tolerance (False for a cycle still approaching at the end of the run).
    """

    outcome: OutcomeKind
    period: float | None = None
    omega: float | None = None
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
    settled: bool = False

    @property
    def periodic(self) -> bool:
        """A cycle that repeats (settled or still approaching): ``period`` is its period,
        not the mean return time of an impacting_nonperiodic run."""
        return self.period is not None and self.outcome != "impacting_nonperiodic"

    def to_json(self) -> dict:
        return {k: (float(v) if isinstance(v, np.floating) else v) for k, v in self.__dict__.items()}


# -- criteria ---------------------------------------------------------------------------
def _remaining(d: np.ndarray, noise: float) -> float:
    """What a sequence with (relative) differences ``d`` has still to change (module
    docstring); once the last difference is below ``noise`` the sequence is at its
    noise level, ``noise``."""
    a = np.abs(d)
    if a[-1] < noise:
        return noise
    if np.all(d > 0) or np.all(d < 0):
        return _geometric_tail(a)
    return float(a.max())


def _geometric_tail(a: np.ndarray) -> float:
    """``a_last μ/(1 − μ)`` for strictly shrinking ``a`` (μ the largest ratio), else inf."""
    if not np.all(a[1:] < a[:-1]):
        return math.inf
    mu = float(np.max(a[1:] / a[:-1]))
    return float(a[-1] * mu / (1 - mu))


def _convergence(cyc: Cycles, m: int, tol: float | None) -> float | None:
    """Remaining relative change of period, amplitude and Poincaré point over the last m
    cycles (``tol``: the settling tolerance; below ``NOISE · tol`` a difference is noise),
    or with ``tol = None`` their largest change; None if too few cycles."""
    if cyc is None or cyc.periods.size < m + 1:
        return None
    p, a = cyc.periods[-m - 1:], cyc.amplitudes[-m - 1:]
    dp, da = np.diff(p) / p[-1], np.diff(a) / max(a[-1], 1e-300)
    dx = np.max(np.abs(np.diff(cyc.points[-m - 2:], axis=0)), axis=1) / cyc.size
    if tol is None:
        return float(max(np.abs(dp).max(), np.abs(da).max(), dx.max()))
    noise = NOISE * tol
    return float(max(_remaining(dp, noise), _remaining(da, noise), _distance_to_go(dx, noise)))


def _distance_to_go(dx: np.ndarray, noise: float) -> float:
    """Remaining distance of Poincaré points whose successive distances are ``dx``: the
    geometric tail if they shrink, else the largest (``noise`` once at the noise level)."""
    if dx[-1] < noise:
        return noise
    return _geometric_tail(dx) if np.all(dx[1:] < dx[:-1]) else float(dx.max())


def _swings(cyc: Cycles, m: int, tol: float) -> tuple[Cycles, float] | None:
    """``(cycles, change)`` of the fewest tip swings k <= :data:`MAX_SWINGS` per cycle
    whose cycles (every k-th return, the last among them) change by less than ``tol``,
    or None."""
    for k in range(2, MAX_SWINGS + 1):
        every = np.arange(cyc.times.size - 1, -1, -k)[::-1]
        if every.size < m + 2:
            return None
        times = cyc.times[every]
        amplitudes = [cyc.amplitudes[a:b].max() for a, b in zip(every[:-1], every[1:])]
        grouped = Cycles(cyc.index[every], times, cyc.points[every], np.diff(times),
                         np.array(amplitudes), cyc.size)
        change = _convergence(grouped, m, None)
        if change < tol:
            return grouped, change
    return None


def _decayed(cyc: Cycles | None, crit: Criteria, X, x_ref, gap, first_amplitude) -> bool:
    if np.max(np.abs(X[-max(len(X) // 8, 1):] - x_ref)) < crit.floor * gap:
        return True
    if cyc is None or cyc.amplitudes.size < crit.cycles + 1:
        return False
    last = cyc.amplitudes[-crit.cycles - 1:]
    return bool(np.all(np.diff(last) < 0) and last[-1] < crit.decay_ratio * first_amplitude)


def _first_contact(t, X, model, p, start: int = 0):
    """(sample index, time, position) of the first contact (a gap at the ``eps`` of the
    parameters ``p``) at or after sample ``start``, or None.

    The samples give the interval; the time is then located inside it (event location):
    the root of ``min_x h(x, t) − eps`` on the cubic through the samples ``k−3 .. k``
    (Lagrange interpolation of the state, error O(dt_out⁴)), by Brent's method.
    """
    touch = penetration(model, X[start:], p).depth >= 0
    if not touch.any():
        return None
    k = start + int(np.argmax(touch))
    if k == 0:
        return 0, float(t[0]), _deepest_at(model, X[0], p)
    state = scipy.interpolate.BarycentricInterpolator(t[max(0, k - 3):k + 1], X[max(0, k - 3):k + 1])
    tc = scipy.optimize.brentq(lambda s: penetration(model, state(s), p).depth[0], t[k - 1], t[k],
                               xtol=1e-14 * max(1.0, abs(t[k])))
    return k, float(tc), _deepest_at(model, state(tc), p)


def _deepest_at(model, x, p) -> float:
    """Where the gap of the state ``x`` is narrowest (:func:`fsicas.model.patch.penetration`)."""
    return float(penetration(model, x, p).position[0])


class Monitor:
    """Incremental classification of a growing run (module docstring); the stop rule of
    :func:`fsicas.timedomain.integrators.simulate`, called with all samples so far.

    ``rtol``: the integrator's (the default settling tolerance follows it);
    ``pressure(t)``: the pressure drop of a scheduled run (None: the steady state's);
    ``contact_only``: stop only at contact (contact-free runs kept to t_end). ``outcome``
    holds the outcome that stopped the run.
    """

    def __init__(self, model: Model, steady, criteria: Criteria = Criteria(), *,
                 rtol: float = 1e-8, pressure: Callable | None = None, contact_only: bool = False):
        self.model, self.steady, self.criteria = model, steady, criteria
        self.tol = criteria.settling_tol(rtol)
        self.pressure, self.contact_only = pressure, contact_only
        self.outcome: Outcome | None = None
        self._scanned, self._contact = 0, None
        self._first_amplitude, self._period = None, None

    def __call__(self, t, X) -> OutcomeKind | None:
        if self.contact_only:   # run to t_end, but a contact-free run still ends at contact
            return "contact" if self._contact_in(t, X) is not None else None
        self.outcome = self.classify(t, X, final=False)
        return None if self.outcome is None else self.outcome.outcome

    def classify(self, t, X, final: bool, closed: bool = False,
                 failed: bool = False) -> Outcome | None:
        """The outcome of the samples so far (None while undecided and not ``final``);
        ``closed``: the run ended on a closed gap after its last sample; ``failed``: the
        run failed (then an impacting run that did not settle is "contact", not
        "impacting_nonperiodic")."""
        model, crit = self.model, self.criteria
        contact = self._contact_in(t, X)
        if contact is None and closed:
            # the gap went from > eps to 0 between the last sample and the solver failure
            contact = len(t) - 1, float(t[-1]), _deepest_at(model, X[-1], self.steady.p)
        stop_on_contact = (not self.steady.scene.contact) if crit.stop_on_contact is None \
            else crit.stop_on_contact
        info = {}
        if contact is not None:
            info = dict(contact=True, first_contact_time=contact[1],
                        first_contact_position=contact[2], contact_positions=[contact[2]])
            if stop_on_contact:
                return Outcome("contact", **info)
        start = self._window(t)
        cyc = self._cycles(t, X, start)
        if cyc is None and start > 0:
            start, cyc = 0, self._cycles(t, X, 0)
        impacting = contact is not None
        tol = crit.tol_impacting if impacting else self.tol
        change = _convergence(cyc, crit.cycles, None if impacting else tol)
        if _decayed(cyc, crit, X[start:], self.steady.x, model.scene.hstar / 2,
                    self._first_amplitude):
            return Outcome("decay", **info)
        kind = "impacting_lco" if impacting else "lco"
        if change is not None and change < tol:
            return self._measure(kind, t[start:], X[start:], cyc, change, info, settled=True)
        if not final:
            return None
        return self._at_end(t[start:], X[start:], cyc, change, info, failed)

    def _at_end(self, t, X, cyc, change, info, failed: bool) -> Outcome:
        """The outcome at the end of a run that did not settle (module docstring): an
        impacting cycle of several swings, an impacting_nonperiodic run, a contact-free
        cycle still approaching, or contact / unsettled."""
        impacting, crit = bool(info), self.criteria
        if impacting and change is not None:
            swings = _swings(cyc, crit.cycles, crit.tol_impacting)
            if swings is not None:
                return self._measure("impacting_lco", t, X, *swings, info, settled=True)
            if not failed:
                return self._measure("impacting_nonperiodic", t, X, cyc, change, info,
                                     settled=False)
        if not impacting and change is not None and change < crit.tol_end:
            return self._measure("lco", t, X, cyc, change, info, settled=False)
        return Outcome("contact", **info) if impacting else Outcome("unsettled", convergence=change)

    def _contact_in(self, t, X):
        """The first contact (:func:`_first_contact`), scanning only samples not seen."""
        if self._contact is None and len(t) > self._scanned:
            self._contact = _first_contact(t, X, self.model, self.steady.p, self._scanned)
            self._scanned = len(t)
        return self._contact

    def _window(self, t) -> int:
        """First sample of the last ``1.5 (cycles + 4)`` periods, after a contact
        ``1.5 (MAX_SWINGS cycles + 4)`` (0 before a period is known)."""
        if self._period is None:
            return 0
        swings = 1 if self._contact is None else MAX_SWINGS
        span = 1.5 * (swings * self.criteria.cycles + 4) * self._period
        return int(np.searchsorted(t, t[-1] - span))

    def _cycles(self, t, X, start, y_ref=None) -> Cycles | None:
        cyc = cycles(t[start:], X[start:], self.model,
                      lambda idx: self._xdot(t[start:], X[start:], idx), y_ref)
        if cyc is not None:
            self._period = float(np.max(cyc.periods[-self.criteria.cycles:]))
            if self._first_amplitude is None:
                self._first_amplitude = float(cyc.amplitudes[0])
        return cyc

    def _xdot(self, t, X, idx) -> np.ndarray:
        """``xdot`` at the samples ``idx`` (rows), at the run's parameters."""
        dp = None if self.pressure is None else self.pressure(t[idx])
        return xdot_rows(self.model, X[idx], self.steady.p, dp)

    def _measure(self, kind, t, X, cyc, change, info, settled) -> Outcome:
        m = self.criteria.cycles
        a, b = cyc.index[-m - 1], cyc.index[-1]
        T = float((cyc.times[-1] - cyc.times[-m - 1]) / m)
        Qs = self.steady.x[-2:].sum()
        flow = X[a:b, -2:].sum(axis=1)
        reduction = 1.0 - float(np.trapezoid(flow, t[a:b]) / (t[b - 1] - t[a]) / Qs)
        out = dict(period=T, omega=2 * np.pi / T, tip_amplitude=float(cyc.amplitudes[-1]),
                   convergence=change, cycles=int(cyc.periods.size), mean_flow_reduction=reduction,
                   t_settled=float(cyc.times[-1]), settled=settled)
        if info.get("contact"):
            out.update(_impacts(X[a:b], self.model, self.steady.p, m))
        return Outcome(kind, **{**info, **out})


def _impacts(X, model, p, m):
    """Impact force, contact positions (where each contact interval penetrates deepest)
    and chattering count over the measured cycles, under the contact law of ``p``
    (:func:`fsicas.model.patch.penetration`)."""
    patch = penetration(model, X, p)
    spans = contact_intervals(patch.load)
    positions = sorted({round(float(patch.position[a + np.argmax(patch.depth[a:b + 1])]), 3)
                        for a, b in spans})
    return dict(max_impact_force=float(patch.load.max() / reference_force(model)),
                impacts_per_cycle=len(spans) / m, contact_positions=positions)


def classify(traj: Trajectory, steady, criteria: Criteria = Criteria()) -> Outcome:
    """Classify a whole trajectory and measure its cycle (module docstring)."""
    monitor = Monitor(traj.model, steady, criteria, rtol=traj.settings.rtol,
                      pressure=lambda s: np.interp(s, traj.t, traj.pressure_drop))
    return monitor.classify(traj.t, traj.x, final=True, closed=traj.gap_closed,
                            failed=traj.failed)
