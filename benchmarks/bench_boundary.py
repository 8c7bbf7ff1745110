"""The Fig. 2 stability boundary (41 log-spaced M* in [0.01, 100]) of the working tree
against an earlier revision, side by side in one run.

Each repeat runs the boundary once per tree in fresh processes, alternating (old, new,
old, new, ...; ``baseline.run_child``), on a model built beforehand. Printed per N: the
median times, the median of the pairwise ratios old/new (the speed-up, robust to a
machine whose load drifts), the largest relative difference of U*_c over the 41 M*
between the trees, the switches of each (count, largest relative difference of their
M*), and where the time went in each tree: CasADi evaluations (residuals, Jacobians and
the Hopf systems' Jacobians, normal forms), dense eigen-solves, sparse LU (SuperLU
factorizations and solves) and the rest (Python, NumPy, sparse assembly). Both trees
run with one BLAS thread (``OPENBLAS_NUM_THREADS=1``, as the library does inside its
runs since later revisions; on the shared 2-core machine two BLAS threads only compete).

    python benchmarks/bench_boundary.py [--baseline d4eeda9] [--modes 10 40] [--repeats 3]
"""
from __future__ import annotations

import argparse
import os
import platform

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # inherited by the child processes

import numpy as np  # noqa: E402

from baseline import ROOT, Baseline, run_child  # noqa: E402

CHILD = """
import json, sys, time, collections
import numpy as np
import scipy.linalg, scipy.sparse.linalg
import fsicas
from continuation._casadi import symbolic as _symbolic
from continuation._driver import newton as _newton
spent = collections.Counter()

def timed(owner, name, key):
    fun = getattr(owner, name)
    def wrapper(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return fun(*args, **kwargs)
        finally:
            spent[key] += time.perf_counter() - t0
    setattr(owner, name, wrapper)

timed(_symbolic.BufferedFunction, "__call__", "casadi")
timed(scipy.linalg, "eig", "eigen")
timed(scipy.sparse.linalg, "splu", "lu")
timed(_newton.LU, "solve", "lu")
n = int(sys.argv[1])
scene = fsicas.Scene(mstar=1.0, ustar=5.0, modes=n)
model = fsicas.build_model(scene)
spent.clear()
t0 = time.perf_counter()
b = fsicas.stability_boundary(scene, np.logspace(-2, 2, 41), model)
t = time.perf_counter() - t0
print(json.dumps({"time": t, "value": [p.ustar_crit or 0.0 for p in b.points],
                  "switches": [s.mstar for s in b.switches], "spent": dict(spent)}))
"""


def breakdown(run: dict) -> str:
    """casadi / eigen / LU / rest shares of one run's time."""
    t, spent = run["time"], run["spent"]
    shares = [spent.get(k, 0.0) / t for k in ("casadi", "eigen", "lu")]
    return " / ".join(f"{100 * s:.0f}%" for s in [*shares, 1 - sum(shares)])


def row(n: int, old: list, new: list) -> str:
    t_old = np.array([r["time"] for r in old])
    t_new = np.array([r["time"] for r in new])
    u_old, u_new = np.array(old[0]["value"]), np.array(new[0]["value"])
    du = float(np.max(np.abs(u_new - u_old) / np.where(u_old > 0, u_old, 1.0)))
    s_old, s_new = old[0]["switches"], new[0]["switches"]
    ds = float(np.max(np.abs(np.subtract(s_new, s_old)) / np.asarray(s_old))) \
        if len(s_old) == len(s_new) and s_old else float("nan")
    pick = lambda runs, times: runs[int(np.argsort(times)[len(times) // 2])]
    return (f"| {n} | {np.median(t_old):.1f} | {np.median(t_new):.1f} | "
            f"{np.median(t_old / t_new):.2f}x | {du:.1e} | {len(s_old)} / {len(s_new)}, "
            f"{ds:.1e} | {breakdown(pick(old, t_old))} | {breakdown(pick(new, t_new))} | "
            f"{os.getloadavg()[0]:.1f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="d4eeda9", help="git revision to compare with")
    parser.add_argument("--modes", type=int, nargs="+", default=[10, 40])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load "
          f"{os.getloadavg()[0]:.1f}, python {platform.python_version()}; "
          f"baseline {args.baseline}; OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}")
    print("| N | old s | new s | speed-up (median of pairs) | max rel. ΔU*_c | switches old / "
          "new, max rel. ΔM* | old: CasADi / eig / LU / rest | new: CasADi / eig / LU / rest "
          "| load at end |")
    print("|---|---|---|---|---|---|---|---|---|")
    with Baseline(args.baseline) as base:
        for n in args.modes:
            old, new = [], []
            for _ in range(args.repeats):
                old.append(run_child(base.path, CHILD, [n]))
                new.append(run_child(ROOT, CHILD, [n]))
            print(row(n, old, new), flush=True)


if __name__ == "__main__":
    main()
