"""Work-precision of the two routes to impacting cycles: adaptive collocation against
multiple shooting, at the same U*, interleaved in one run.

    python benchmarks/bench_impacting_routes.py --modes 10 --ustar 6.8 \
        --ntst 100 200 400 --shoot 12:1e-8 12:1e-10 --ref-ntst 800 --points 4

Single-threaded BLAS (``OPENBLAS_NUM_THREADS=1`` unless set). M* = 1, zeta = 0.01, H* = 1/10, f = 0.14, contact k* = 1e8, eps/H = 1e-2, smoothing 0.1.
Start: the contact-free collocation branch (``cycle_branch``) up to its last cycle with
gap >= 3 eps, then a collocation branch past contact up to the target U*; the cycle
nearest the target is the common start guess (state, period) of every run at the
target's pressure drop. Each run: one branch of ``--points`` points from there; its first
point is the cycle *at* the target (the error: period, tip half-amplitude and the
largest non-trivial |mu|, relative to the reference: collocation on ``--ref-ntst``
intervals for period and amplitude, shooting at ``--ref-shoot`` for |mu|, both printed); the time per point is the mean
wall time of the continuation points after the first (corrector, tangent, multipliers,
measurements; as for shooting, no special cycles detected and no turn limit), with the
mean step in U*. A time integration (IDAS, rtol 1e-10) over
``--ti-periods`` periods from the reference cycle's state is the third check: the state's
return after each period and the amplitude over the first.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # before NumPy: see docs/continuation.md
import numpy as np  # noqa: E402

from fsicas import Scene  # noqa: E402
from fsicas.cycles import (CollocationImpactSettings, CycleSettings, ImpactSettings,  # noqa: E402
                           StartCycle, cycle_branch, impacting_cycles,
                           pre_contact_start)
from fsicas.linear.steady import steady_state  # noqa: E402
from fsicas.model import build_model  # noqa: E402
from fsicas.timedomain.integrators import Settings, simulate  # noqa: E402

IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)


def target_guess(modes: int, ustar: float, ntst: int = 200):
    """(scene at the target, model, state, period, pressure drop) of the period-1 cycle
    continued past contact to the point nearest ``ustar``."""
    base = Scene(mstar=1.0, zeta=0.01, modes=modes, contact_eps=1e-2)
    start = pre_contact_start(cycle_branch(base, ustar_max=10.0, settings=CycleSettings(ntst=40)))
    scene = base.replace(ustar=start.ustar, **IMPACT)
    model = build_model(scene)
    br = impacting_cycles(scene, start, model=model, ustar_max=ustar + 0.1,
                          settings=CollocationImpactSettings(ntst=ntst, max_points=80, ds=0.05, ds_max=0.6,
                                                             detect=False))
    near = min(br.points, key=lambda p: abs(p.ustar - ustar))
    target = scene.replace(ustar=ustar)
    return target, model, near.state, near.period, steady_state(target, model).pressure_drop


def colloc_run(case, ntst: int, points: int, ds: float):
    scene, model, state, period, dp = case
    s = CollocationImpactSettings(ntst=ntst, max_points=points, ds=ds * np.sqrt(ntst / 20),
                                  ds_max=ds * np.sqrt(ntst / 20), detect=False, max_turn=0.0)
    return impacting_cycles(scene, StartCycle(state, period, dp), model=model, settings=s)


def shoot_run(case, segments: int, tol: float, points: int, ds: float):
    scene, model, state, period, dp = case
    s = ImpactSettings(segments=segments, tol=tol, newton_tol=max(1e-10, 100 * tol),
                       max_points=points, ds=ds * np.sqrt(segments / 12),
                       ds_max=ds * np.sqrt(segments / 12))
    return impacting_cycles(scene, StartCycle(state, period, dp), method="shooting", model=model,
                            settings=s)


def measures(point) -> dict:
    return {"ustar": point.ustar, "period": point.period, "amplitude": point.tip_amplitude,
            "gap_ratio": point.gap_ratio, "impacts": point.impacts,
            "mu": float(np.max(np.abs(point.nontrivial_multipliers)))}


def row(route, size, branch, ref) -> dict:
    """Errors of the branch's first point against ``ref``, time and step per later point."""
    if not branch.points:
        return {"route": route, "size": size, "status": branch.status, "message": branch.message}
    m = measures(branch.points[0])
    later = branch.points[1:]
    err = {k: abs(m[k] / ref[k] - 1) for k in ("period", "amplitude", "mu")}
    return {"route": route, "size": size, "status": branch.status, **m,
            **{f"err_{k}": v for k, v in err.items()},
            "time": float(np.mean([p.wall_time for p in later])) if later else float("nan"),
            "start_time": branch.points[0].wall_time, "points": len(branch.points),
            "dustar": float(np.mean(np.abs(np.diff([p.ustar for p in branch.points]))))
            if later else float("nan")}


