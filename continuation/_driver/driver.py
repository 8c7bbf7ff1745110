"""``continuation(problem, algorithm, settings, *, events, record, stop) -> Branch``:
a thin loop over the PALC step iterator that monitors points, locates special
points (built-in and user events) between consecutive ones, records
user columns, stops on terminal events or a ``stop`` predicate, restarts
problems that ask for it and collects everything into a :class:`Branch`.
"""

from __future__ import annotations

import contextvars
import time
from contextlib import contextmanager
from dataclasses import replace
from typing import Callable, Mapping, NamedTuple

import numpy as np
from tqdm import tqdm

from .branch import Branch, SpecialPoint
from .hooks import Event, Hooks, check_hooks, crossed, scalars, stopped
from .locate import Located, locate
from .palc import ContinuationIterator, Step, correct, tangent
from .problem import Problem
from .recorder import Recorder
from .settings import PALC, ContinuationSettings
from .._linalg.threads import single_threaded


#: The observers of the runs in the current context (:func:`observing`).
_OBSERVERS: contextvars.ContextVar = contextvars.ContextVar("continuation_observers", default=())


@contextmanager
def observing(on_branch: Callable | None = None, progress: bool | None = None):
    """Within the block (this thread or task only), every :func:`continuation` run shows
    its progress bar when ``progress`` is True, never when False (None: as its settings
    say), and hands its finished Branch to ``on_branch``. Nested blocks all observe; the
    innermost ``progress`` that is not None wins."""
    token = _OBSERVERS.set(_OBSERVERS.get() + ((on_branch, progress),))
    try:
        yield
    finally:
        _OBSERVERS.reset(token)


def _observed_progress(settings: ContinuationSettings) -> bool:
    wanted = [p for _, p in _OBSERVERS.get() if p is not None]
    return wanted[-1] if wanted else settings.progress


def continuation(problem: Problem, algorithm: PALC | None = None,
                 settings: ContinuationSettings | None = None, *, events=(),
                 record: Callable | None = None, stop: Callable | None = None) -> Branch:
    """Continue ``problem`` with ``algorithm`` (default PALC) and ``settings``.

    events : user :class:`Event` objects, evaluated at every accepted point and located
        between points (also with ``settings.detect = False``, which only turns
        off the problem's own test functions).
    record : ``record(problem, X) -> {name: float | array}``, called once per
        branch point (also after a restart, with the restarted problem); its
        values become ``Branch.columns`` next to the problem's own columns.
    stop : ``stop(problem, X) -> bool | str`` checked after each branch point;
        a true value (or a non-empty message) ends the run with status 'stopped'.

    Never raises for numerical non-convergence: the returned branch carries
    ``status`` (a :data:`Status`: 'max_steps', 'bound', 'failed', 'event' or
    'stopped') and a ``message``. Runs with one BLAS thread (``_linalg.threads``).
    """
    algorithm = PALC() if algorithm is None else algorithm
    settings = ContinuationSettings() if settings is None else settings
    _check(problem, algorithm, settings)
    hooks = check_hooks(events, record, stop)
    t0 = time.perf_counter()
    with single_threaded(), tqdm(total=settings.max_steps + 1, disable=not _observed_progress(settings),
                                 desc=f"{problem.kind} continuation", leave=False) as bar:
        run = _Run(Recorder(problem), hooks, settings, bar)
        it = _run_segments(problem, algorithm, settings, run)
    stats = {**run.rec.stats, "time_total": time.perf_counter() - t0}
    if run.halt is not None:
        branch = run.rec.branch(*run.halt, {}, stats)
    else:
        message = f"reached max_steps = {settings.max_steps}" if it.status == "max_steps" \
            else it.message  # a restarted segment only knows its remaining budget
        branch = run.rec.branch(it.status, message, it.failure, stats)
    for on_branch, _ in _OBSERVERS.get():
        if on_branch is not None:
            on_branch(branch)
    return branch


