"""The Newton solver of collocated cycles: condensation against SuperLU of the whole matrix.

Both routes continue the same cycle branch from the same start, alternating point by
point (interleaved, so the machine's drift hits both alike). Printed per case: the
median time of a continuation point (corrector, tangent, Floquet multipliers) of each,
the median of the pointwise ratios sparse / condensed, the largest relative difference
between the two branches (parameter, period and multipliers: both solve the same
equations to the same tolerance, so this is the error between the routes).

Cases: the flutter model (``fsicas``, M* = 1, N modes, n = 2N + 2 states with dense
blocks, NTST = 20, NCOL = 4, the steps of ``fsicas.cycles.cycle_branch``) and the
Brusselator chain of ``bench_cycles.py`` (``common.py``) (n = 2 cells, banded blocks, NTST = 50).

    python benchmarks/bench_linear_solver.py [--modes 4 10 20 40] [--cells 2 5 10]
        [--points 12]
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import continuation as C  # noqa: E402
from common import A, brusselator_chain, flutter_start, hopf_b, params  # noqa: E402

SOLVERS = ("sparse", "condensed")


def flutter(modes: int, solver: str):
    """The flutter cycle problem from its first Hopf point, and its step settings."""
    eq, hopf = flutter_start(modes)
    prob = C.cycle_from_hopf(eq, hopf.point, dp=1e-3, settings=C.CollocationSettings(
        ntst=20, ncol=4, floquet="product", linear_solver=solver))
    return prob, C.ContinuationSettings(ds=0.01, ds_min=1e-9, ds_max=0.1,
                                        direction=prob.hopf_direction, detect=False)


def brusselator(n: int, solver: str):
    """The Brusselator chain of ``bench_cycles`` (n states) from its Hopf point."""
    F = brusselator_chain(n)
    eq = C.EquilibriumProblem(F, np.tile([A, 4.5 / A], n // 2), params(4.5), "B")
    br = C.continuation(eq, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.1, bounds={"B": (4.0, hopf_b(n) + 0.3)}))
    prob = C.cycle_from_hopf(eq, br.special("hopf")[0], dp=1e-3, settings=C.CollocationSettings(
        ntst=50, ncol=4, floquet="product", linear_solver=solver))
    scale = np.sqrt(50 * 4)
    return prob, C.ContinuationSettings(ds=0.01 * scale, ds_max=0.05 * scale,
                                        direction=prob.hopf_direction, detect=False)


def walkers(make, size: int, points: int) -> dict:
    """Per solver: the problem and a generator of ``(X, multipliers)`` past the start."""
    out = {}
    for solver in SOLVERS:
        prob, settings = make(size, solver)
        it = iter(C.ContinuationIterator(prob, C.PALC(),
                                         replace(settings, max_steps=points)))
        first = next(it)
        prob.multipliers(first.X)                       # builds everything, not timed
        out[solver] = (prob, (lambda prob=prob, it=it: _point(prob, it)))
    return out


def _point(prob, it):
    step = next(it)
    return step.X, prob.multipliers(step.X)


def compare(make, size: int, points: int) -> dict:
    """Interleaved timing and the differences between the two branches."""
    runs = walkers(make, size, points)
    times = {s: [] for s in SOLVERS}
    last = {}
    for _ in range(points):
        for solver, (prob, step) in runs.items():
            t0 = time.perf_counter()
            last[solver] = step()
            times[solver].append(time.perf_counter() - t0)
    (pa, _), (pb, _) = runs["sparse"], runs["condensed"]
    (Xa, mua), (Xb, mub) = last["sparse"], last["condensed"]
    diff = max(_rel(pa.params(Xa), pb.params(Xb)), _rel(pa.period(Xa), pb.period(Xb)),
               _rel(mua, mub))
    ratio = np.median(np.array(times["sparse"]) / np.array(times["condensed"]))
    return {"sparse": np.median(times["sparse"]), "condensed": np.median(times["condensed"]),
            "ratio": ratio, "diff": diff}


def _rel(a, b) -> float:
    a, b = np.atleast_1d(a), np.atleast_1d(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs="*", default=[4, 10, 20, 40])
    ap.add_argument("--cells", type=int, nargs="*", default=[2, 5, 10])
    ap.add_argument("--points", type=int, default=12)
    args = ap.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.1f} ({os.cpu_count()} cores)")
    print("| model | n | sparse [ms/point] | condensed [ms/point] | speed-up | "
          "max rel. difference |")
    print("| --- | --- | --- | --- | --- | --- |")
    cases = [("flutter N = %d" % m, flutter, m, 2 * m + 2) for m in args.modes] + \
        [("Brusselator", brusselator, 2 * c, 2 * c) for c in args.cells]
    for name, make, size, n in cases:
        r = compare(make, size, args.points)
        print(f"| {name} | {n} | {1e3 * r['sparse']:.1f} | {1e3 * r['condensed']:.1f} | "
              f"{r['ratio']:.2f}x | {r['diff']:.1e} |",
              flush=True)


if __name__ == "__main__":
    main()