def time_integration(case, ref_point, periods: int) -> dict:
    """IDAS (rtol 1e-10) from the reference state over ``periods`` periods: the relative
    state miss after each period and the tip half-amplitude over the first."""
    scene, model, _, _, _ = case
    T = ref_point.period
    traj = simulate(model, steady_state(scene, model), periods * T, x0=ref_point.state,
                    settings=Settings(method="idas", rtol=1e-10, atol=1e-12, dt_out=T / 20000))
    x, t = traj.x, traj.t
    idx = [int(np.argmin(np.abs(t - k * T))) for k in range(1, periods + 1)]
    scale = np.max(np.abs(ref_point.state))
    miss = [float(np.max(np.abs(x[i] - ref_point.state)) / scale) for i in idx]
    y = model.tip_deflection(x[: idx[0] + 1])
    return {"status": traj.status, "return_miss": miss, "amplitude": float(y.max() - y.min()) / 2}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--modes", type=int, default=10)
    ap.add_argument("--ustar", type=float, default=6.8)
    ap.add_argument("--ntst", type=int, nargs="+", default=[100, 200, 400])
    ap.add_argument("--shoot", nargs="+", default=["12:1e-8", "12:1e-10"],
                    help="segments:tol of each shooting run, or 'none'")
    ap.add_argument("--ref-ntst", type=int, default=800)
    ap.add_argument("--ref-shoot", default="24:1e-12", help="segments:tol, or 'none'")
    ap.add_argument("--points", type=int, default=4)
    ap.add_argument("--ds", type=float, default=0.05, help="collocation ds at NTST = 20")
    ap.add_argument("--ds-shoot", type=float, default=0.05, help="shooting ds at 12 segments")
    ap.add_argument("--ti-periods", type=int, default=2)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    print(f"# {time.strftime('%Y-%m-%d %H:%M:%S')} load {os.getloadavg()}", flush=True)
    t0 = time.perf_counter()
    case = target_guess(args.modes, args.ustar)
    print(f"# setup {time.perf_counter() - t0:.1f} s", flush=True)
    ref_c = colloc_run(case, args.ref_ntst, 1, args.ds)
    ref = measures(ref_c.points[0])
    print("# reference collocation", args.ref_ntst, json.dumps(ref), flush=True)
    rows = []
    if args.ref_shoot != "none":
        seg, tol = args.ref_shoot.split(":")
        ref_s = shoot_run(case, int(seg), float(tol), 1, args.ds_shoot)
        print("# reference shooting", args.ref_shoot, json.dumps(
            measures(ref_s.points[0]) if ref_s.points else ref_s.message), flush=True)
        if ref_s.points:   # the multipliers' reference (collocation's converge slower)
            ref["mu"] = measures(ref_s.points[0])["mu"]
            rows.append(row("shooting (reference)", args.ref_shoot, ref_s, ref))
    print("# time integration from the reference state", json.dumps(
        time_integration(case, ref_c.points[0], args.ti_periods)), flush=True)
    jobs = [("collocation", n) for n in args.ntst]
    shots = [("shooting", s) for s in args.shoot if s != "none"]
    for k in range(max(len(jobs), len(shots))):          # interleaved
        for route, size in (jobs[k:k + 1] + shots[k:k + 1]):
            if route == "collocation":
                br = colloc_run(case, size, args.points, args.ds)
            else:
                seg, tol = size.split(":")
                br = shoot_run(case, int(seg), float(tol), args.points, args.ds_shoot)
            rows.append(row(route, size, br, ref))
            print(json.dumps(rows[-1]), flush=True)
    print(f"# end {time.strftime('%H:%M:%S')} load {os.getloadavg()}")
    print_table(args.modes, rows)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"modes": args.modes, "ustar": args.ustar, "reference": ref, "rows": rows}, f,
                      indent=1)
    return 0


def print_table(modes, rows) -> None:
    print("| route | N | NTST or segments:tol | time per point (s) | ΔU* per point | "
          "start point (s) | period error | amplitude error | max |μ| error |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if "err_period" not in r:
            print(f"| {r['route']} | {modes} | {r['size']} | failed: {r['message']} |")
            continue
        print(f"| {r['route']} | {modes} | {r['size']} | {r['time']:.3g} | {r['dustar']:.3g} | "
              f"{r['start_time']:.3g} | {r['err_period']:.1e} | {r['err_amplitude']:.1e} | "
              f"{r['err_mu']:.1e} |")


if __name__ == "__main__":
    sys.exit(main())
