"""Cost growth of one collocation cycle point with N, NTST and the quadrature nodes.

The flutter model at M* = 1 (``fsicas.cycles.cycle_branch`` from the first Hopf point,
NCOL = 4, default backend), one variable at a time around N = 10, NTST = 20 and the
default 2N + 20 nodes. Per row: the time of a continuation point (corrector, tangent,
multipliers, gauge: the wall time of a ``cycle_branch`` of ``--points`` points on a
fixed mesh, divided by its points) after a warm-up branch that builds (and compiles)
everything, and the fitted exponent ``d log t / d log (variable)`` between neighbouring
rows. One BLAS thread. About a minute.

    python3 benchmarks/bench_scaling.py [--modes 4 10 20 40] [--ntst 10 20 40 80]
        [--nodes 40 80 160] [--points 6]
"""
from __future__ import annotations

import argparse
import os
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402



def point_cost(modes: int, ntst: int, nodes: int | None, points: int) -> float:
    """Wall time per point of a ``cycle_branch`` (see the module docstring)."""
    import fsicas
    from fsicas.cycles import CycleSettings, cycle_branch
    scene = fsicas.Scene(mstar=1.0, modes=modes, quad_nodes=nodes)
    model = fsicas.build_model(scene)
    hopf = fsicas.critical_velocity(scene, model)
    cycle_branch(scene, model, settings=CycleSettings(max_points=2, ntst=ntst), hopf=hopf)
    t0 = time.perf_counter()
    br = cycle_branch(scene, model, hopf=hopf,
                      settings=CycleSettings(max_points=points, ntst=ntst, adapt_every=0))
    return (time.perf_counter() - t0) / len(br.points)


def table(name: str, values, make, points: int) -> None:
    print(f"\n| {name} | ms / point | exponent |")
    print("| --- | --- | --- |")
    last = None
    for v in values:
        t = make(v, points)
        slope = "" if last is None else f"{np.log(t / last[1]) / np.log(v / last[0]):.2f}"
        print(f"| {v} | {1e3 * t:.1f} | {slope} |", flush=True)
        last = (v, t)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs="*", default=[4, 10, 20, 40])
    ap.add_argument("--ntst", type=int, nargs="*", default=[10, 20, 40, 80])
    ap.add_argument("--nodes", type=int, nargs="*", default=[40, 80, 160])
    ap.add_argument("--points", type=int, default=6)
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    table("N (NTST 20, 2N + 20 nodes)", args.modes,
          lambda v, k: point_cost(v, 20, None, k), args.points)
    table("NTST (N = 10)", args.ntst, lambda v, k: point_cost(10, v, None, k), args.points)
    table("nodes (N = 10, NTST 20)", args.nodes, lambda v, k: point_cost(10, 20, v, k),
          args.points)
    print(f"\nmachine at the end: load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
