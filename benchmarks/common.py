"""Helpers shared by the benchmark scripts (a module, not a script: it runs nothing).

* the Brusselator chain of ``bench_cycles.py`` (``brusselator_chain``, ``params``,
  ``hopf_b``), also continued by ``bench_linear_solver.py`` and ``bench_speedup.py``;
* ``flutter_start``: the flutter model's equilibrium problem and first Hopf point;
* ``machine``: the core count and load average to print beside a table;
* ``Baseline``, ``run_child``, ``compare``: side-by-side timing of the working tree
  against another git revision in one run (``git archive`` of the revision into a
  temporary folder; the same child script run on both trees in turn, A B A B ..., each a
  fresh process whose ``sys.path`` starts with its tree; the median time of each, the
  median of the pairwise ratios old / new, and the largest difference of the values
  both return). The child prints one JSON object ``{"time": s, "value": [...]}``.

A script imports it as ``from common import ...`` (its own folder is on ``sys.path``
when it runs; scripts the tests load by path insert it first).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import tempfile
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path

import casadi as ca
import numpy as np

A, D1, D2 = 2.0, 1.0, 1.0


def brusselator_chain(n: int) -> ca.Function:
    """F(x, p), x = (u_1, v_1, ..., u_N, v_N), p = (A, B, d1, d2)."""
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", 4)
    a, b, d1, d2 = p[0], p[1], p[2], p[3]
    u, v = x[0::2], x[1::2]
    N = n // 2
    ul = ca.vertcat(a, u[:-1]) if N > 1 else a
    ur = ca.vertcat(u[1:], a) if N > 1 else a
    vl = ca.vertcat(b / a, v[:-1]) if N > 1 else b / a
    vr = ca.vertcat(v[1:], b / a) if N > 1 else b / a
    fu = a - (b + 1) * u + u ** 2 * v + d1 * (ul - 2 * u + ur)
    fv = b * u - u ** 2 * v + d2 * (vl - 2 * v + vr)
    return ca.Function("F", [x, p], [ca.vec(ca.horzcat(fu, fv).T)])


def params(B):
    return {"A": A, "B": float(B), "d1": D1, "d2": D2}


def hopf_b(n: int) -> float:
    return 1 + A ** 2 + (D1 + D2) * 2 * (1 - np.cos(np.pi / (n // 2 + 1)))



def flutter_start(modes: int):
    """``(equilibrium problem, Hopf point)`` of the flutter model at M* = 1."""
    import fsicas
    from fsicas.linear.hopf import critical_velocity, flutter_problem
    scene = fsicas.Scene(modes=modes)
    model = fsicas.build_model(scene)
    hopf = critical_velocity(scene, model, ustar_max=20.0)
    return flutter_problem(scene, model, min(0.2, hopf.ustar / 2)), hopf


def machine() -> str:
    """``"2 cores, load average 1.2 / 1.0 / 0.9"``."""
    load = os.getloadavg()
    return f"{os.cpu_count()} cores, load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}"


ROOT = Path(__file__).resolve().parents[1]


class Baseline:
    """The source tree of ``rev`` in a temporary folder (removed on exit)."""

    def __init__(self, rev: str):
        self.rev = rev
        self._tmp = tempfile.TemporaryDirectory(prefix="fsicas-baseline-")
        archive = subprocess.run(["git", "archive", rev], cwd=ROOT, check=True,
                                 capture_output=True).stdout
        with tarfile.open(fileobj=BytesIO(archive)) as tar:
            tar.extractall(self._tmp.name, filter="data")
        self.path = Path(self._tmp.name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._tmp.cleanup()


@dataclass(frozen=True)
class Comparison:
    """Median times (s) of the old and new tree, median pairwise speed-up, max |Δvalue|."""

    old: float
    new: float
    speedup: float
    difference: float


def run_child(tree: Path, script: str, args) -> dict:
    """Run ``script`` with ``sys.path[0] = tree``; its JSON output."""
    code = f"import sys; sys.path.insert(0, {str(tree)!r})\n" + script
    out = subprocess.run([sys.executable, "-c", code, *map(str, args)], check=True,
                         capture_output=True, text=True, cwd=tree).stdout
    return json.loads(out.strip().splitlines()[-1])


def compare(old_tree: Path, script: str, args, repeats: int = 3) -> Comparison:
    """Interleaved runs of ``script`` on ``old_tree`` and on the working tree."""
    old, new = [], []
    for _ in range(repeats):
        old.append(run_child(old_tree, script, args))
        new.append(run_child(ROOT, script, args))
    t_old = np.array([r["time"] for r in old])
    t_new = np.array([r["time"] for r in new])
    diff = max(float(np.max(np.abs(np.subtract(a["value"], b["value"]))))
               for a, b in zip(old, new))
    return Comparison(float(np.median(t_old)), float(np.median(t_new)),
                      float(np.median(t_old / t_new)), diff)