def _run_segments(problem, algorithm, settings, run):
    """Iterate PALC; when the problem asks for a restart (reference vectors of
    an augmented system drifted, a re-mesh), continue with the rebuilt problem
    from the same point, oriented by the previous tangent. Returns the last
    iterator."""
    tau_ref, origin, seg_settings = None, None, settings
    while True:
        it = ContinuationIterator(problem, algorithm, seg_settings, tau_ref, origin)
        step, restart = _iterate(problem, it, tau_ref is not None, settings, run)
        _merge(run.rec.stats, it.stats)
        if restart is None:
            return it
        problem, X_new, *carry = restart
        tau_ref = np.zeros(X_new.size)
        frame = problem.frame(X_new)
        tau_ref[frame] = step.tau[frame]
        origin = Step(X_new, carry[0](step.tau), 0.0, 0, step.residual) if carry else None
        remaining = settings.max_steps - (len(run.rec.X) - 1)
        run.rec.stats["restarts"] = run.rec.stats.get("restarts", 0) + 1
        seg_settings = replace(settings, max_steps=remaining,
                               ds=min(max(it.ds, settings.ds_min), settings.ds_max))


def _iterate(problem, it, restarted, settings, run):
    """One segment: ``(last step, restart or None)``; stops early on ``run.halt``."""
    step = None
    for step in it:
        if restarted and step.ds == 0.0:  # restart point, already recorded
            info = run.prev[1] if it.origin is not None else \
                problem.monitor(step.X, step.tau, step.lu, settings)
            run.prev = (step, info, run.prev[2])
            continue
        info = problem.monitor(step.X, step.tau, step.lu, settings)
        before = run.prev[1] if run.prev is not None else None
        run.point(problem, step, info)
        if run.halt is not None:
            return step, None
        if before is not None:
            limit = problem.step_limit(before, info, step.ds, settings)
            if limit is not None:               # the next step only, never below 10 ds_min
                it.cap = max(limit, 10 * settings.ds_min)
        done = len(run.rec.X) - 1
        restart = problem.restart(step.X) if done < settings.max_steps else None
        if restart is not None:
            return step, restart
    return step, None


class _Found(NamedTuple):
    """A special point found between two branch points, at arclength ``s``."""

    s: float
    point: SpecialPoint
    X: np.ndarray
    event: Event | None = None
    located: Located | None = None


