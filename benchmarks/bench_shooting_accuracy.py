"""Run time against error of the impacting shooting Jacobian: each sensitivity route
and integrator tolerance against a reference integrated at a tolerance of 1e-13.

    python3 benchmarks/bench_shooting_accuracy.py [--modes 4 10]
        [--variants exact@1e-10 fast@1e-10 fast@1e-11 fast@1e-12] [--starts starts.json]

At the first impacting cycle of the shooting branch (M* = 1, contact law k* = 1e8,
eps/H = 1e-2, 12 segments) each variant builds a ``continuation.ShootingProblem`` with
``ImpactSettings(tol=..., sensitivities=...)`` and evaluates its Jacobian (all segment
blocks, forward sensitivities through the impacts) and Floquet multipliers at the same
unknowns. Printed per variant: the time of one Jacobian (after a first call that builds
CasADi's derived integrators), the largest error of the Jacobian relative to the
reference's largest entry, the largest relative error of the moduli of the 6 largest
multipliers, and the same two differences to the first variant ('exact' at 1e-10). The reference is 'exact' at 1e-13: both routes
converge to it as the tolerance shrinks, so it measures each route's own integration
error, which is what their difference has to be compared with.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)
REFERENCE = "exact@1e-13"


def load() -> str:
    return "load average " + " ".join(f"{v:.1f}" for v in os.getloadavg())


def start_cycle(n: int) -> dict:
    """The first impacting cycle of N = n: the collocation branch up to contact, its last
    cycle with a min gap >= 1.05 eps, then shooting steps (ds = 0.02) until the first
    cycle that touches the wall (gap < eps, impacts >= 1)."""
    import fsicas
    from fsicas.cycles import cycle_branch, impacting_cycles
    from fsicas.cycles.impacting import ImpactSettings, pre_contact_start
    base = fsicas.Scene(mstar=1.0, zeta=0.01, modes=n, contact_eps=1e-2)
    s = pre_contact_start(cycle_branch(base, ustar_max=10.0), 1.05)
    br = impacting_cycles(base.replace(ustar=s.ustar, **IMPACT), s, method="shooting",
                          settings=ImpactSettings(max_points=12, ds=0.02, ds_max=0.2,
                                                  sensitivities="fast"))
    p = next(p for p in br.points if p.gap_ratio < 1 and p.impacts >= 1)
    return {"state": [float(v) for v in p.state], "period": p.period,
            "pressure_drop": p.pressure_drop, "ustar": p.ustar, "gap_ratio": p.gap_ratio,
            "impacts": p.impacts}


def starts(modes, path: Path | None) -> dict:
    """The start cycle of each N, kept in ``path`` (JSON) for later runs."""
    known = json.loads(path.read_text()) if path and path.exists() else {}
    for n in modes:
        if str(n) not in known:
            known[str(n)] = start_cycle(n)
    if path:
        path.write_text(json.dumps(known))
    return known


def problem(n: int, start: dict, variant: str):
    """The shooting problem of ``variant`` ('route@tol') at the start cycle of N = n."""
    import continuation as C
    import fsicas
    from fsicas.cycles import impacting as I
    from fsicas.linear.adapter import LOG_M, PI, PI_SCALE, TIME_SCALE, flutter_field
    from fsicas.linear.steady import steady_state

    route, tol = variant.split("@")
    scene = fsicas.Scene(mstar=1.0, zeta=0.01, modes=n, ustar=start["ustar"], **IMPACT)
    model = fsicas.build_model(scene)
    vf, st = flutter_field(model), steady_state(scene, model)
    values = dict(zip(model.parameter_names, st.p))
    params = {PI: start["pressure_drop"] / (scene.mstar * PI_SCALE),
              LOG_M: math.log10(scene.mstar)}
    params.update({k: values[k] for k in vf.par_names[2:]})
    T, x0 = start["period"] * TIME_SCALE, np.array(start["state"])
    shoot = I.shooting_settings(I.ImpactSettings(tol=float(tol), sensitivities=route,
                                                 threads=1))
    points = I.shooting_points(vf, x0, T, params, 12,
                               I.shooting_settings(I.ImpactSettings(tol=1e-13)))
    return C.ShootingProblem(vf, points, T, params, PI, settings=shoot)


def measure(n: int, start: dict, variant: str) -> dict:
    """Time of one Jacobian, the Jacobian and the 6 largest multiplier moduli."""
    pr = problem(n, start, variant)
    X = pr.X0
    pr.jacobian(X + 1e-9)                        # builds the derived integrators
    t0 = time.perf_counter()
    J = pr.jacobian(X).toarray()
    t = time.perf_counter() - t0
    top = np.sort(np.abs(pr.multipliers(X)))[::-1][:6]
    return {"time": t, "J": J, "mu": top}


def rel(a: dict, b: dict) -> tuple[float, float]:
    """Largest Jacobian error relative to ``b``'s largest entry; multiplier moduli."""
    return (float(np.max(np.abs(a["J"] - b["J"])) / np.max(np.abs(b["J"]))),
            float(np.max(np.abs(a["mu"] - b["mu"]) / b["mu"])))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs="+", default=[4, 10])
    ap.add_argument("--variants", nargs="+",
                    default=["exact@1e-10", "fast@1e-10", "fast@1e-11", "fast@1e-12"])
    ap.add_argument("--starts", type=Path, default=None, help="cache of the start cycles")
    args = ap.parse_args()
    for v in args.variants:
        route, _, tol = v.partition("@")
        if route not in ("exact", "fast") or not tol:
            ap.error(f"--variants: 'exact@TOL' or 'fast@TOL', got {v!r}")
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, python "
          f"{platform.python_version()}; {load()}", flush=True)
    known = starts(args.modes, args.starts)
    print("| N | variant | Jacobian [s] | Jacobian error | multiplier error | "
          f"Jacobian diff to {args.variants[0]} | multiplier diff |\n"
          "|---|---|---|---|---|---|---|", flush=True)
    for n in args.modes:
        ref = measure(n, known[str(n)], REFERENCE)
        runs = {v: measure(n, known[str(n)], v) for v in args.variants}
        first = runs[args.variants[0]]
        for v, r in runs.items():
            (eJ, em), (dJ, dm) = rel(r, ref), rel(r, first)
            print(f"| {n} | {v} | {r['time']:.2f} | {eJ:.1e} | {em:.1e} | {dJ:.1e} | {dm:.1e} |",
                  flush=True)
        print(f"<!-- N = {n}: reference {REFERENCE} {ref['time']:.1f} s; {load()} -->",
              flush=True)


if __name__ == "__main__":
    main()
