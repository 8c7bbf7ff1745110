"""``continuation(problem, algorithm, settings) -> Branch``: a thin loop over
the PALC step iterator that monitors points, locates special points between
consecutive ones and collects everything into a :class:`Branch`.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from tqdm.auto import tqdm

from ._branch import Branch, SpecialPoint
from ._locate import locate
from ._palc import ContinuationIterator
from ._problem import Problem
from ._settings import PALC, ContinuationSettings


def continuation(problem: Problem, algorithm: PALC | None = None,
                 settings: ContinuationSettings | None = None) -> Branch:
    """Continue ``problem`` with ``algorithm`` (default PALC) and ``settings``.

    Never raises for numerical non-convergence: the returned branch carries
    ``status`` ('max_steps', 'bound' or 'failed') and a ``message``.
    """
    algorithm = PALC() if algorithm is None else algorithm
    settings = ContinuationSettings() if settings is None else settings
    _check(problem, algorithm, settings)
    t0 = time.perf_counter()
    rec = _Recorder(problem)
    with tqdm(total=settings.max_steps + 1, disable=not settings.progress,
              desc=f"{problem.kind} continuation", leave=False) as bar:
        it = _run_segments(problem, algorithm, settings, rec, bar)
    stats = {**rec.stats, "time_total": time.perf_counter() - t0}
    message = f"reached max_steps = {settings.max_steps}" if it.status == "max_steps" \
        else it.message  # a restarted segment only knows its remaining budget
    return rec.branch(it.status, message, it.failure, stats)


def _run_segments(problem, algorithm, settings, rec, bar):
    """Iterate PALC; when the problem asks for a restart (reference vectors of
    an augmented system drifted), continue with the rebuilt problem from the
    same point, oriented by the previous tangent. Returns the last iterator."""
    tau_ref, prev, seg_settings = None, None, settings
    while True:
        it = ContinuationIterator(problem, algorithm, seg_settings, tau_ref)
        restart = None
        for step in it:
            info = problem.monitor(step.X, step.tau, step.lu, settings)
            if tau_ref is not None and step.ds == 0.0:  # restart point, already recorded
                prev = (step, info)
                continue
            _detect(problem, prev, (step, info), settings, rec)
            rec.add(step, info, problem.columns(step.X))
            prev = (step, info)
            bar.update()
            done = len(rec.X) - 1
            restart = problem.restart(step.X) if done < settings.max_steps else None
            if restart is not None:
                break
        _merge(rec.stats, it.stats)
        if restart is None:
            return it
        problem, X_new = restart
        tau_ref = np.zeros(X_new.size)
        frame = problem.frame(X_new)
        tau_ref[frame] = step.tau[frame]
        remaining = settings.max_steps - (len(rec.X) - 1)
        rec.stats["restarts"] = rec.stats.get("restarts", 0) + 1
        seg_settings = replace(settings, max_steps=remaining,
                               ds=min(max(it.ds, settings.ds_min), settings.ds_max))


def _detect(problem, prev, cur, settings, rec):
    if prev is None or not settings.detect:
        return
    for kind in problem.events(prev[1], cur[1]):
        found = _special(problem, kind, prev, cur, settings, len(rec.X), rec.stats)
        if found is not None:
            rec.special.append(found)


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


def _special(problem, kind, a, b, settings, index, stats) -> SpecialPoint:
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
    return SpecialPoint(kind, index, problem.state(desc.X), problem.par_dict(desc.X),
                        status, float(precision), data, message)


class _Recorder:
    """Accumulates monitored points; builds the Branch at the end."""

    def __init__(self, problem):
        self.problem = problem
        self.X, self.steps, self.infos, self.special, self.cols = [], [], [], [], []
        self.stats = {}

    def add(self, step, info, columns):
        """Record a point; ``columns`` are taken now, from the problem that
        produced it (a restarted cycle problem has a different mesh)."""
        self.cols.append(columns)
        self.X.append(step.X)
        self.steps.append(step)
        self.infos.append(info)

    def branch(self, status, message, failure, stats) -> Branch:
        prob = self.problem
        X = np.array(self.X).reshape(len(self.X), prob.system.n_unknowns)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(X, axis=0), axis=1))]) \
            if len(X) else np.zeros(0)
        tests = {k: np.array([i.tests.get(k, 0.0) for i in self.infos])
                 for k in (self.infos[0].tests if self.infos else {})}
        tests.update({k: np.array([i.counts.get(k, 0) for i in self.infos], dtype=float)
                      for k in (self.infos[0].counts if self.infos else {})})
        cols = self.cols
        columns = {k: np.array([c[k] for c in cols]) for k in (cols[0] if cols else {})}
        return Branch(prob.kind, prob.vf.par_names, prob.free,
                      np.array([prob.state(x) for x in self.X]).reshape(len(X), prob.vf.n),
                      np.array([prob.params(x) for x in self.X]).reshape(
                          len(X), len(prob.vf.par_names)),
                      s, np.array([st.ds for st in self.steps]),
                      np.array([st.iterations for st in self.steps], dtype=int),
                      np.array([st.residual for st in self.steps]),
                      [i.eigenvalues for i in self.infos], tests, columns,
                      self.special, status, message, failure, stats)