class _Run:
    """One run: the recorder, the user hooks, the previous point
    ``(step, info, event values)`` and ``halt = (status, message)`` once ended."""

    def __init__(self, rec, hooks: Hooks, settings, bar):
        self.rec, self.hooks, self.settings, self.bar = rec, hooks, settings, bar
        self.prev, self.halt = None, None
        self._cache = (None, {})

    def point(self, problem, step, info) -> None:
        """Record an accepted point and the special points since the previous one;
        set ``halt`` when a terminal event or the ``stop`` predicate ends the run."""
        cur = (step, info, self.event_values(problem, step.X))
        found = self.specials(problem, cur)
        hit = min((f for f in found if f.event is not None and f.event.terminal),
                  key=lambda f: f.s, default=None)
        if hit is not None and hit.located.bracketed:
            self.rec.special += [f.point for f in found if f.s <= hit.s]
            self.add(problem, self.located_step(problem, hit), hit.event)
        else:
            self.rec.special += [f.point for f in found]
            self.add(problem, cur, hit.event if hit is not None else None)
        self.prev = cur
        stops = [f.point.kind for f in found if f.point.kind in self.settings.stop_at]
        if stops and self.halt is None:
            self.halt = ("stopped", f"stopped at the first {stops[0]!r} (before point "
                                    f"{len(self.rec.X) - 1})")

    def add(self, problem, cur, terminal: Event | None) -> None:
        """Append ``cur`` to the branch; then apply ``terminal`` or ``stop``."""
        step, info, values = cur
        own, user = problem.columns(step.X), self.record(problem, step.X)
        if not self.rec.X and set(own) & set(user):
            raise ValueError(f"record returned columns {sorted(set(own) & set(user))} that "
                             "the problem already records; rename them")
        self.rec.add(step, info, {**own, **user}, values)
        self.bar.update()
        index = len(self.rec.X) - 1
        if terminal is not None:
            where = ", ".join(f"{k} = {v:.10g}" for k, v in zip(
                problem.free, step.X[len(step.X) - len(problem.free):]))
            self.halt = ("event", f"terminal event {terminal.name!r} at point {index} "
                                  f"({where})")
        elif self.hooks.stop is not None:
            self.halt = stopped(self.hooks.stop(problem, step.X), index)

    def event_values(self, problem, X) -> dict:
        """``{name: function(problem, X)}`` of the user events."""
        t0 = time.perf_counter()
        values = {e.name: float(e.function(problem, X)) for e in self.hooks.events}
        _add_time(self.rec.stats, "time_events", t0)
        return values

    def record(self, problem, X) -> dict:
        """The ``record`` callback's columns at ``X`` (kept for the last X)."""
        if self.hooks.record is None:
            return {}
        if self._cache[0] is not None and np.array_equal(self._cache[0], X):
            return self._cache[1]
        t0 = time.perf_counter()
        out = self.hooks.record(problem, X)
        if not isinstance(out, Mapping):
            raise ValueError(f"record must return a mapping {{name: value}}, got "
                             f"{type(out).__name__}")
        _add_time(self.rec.stats, "time_record", t0)
        self._cache = (np.array(X), dict(out))
        return self._cache[1]

    def specials(self, problem, cur) -> list:
        """Built-in (when ``settings.detect``) and user special points between
        ``prev`` and ``cur``, sorted by arclength."""
        if self.prev is None:
            return []
        found = _detect(problem, self.prev[:2], cur[:2], self.settings, self.rec)
        found += [self.user_special(problem, e, cur) for e in self.hooks.events
                  if crossed(self.prev[2][e.name], cur[2][e.name])]
        found = [f for f in found if f is not None]
        for f in found:
            record = self.record(problem, f.X)
            f.point.data.update({k: v for k, v in scalars(record).items()
                                 if k not in f.point.data})
            f.point.record.update(record)
        return sorted(found, key=lambda f: f.s)

    def user_special(self, problem, event: Event, cur) -> _Found:
        """Locate the zero of ``event`` between ``prev`` and ``cur``."""
        t0 = time.perf_counter()
        f = lambda X, tau, lu: float(event.function(problem, X))
        loc = locate(problem, event.name, self.prev[:2], cur[:2], self.settings, f)
        _add_time(self.rec.stats, "time_location", t0)
        self.rec.stats["located"] = self.rec.stats.get("located", 0) + 1
        status = "converged" if loc.converged else "guess"
        data = {"bracket": float(loc.bracket), "s": loc.s, "value": loc.value}
        point = SpecialPoint(event.name, len(self.rec.X), problem.state(loc.X),
                             problem.par_dict(loc.X), status, float(loc.bracket), data,
                             loc.message, unknowns=np.array(loc.X),
                             tangent=np.array(self.prev[0].tau))
        return _Found(loc.s, point, np.array(loc.X), event, loc)

    def located_step(self, problem, hit: _Found):
        """``(step, info, event values)`` of a located terminal event as a branch
        point (accepted by the problem, monitored like the others)."""
        loc, prev = hit.located, self.prev[0]
        tau, lu = tangent(problem, loc.X, prev.tau)
        tau = loc.tau if tau is None else tau
        problem.accept(loc.X)
        step = Step(loc.X, tau, loc.s, loc.iterations, loc.residual, lu)
        info = problem.monitor(loc.X, tau, lu, self.settings)
        return step, info, self.event_values(problem, loc.X)


def _add_time(stats, key, t0) -> None:
    stats[key] = stats.get(key, 0.0) + time.perf_counter() - t0


#: Halvings of one step at most while separating several crossings in it (:func:`_split`).
MAX_SPLITS = 8


