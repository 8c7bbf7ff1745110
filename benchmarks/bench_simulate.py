"""Work–precision of the time integrators, and the Fig. 4 map per integrator.

    python benchmarks/bench_simulate.py            # N = 40 cycles, the 15 x 7 Fig. 4 map at N = 10
    python benchmarks/bench_simulate.py --quick    # N = 10 cycles, 3 x 2 map
    python benchmarks/bench_simulate.py --scaling  # cost of the integrators' functions vs N

For each case (a no-contact limit cycle, M* = 1, U* = 6.5; the impacting cycle,
M* = 1, U* = 8.5 with contact) every integrator (CVODES, IDAS: CasADi; Radau, BDF:
SciPy) runs from the same settled state for the same number of periods over a range of
tolerances. Period and tip amplitude of the last cycles, and the final state, are
compared with a reference run (IDAS, rtol 1e-11). Prints markdown tables (wall time, errors) and the speed-up over
SciPy at equal error: for each SciPy run, the fastest CasADi run whose period and
amplitude errors are both at most the SciPy run's.
"""
from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np

from fsicas import Scene
from fsicas.timedomain.impact_map import MAP_SCENE, impact_map
from fsicas.timedomain.outcome import Criteria, classify
from fsicas.timedomain.run import guarded_model, run_case
from fsicas.timedomain.integrators import Settings, simulate
from fsicas.linear.steady import steady_state

CONTACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2)
METHODS = {"idas": [1e-4, 1e-6, 1e-8, 1e-10], "cvodes": [1e-4, 1e-6, 1e-8, 1e-10],
           "radau": [1e-4, 1e-6, 1e-8], "bdf": [1e-4, 1e-6]}
REFERENCE = ("idas", 1e-11)


def machine() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        model = next(l.split(":", 1)[1].strip() for l in out.splitlines() if l.startswith("Model name"))
    except (OSError, StopIteration):
        model = platform.processor() or "unknown"
    return f"{os.cpu_count()} cores, {model}, Python {platform.python_version()}"


def measure(model, steady, t_end, settings, x0):
    """(wall time, period, amplitude, outcome, steps, final state) of one run from x0 to t_end."""
    start = time.perf_counter()
    traj = simulate(model, steady, t_end, settings=settings, x0=x0)
    wall = time.perf_counter() - start
    if traj.status != "success":
        return wall, np.nan, np.nan, "failed: " + traj.message[:60], traj.steps, np.full(model.n_state, np.nan)
    o = classify(traj, steady, Criteria(cycles=3, tol=0.5, tol_impacting=0.5, stop_on_contact=False))
    return wall, o.period or np.nan, o.tip_amplitude or np.nan, o.outcome, traj.steps, traj.x[-1]


def work_precision(name, scene, t_pre, dt_out, methods, periods):
    model, _ = guarded_model(scene)
    steady = steady_state(scene, model)
    # a common start on the cycle: run the transient once, start everyone from there
    start = time.perf_counter()
    pre = run_case(scene, t_pre, settings=Settings(rtol=1e-8, atol=1e-10, dt_out=dt_out, chunk=0.5),
                   model=model, perturbation=0.3, stop_early=False,
                   criteria=Criteria(stop_on_contact=False))
    x0 = pre.trajectory.x[-1]
    span = periods * (pre.outcome.period or 0.13)
    print(f"\n### {name}: N = {scene.modes}, U* = {scene.ustar}, M* = {scene.mstar}, "
          f"contact = {scene.contact}, run of {span:.4f} ({periods} periods) from a settled state "
          f"(transient {t_pre} in {time.perf_counter() - start:.0f} s, outcome {pre.outcome.outcome})\n")
    ref = measure(model, steady, span, Settings(method=REFERENCE[0], rtol=REFERENCE[1], atol=REFERENCE[1] * 1e-2,
                                                  dt_out=dt_out, chunk=span), x0)
    print(f"reference ({REFERENCE[0]} rtol {REFERENCE[1]:.0e}): period {ref[1]:.10f}, amplitude {ref[2]:.10f}, "
          f"{ref[0]:.2f} s, outcome {ref[3]}\n")
    print("| integrator | rtol | wall time (s) | steps | period error | amplitude error | final-state error | outcome |")
    print("|---|---|---|---|---|---|---|---|")
    rows = []
    for method, tols in methods.items():
        for rtol in tols:
            s = Settings(method=method, rtol=rtol, atol=rtol * 1e-2, dt_out=dt_out, chunk=span)
            wall, period, amp, outcome, steps, x_end = measure(model, steady, span, s, x0)
            ep, ea = abs(period - ref[1]) / ref[1], abs(amp - ref[2]) / ref[2]
            ex = float(np.max(np.abs(x_end - ref[5])) / np.max(np.abs(ref[5])))
            rows.append((method, rtol, wall, ep, ea))
            print(f"| {method} | {rtol:.0e} | {wall:.3f} | {steps} | {ep:.2e} | {ea:.2e} | {ex:.2e} | {outcome} |",
                  flush=True)
    speedups(rows)
    return rows


