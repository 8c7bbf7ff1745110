"""Speed-up of the working tree over an earlier revision, side by side in one run.

Each row runs the same task in fresh processes, alternating the old tree (``--baseline``,
unpacked from git) and the working tree, and prints the median times, the median of the
pairwise ratios old/new and the largest difference between the two trees' results
(the error between routes: both compute the same quantity):

- ``eig``: one eigen-analysis (steady state + generalized eigenproblem) at M* = 1, U* = 5,
  median of 20 calls (value: the flutter eigenvalue near 45.6i);
- ``ucrit``: one flutter onset U*_c at M* = 1 on a built model, after a warm-up at
  M* = 1.1 (value: U*_c and omega);
- ``boundary``: the Fig. 2 boundary over ``--points`` log-spaced M* in [0.01, 100]
  (value: U*_c at every M*);
- ``cycle``: cost per point of a collocation branch of ``--cycle-points`` (default 8)
  cycles from the Hopf point at M* = 1 (NTST = 20, NCOL = 4), after a warm-up branch of
  2 points that builds the systems (and compiles the kernel into the on-disk cache if
  it is not there yet); value: period and Δp of the last cycle;
- ``branch``: the same with ``cycle_branch``'s defaults (re-meshed every 5 points,
  detection, the measures of every point), 40 points;
- ``impacting``: cost per point of the impacting collocation branch (k* = 1e8,
  eps/H = 1e-2, smoothing 0.1, zeta = 0.01, NTST = 200, re-meshed at every point) from
  the last contact-free cycle 3 eps from the wall, ``--cycle-points`` points after a
  2-point warm-up; value: U* and period of the last cycle;
- ``brusselator``: cost per point (corrector, tangent, multipliers) of the cycle branch
  of ``bench_cycles.py`` (the Brusselator chain of ``--modes`` states, NTST = 50), 20
  points after 2 untimed ones; no flutter model is built; value: the last point's B
  and period.

    python3 benchmarks/bench_speedup.py [--baseline main] [--modes 10] [--tasks eig ucrit]
"""
from __future__ import annotations

import argparse
import os
import platform

import inspect

import common
from common import Baseline, compare

PRELUDE = """
import json, sys, time
import numpy as np
import fsicas
n = int(sys.argv[1])
def done(t, value):
    print(json.dumps({"time": t, "value": [float(v) for v in value]}))
"""
#: the flutter model of the tasks on it (all but 'brusselator')
FLUTTER = """
scene = fsicas.Scene(mstar=1.0, ustar=5.0, modes=n)
model = fsicas.build_model(scene)
"""

#: the Brusselator chain of bench_cycles.py, written into the child (an older tree's
#: benchmarks may not have it)
CHAIN = (f"import casadi as ca\nA, D1, D2 = {common.A}, {common.D1}, {common.D2}\n"
         + "".join(inspect.getsource(f) for f in (common.brusselator_chain, common.params,
                                                   common.hopf_b)))