def _detect(problem, prev, cur, settings, rec) -> list:
    """Built-in special points between ``prev`` and ``cur`` (``_Found`` or None)."""
    if not settings.detect:
        return []
    return [found for kind in problem.events(prev[1], cur[1])
            for found in _split(problem, kind, prev, cur, settings, rec, MAX_SPLITS)]


def _split(problem, kind, a, b, settings, rec, splits: int, offset: float = 0.0) -> list:
    """The points of ``kind`` between ``a`` and ``b``: one located point when the counts
    say one (:meth:`Problem.crossings`); else the step is halved at its arclength middle
    (a corrected and monitored point), the counts taken again, and each half searched,
    so two Hopf pairs crossing in one step give two located points. ``offset``: the
    arclength of ``a`` from the step's start (the found points' ``s``)."""
    if splits == 0 or problem.crossings(kind, a[1], b[1]) <= 1:
        found = _special(problem, kind, a, b, settings, len(rec.X), rec.stats)
        return [found if found is None else found._replace(s=offset + found.s)]
    sa = a[0]
    half = 0.5 * float(sa.tau @ (b[0].X - sa.X))
    res = correct(problem, sa.X + half * sa.tau, sa.tau, settings.newton)
    tau, lu = tangent(problem, res.X, sa.tau) if res.converged else (None, None)
    if tau is None:
        found = _special(problem, kind, a, b, settings, len(rec.X), rec.stats)
        return [found if found is None else found._replace(s=offset + found.s)]
    rec.stats["split_steps"] = rec.stats.get("split_steps", 0) + 1
    mid = (Step(res.X, tau, half, res.iterations, res.residual, lu),
           problem.monitor(res.X, tau, lu, settings))
    return [found for lo, hi, at in ((a, mid, offset), (mid, b, offset + half))
            if kind in problem.events(lo[1], hi[1])
            for found in _split(problem, kind, lo, hi, settings, rec, splits - 1, at)]


def _merge(stats, it_stats):
    for key, value in it_stats.items():
        stats[key] = stats.get(key, 0) + value


def _check(problem, algorithm, settings):
    if not isinstance(problem, Problem):
        raise ValueError(f"problem must be a continuation Problem, got "
                         f"{type(problem).__name__}")
    if not isinstance(algorithm, PALC):
        raise ValueError(f"algorithm must be PALC, got {type(algorithm).__name__}")
    if not isinstance(settings, ContinuationSettings):
        raise ValueError(f"settings must be ContinuationSettings, got "
                         f"{type(settings).__name__}")
    unknown = set(settings.bounds) - set(problem.vf.par_names)
    if unknown:
        raise ValueError(f"settings.bounds names unknown parameters {sorted(unknown)}")


def _special(problem, kind, a, b, settings, index, stats) -> _Found | None:
    """Locate and describe the built-in ``kind`` between ``a`` and ``b``
    (None when rejected)."""
    t0 = time.perf_counter()
    loc = locate(problem, kind, a, b, settings)
    if not loc.bracketed and kind in problem.verified_kinds:
        stats["rejected_events"] = stats.get("rejected_events", 0) + 1
        return None
    desc = problem.describe(kind, loc.X, loc.tau, settings)
    stats["time_location"] = stats.get("time_location", 0.0) + time.perf_counter() - t0
    if desc.status == "rejected":
        stats["rejected_events"] = stats.get("rejected_events", 0) + 1
        return None
    stats["located"] = stats.get("located", 0) + 1
    status = desc.status if loc.converged else "guess"
    data = {"bracket": loc.bracket, **desc.data}
    message = "; ".join(m for m in (loc.message, desc.message) if m)
    precision = desc.precision if desc.precision > 0 else loc.bracket
    point = SpecialPoint(kind, index, problem.state(desc.X), problem.par_dict(desc.X),
                         status, float(precision), data, message, unknowns=np.array(desc.X),
                         tangent=np.array(a[0].tau))
    return _Found(loc.s, point, np.array(desc.X))