def speedups(rows):
    print("\nspeed-up over SciPy at equal error (fastest CasADi run at least as accurate):\n")
    print("| SciPy run | its time (s) | CasADi run | time (s) | speed-up |")
    print("|---|---|---|---|---|")
    for m, rtol, wall, ep, ea in rows:
        if m not in ("radau", "bdf") or not np.isfinite(ep):
            continue
        err = max(ep, ea)
        better = [r for r in rows if r[0] in ("cvodes", "idas") and max(r[3], r[4]) <= err]
        if better:
            best = min(better, key=lambda r: r[2])
            print(f"| {m} {rtol:.0e} | {wall:.3f} | {best[0]} {best[1]:.0e} | {best[2]:.3f} | "
                  f"{wall / best[2]:.1f}x |")


def scaling(modes):
    """One call of each function an integrator evaluates, per N (median of repeats, µs):
    the IDAS residual M z − F with the matrix-free and with the assembled M z, the IDAS
    Newton matrix (Jacobian in x and z), the explicit M⁻¹F (CVODES, SciPy), its Jacobian
    by AD through solve(M, F) (CVODES) and through the matrix-free M v (SciPy)."""
    import statistics
    import timeit

    import casadi as ca

    from fsicas.timedomain.breathing import PressureSchedule
    from fsicas.timedomain.rhs import explicit_ode, ode_symbols

    def per_call(f, *args):
        f(*args)
        t = timeit.repeat(lambda: f(*args), number=20, repeat=7)
        return 1e6 * statistics.median(t) / 20

    print("\n### Cost of one call (µs) per N, contact on, quad_nodes = 2N + 20\n")
    print("| N | M z − F (matrix-free) | M z − F (assembled M) | IDAS Newton matrix (matrix-free) | "
          "(assembled) | M⁻¹F | d(M⁻¹F)/dx by AD | d(M⁻¹F)/dx via M v |")
    print("|---|---|---|---|---|---|---|---|")
    for n in modes:
        scene = Scene(mstar=1.0, ustar=8.5, zeta=0.01, modes=n, **CONTACT)
        model, _ = guarded_model(scene)
        steady = steady_state(scene, model)
        x, pe, t, p_t, F = ode_symbols(model)
        z = ca.MX.sym("z", model.n_state)
        xdot, jac = explicit_ode(model, x, pe, t, p_t, F)
        free = model.mass_action(x, p_t, z) - F
        assembled = ca.mtimes(model.mass(x, p_t), z) - F
        xz = ca.vertcat(x, z)
        fns = [ca.Function("r", [x, z, pe, t], [free]), ca.Function("ra", [x, z, pe, t], [assembled]),
               ca.Function("J", [x, z, pe, t], [ca.jacobian(free, xz)]),
               ca.Function("Ja", [x, z, pe, t], [ca.jacobian(assembled, xz)]),
               ca.Function("f", [x, z, pe, t], [xdot]),
               ca.Function("Jad", [x, z, pe, t], [ca.jacobian(xdot, x)])]
        pv = np.concatenate([steady.p, PressureSchedule.constant(8.5).vector(1.0), [0.0]])
        x0 = steady.x + 1e-3 * np.r_[np.ones(2 * n), 0, 0] / np.r_[np.arange(1, n + 1), np.arange(1, n + 1), 1, 1]
        z0 = np.array(fns[4](x0, x0, pv, 0.0)).ravel()
        cost = [per_call(f, x0, z0, pv, 0.0) for f in fns] + [per_call(jac, 0.0, x0, pv)]
        print(f"| {n} | " + " | ".join(f"{c:.0f}" for c in cost) + " |", flush=True)