TASKS = {
    "eig": """
fsicas.linear_stability(scene, model)
times = []
for _ in range(20):
    t0 = time.perf_counter(); a = fsicas.linear_stability(scene, model)
    times.append(time.perf_counter() - t0)
lam = np.asarray(a.eigenvalues)
lam = lam[np.argmin(np.abs(lam - 45.6j))]
done(float(np.median(times)), [lam.real, lam.imag])
""",
    "ucrit": """
fsicas.critical_velocity(scene.replace(mstar=1.1), model)
t0 = time.perf_counter(); h = fsicas.critical_velocity(scene, model)
done(time.perf_counter() - t0, [h.ustar, h.omega])
""",
    "boundary": """
points = int(sys.argv[2])
t0 = time.perf_counter(); b = fsicas.stability_boundary(scene, np.logspace(-2, 2, points), model)
t = time.perf_counter() - t0
rows = [p.to_json() if hasattr(p, "to_json") else p for p in b.points]
done(t, [r["ustar_crit"] or 0.0 for r in rows])
""",
    "cycle": """
from fsicas.cycles import CycleSettings, cycle_branch
hopf = fsicas.critical_velocity(scene, model)
cycle_branch(scene, model, settings=CycleSettings(max_points=2), hopf=hopf)
t0 = time.perf_counter()
points = int(sys.argv[3])
br = cycle_branch(scene, model, settings=CycleSettings(max_points=points, adapt_every=0), hopf=hopf)
t = (time.perf_counter() - t0) / len(br.points)
last = br.points[-1]
done(t, [last.period, last.pressure_drop])
""",
    "branch": """
from fsicas.cycles import cycle_branch
hopf = fsicas.critical_velocity(scene, model)
cycle_branch(scene, model, hopf=hopf)
t0 = time.perf_counter()
br = cycle_branch(scene, model, settings=fsicas.cycles.CycleSettings(max_points=40), hopf=hopf)
t = (time.perf_counter() - t0) / len(br.points)
done(t, [br.points[-1].ustar, br.points[-1].period])
""",
    "impacting": """
from fsicas.cycles import cycle_branch
from fsicas.cycles.impacting import pre_contact_start
from fsicas.cycles import CollocationImpactSettings, impacting_cycles
scene = fsicas.Scene(mstar=1.0, zeta=0.01, modes=n, contact=True, contact_stiffness=1e8,
                     contact_eps=1e-2, contact_smoothing=0.1)
model = fsicas.build_model(scene)
start = pre_contact_start(cycle_branch(scene.replace(contact=False), ustar_max=12), 3.0)
run = lambda points: impacting_cycles(
    scene.replace(ustar=start.ustar), start, model=model, ustar_max=12,
    settings=CollocationImpactSettings(max_points=points))
run(2)
t0 = time.perf_counter()
br = run(int(sys.argv[3]))
t = (time.perf_counter() - t0) / len(br.points)
done(t, [br.points[-1].ustar, br.points[-1].period])
""",
    "brusselator": """
import continuation as C
eq = C.EquilibriumProblem(brusselator_chain(n), np.tile([A, 4.5 / A], n // 2), params(4.5), "B")
hopf = C.continuation(eq, settings=C.ContinuationSettings(
    ds=0.05, ds_max=0.1, bounds={"B": (4.0, hopf_b(n) + 0.3)})).special("hopf")[0]
cyc = C.cycle_from_hopf(eq, hopf, dp=1e-3, settings=C.CollocationSettings(
    ntst=50, ncol=4, floquet="product"))
scale = np.sqrt(200)
it = C.ContinuationIterator(cyc, C.PALC(), C.ContinuationSettings(
    ds=0.01 * scale, ds_max=0.05 * scale, max_steps=30, direction=cyc.hopf_direction))
step = it.start()
for _ in range(2):                      # untimed: builds and loads everything
    step = it.advance(step); cyc.multipliers(step.X)
t0 = time.perf_counter()
for _ in range(20):
    step = it.advance(step); cyc.multipliers(step.X)
done((time.perf_counter() - t0) / 20, [cyc.params(step.X)[1], cyc.period(step.X)])
""",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="main", help="git revision to compare with")
    parser.add_argument("--modes", type=int, nargs="+", default=[10])
    parser.add_argument("--tasks", nargs="+", choices=sorted(TASKS), default=sorted(TASKS))
    parser.add_argument("--points", type=int, default=41, help="M* values of 'boundary'")
    parser.add_argument("--cycle-points", type=int, default=8, help="points of 'cycle'")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load "
          f"{os.getloadavg()[0]:.1f}, python {platform.python_version()}; "
          f"baseline {args.baseline}")
    print("| task | N | old s | new s | speed-up (median of pairs) | max |Δ result| |")
    print("|---|---|---|---|---|---|")
    with Baseline(args.baseline) as base:
        for task in args.tasks:
            for n in args.modes:
                prelude = PRELUDE + (CHAIN if task == "brusselator" else FLUTTER)
                c = compare(base.path, prelude + TASKS[task], [n, args.points, args.cycle_points],
                            args.repeats)
                print(f"| {task} | {n} | {c.old:.4g} | {c.new:.4g} | {c.speedup:.1f}x | "
                      f"{c.difference:.1e} |", flush=True)


if __name__ == "__main__":
    main()
