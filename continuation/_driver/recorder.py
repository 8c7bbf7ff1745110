"""The record of a continuation run: its monitored points, collected into a Branch."""

from __future__ import annotations

import numpy as np

from .branch import Branch


def check_names(info, values) -> None:
    """User event names must not shadow the problem's test-function columns."""
    clash = sorted(set(values) & (set(info.tests) | set(info.counts)))
    if clash:
        raise ValueError(f"events {clash} have the names of test functions of the problem; "
                         "rename them")


class Recorder:
    """Accumulates monitored points; builds the Branch at the end."""

    def __init__(self, problem):
        self.problem = problem
        self.X, self.steps, self.infos, self.special, self.cols = [], [], [], [], []
        self.values, self.stats = [], {}

    def add(self, step, info, columns, values):
        """Record a point; ``columns`` are taken now, from the problem that
        produced it (a restarted cycle problem has a different mesh); ``values``
        are the user events' values."""
        if not self.X:
            check_names(info, values)
        self.cols.append(columns)
        self.values.append(values)
        self.X.append(step.X)
        self.steps.append((step.ds, step.iterations, step.residual))   # not its factors
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
        tests.update({k: np.array([v[k] for v in self.values])
                      for k in (self.values[0] if self.values else {})})
        cols = self.cols
        columns = {k: np.array([c[k] for c in cols]) for k in (cols[0] if cols else {})}
        return Branch(prob.kind, prob.vf.par_names, prob.free,
                      np.array([prob.state(x) for x in self.X]).reshape(len(X), prob.vf.n),
                      np.array([prob.params(x) for x in self.X]).reshape(
                          len(X), len(prob.vf.par_names)),
                      s, np.array([st[0] for st in self.steps]),
                      np.array([st[1] for st in self.steps], dtype=int),
                      np.array([st[2] for st in self.steps]),
                      [i.eigenvalues for i in self.infos], tests, columns,
                      self.special, status, message, failure, stats)