def map_benchmark(ustars, mstars, modes, t_end, methods):
    print(f"\n### Fig. 4 map: {len(ustars)} x {len(mstars)} points, N = {modes}, t_end = {t_end}, "
          "2 worker processes\n")
    print("| integrator | rtol | wall time (s) | decay | lco | contact | unsettled | other | agrees with IDAS |")
    print("|---|---|---|---|---|---|---|---|---|")
    first = None
    for method, rtol in methods:
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            res = impact_map(ustars, mstars, f"{tmp}/map.jsonl", scene=MAP_SCENE.replace(modes=modes),
                             t_end=t_end, workers=2,
                             settings=Settings(method=method, rtol=rtol, atol=rtol * 1e-2,
                                               dt_out=2e-3, chunk=1.0))
            wall = time.perf_counter() - start
        kinds = [p["outcome"] for p in res.points]
        first = first or kinds
        c = {k: kinds.count(k) for k in ("decay", "lco", "contact", "unsettled")}
        other = len(kinds) - sum(c.values())
        agree = sum(a == b for a, b in zip(kinds, first))
        print(f"| {method} | {rtol:.0e} | {wall:.1f} | {c['decay']} | {c['lco']} | {c['contact']} | "
              f"{c['unsettled']} | {other} | {agree}/{len(kinds)} |")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--modes", type=int, default=None, help="N of the cycles (default 40, quick 10)")
    ap.add_argument("--map-only", action="store_true", help="only the Fig. 4 map timing")
    ap.add_argument("--no-map", action="store_true", help="only the work-precision tables")
    ap.add_argument("--cases", nargs="+", default=["free", "impacting"], choices=["free", "impacting"],
                    help="work-precision cases: the no-contact and/or the impacting cycle")
    ap.add_argument("--methods", nargs="+", default=list(METHODS), choices=list(METHODS))
    ap.add_argument("--scaling", action="store_true", help="only the cost of the functions vs N")
    args = ap.parse_args(argv)
    n = args.modes or (10 if args.quick else 40)
    print(f"machine: {machine()}")
    if args.scaling:
        scaling([10, 20, 40, 80])
        return 0
    methods = METHODS if not args.quick else {m: t[:3] for m, t in METHODS.items()}
    if n > 20:   # CVODES and SciPy (Jacobian of M⁻¹F, 16 ms at N = 40) too slow at tight tolerances
        methods = {**methods, "cvodes": [1e-4, 1e-6, 1e-8], "radau": [1e-4, 1e-6], "bdf": [1e-4]}
    base = Scene(mstar=1.0, zeta=0.01, modes=n)
    methods = {m: t for m, t in methods.items() if m in args.methods}
    periods = 10 if n <= 20 else 5
    if not args.map_only and "free" in args.cases:
        work_precision("no-contact limit cycle", base.replace(ustar=6.5), 6.0, 1e-4, methods, periods)
    if not args.map_only and "impacting" in args.cases:
        work_precision("impacting cycle", base.replace(ustar=8.5, **CONTACT), 4.0, 2e-5, methods, periods)
    if args.no_map:
        return 0
    if args.quick:
        map_benchmark(np.linspace(4, 12, 3), [0.3, 3.0], 10, 20.0,
                      [("idas", 1e-7), ("cvodes", 1e-7), ("radau", 1e-7)])
    else:
        map_benchmark(np.linspace(2, 16, 15), np.geomspace(0.1, 10, 7), 10, 30.0,   # Fig. 4's grid
                      [("idas", 1e-7), ("cvodes", 1e-7), ("radau", 1e-7)])
    return 0


if __name__ == "__main__":
    sys.exit(main())
