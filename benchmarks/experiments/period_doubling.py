"""Period doubling of impacting cycles: absent in the symmetric channel, present off centre.

    python benchmarks/experiments/period_doubling.py [--modes 4] [--scan 0.1 0.3 1 3 10]
        [--offset 0.02 --mstar 0.287 --ustar-max 9.25]

k* = 1e8, eps/H = 1e-2, smoothing 0.1, zeta = 0.01, NTST = 200. Two parts:

1. ``--scan``: in the symmetric channel, the period-1 impacting branch from the first
   contact (``impacting_cycles``, special cycles located) at each M*: its
   special cycles and the real multiplier nearest -1 along it. A symmetric cycle
   cannot period-double (docs/cycles.md), so none is expected. ``--ns-curve M*``: the
   located Neimark-Sacker point of that branch nearest -1, continued as a curve in
   (U*, M*) both ways (``continuation.CycleCurveProblem``): the largest angle of its
   pair (pi would be the 1:2 resonance, where a period doubling curve could start).
2. ``--offset``: the walls moved off centre by that fraction (H1, H2 = (1 +- offset) H/2)
   at ``--mstar``: the branch to ``--ustar-max``, its first period doubling (located
   once more on ``--refine-ntst`` intervals where given), the doubled
   branch (``period_doubled_branch``) and, at ``--checks`` of its points, a time
   integration from the cycle (``settled_cycle``, IDAS 1e-10): period, amplitude and
   peak force against the cycle's.
"""
from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # before NumPy: docs/continuation.md
import numpy as np  # noqa: E402

import continuation as C  # noqa: E402
from fsicas import Scene  # noqa: E402
from fsicas.cycles import (CollocationImpactSettings, CycleSettings,  # noqa: E402
                           impacting_cycles, period_doubled_branch)
from fsicas.cycles.impacting_collocation import impacting_collocation_problem  # noqa: E402
from fsicas.linear.adapter import LOG_M, PI  # noqa: E402
from fsicas.model import build_model  # noqa: E402
from fsicas.scene import Profile  # noqa: E402
from fsicas.timedomain.settled import settled_cycle  # noqa: E402

IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)


def impacting(base: Scene, ustar_max: float, points: int, refine_ntst: int = 0):
    """(scene, model, branch): the period-1 impacting branch from 3 eps before contact."""
    scene = base.replace(**IMPACT)
    model = build_model(scene)                    # independent of U*: one build
    branch = impacting_cycles(
        scene, model=model, ustar_max=ustar_max,
        cycle_settings=CycleSettings(quadrature_tol=None), settings=CollocationImpactSettings(
            ntst=200, max_points=points, ds=0.1, refine_ntst=refine_ntst))
    return branch.scene, model, branch


def nearest_real_to_minus_one(branch) -> tuple[float, float]:
    """(U*, multiplier) of the real non-trivial multiplier nearest -1 along the branch."""
    best = (np.nan, np.inf)
    for p in branch.points:
        mu = p.nontrivial_multipliers
        real = mu.real[mu.imag == 0]
        m = real[np.argmin(abs(real + 1))] if real.size else np.inf
        if abs(m + 1) < abs(best[1] + 1):
            best = (p.ustar, float(m))
    return best


def scan(modes: int, mstars, ustar_max: float) -> None:
    print("| M* | U* range | special cycles | real multiplier nearest -1 (at U*) | time |")
    print("|---|---|---|---|---|")
    for mstar in mstars:
        t0 = time.perf_counter()
        _, _, br = impacting(Scene(mstar=mstar, zeta=0.01, modes=modes, contact_eps=1e-2),
                             ustar_max, 400)
        kinds = ", ".join(f"{p.kind} {p.ustar:.4f}" for p in br.special) or "none"
        u, m = nearest_real_to_minus_one(br)
        print(f"| {mstar:g} | {br.column('ustar').min():.3f}-{br.column('ustar').max():.3f} | "
              f"{kinds} | {m:.3g} ({u:.4f}) | {time.perf_counter() - t0:.0f} s |", flush=True)


def ns_curve(modes: int, mstar: float, ustar_max: float, steps: int) -> None:
    """The Neimark-Sacker curve through the branch's NS point nearest -1, both ways."""
    scene, model, br = impacting(Scene(mstar=mstar, zeta=0.01, modes=modes,
                                       contact_eps=1e-2), ustar_max, 400)
    ns = min((p for p in br.special if p.kind == "ns" and p.located),
             key=lambda p: abs(p.critical_multiplier + 1))
    problem = impacting_collocation_problem(
        scene.replace(ustar=ns.ustar), ns.state, ns.period, ns.pressure_drop, model=model,
        settings=CollocationImpactSettings(ntst=200))
    square, result = C.locate_cycle(problem, problem.X0, C.NeimarkSacker())
    for direction in (1, -1):
        curve = C.CycleCurveProblem(square, result.X, (PI, LOG_M), C.NeimarkSacker())
        angles = []
        record = lambda p, X: angles.append(  # noqa: E731
            (10 ** p.par_dict(X)[LOG_M], abs(np.angle(p.condition.multiplier_at(p, X))))) or {}
        branch = C.continuation(curve, record=record, settings=C.ContinuationSettings(
            ds=0.02, ds_max=0.2, max_steps=steps, direction=direction,
            compute_eigenvalues=False))
        m, angle = max(angles, key=lambda a: a[1])
        print(f"NS curve from M* = {mstar:g}, U* = {ns.ustar:.4f} (pair at "
              f"{ns.critical_multiplier:.4f}), direction {direction:+d}: {len(angles)} points "
              f"to M* = {angles[-1][0]:.4f}, largest angle {angle / np.pi:.5f} pi at "
              f"M* = {m:.4f} ({branch.status})", flush=True)


def off_centre(modes: int, mstar: float, offset: float, ustar_max: float, checks: int,
               refine_ntst: int):
    base = Scene(mstar=mstar, zeta=0.01, modes=modes, contact_eps=1e-2,
                 channel1=Profile.constant(0.05 * (1 + offset)),
                 channel2=Profile.constant(0.05 * (1 - offset)))
    t0 = time.perf_counter()
    scene, model, br = impacting(base, ustar_max, 40, refine_ntst)
    pds = [p for p in br.special if p.kind == "pd" and p.located]
    print(f"walls off centre by {offset:g} (M* = {mstar:g}, N = {modes}): {len(br.points)} "
          f"points, {time.perf_counter() - t0:.0f} s; special: "
          + ", ".join(f"{p.kind} {p.ustar:.6f}" for p in br.special))
    if not pds:
        print("no period doubling below --ustar-max")
        return
    pd = pds[0]
    print(f"period doubling at U* = {pd.ustar:.6f}, T1 = {pd.period:.6f}, multiplier "
          f"{pd.critical_multiplier.real:.10f} (NTST = {pd.ntst}), contact intervals "
          f"{pd.impacts}")
    t0 = time.perf_counter()
    db = period_doubled_branch(scene, pd, model=model, ustar_max=ustar_max,
                               settings=CollocationImpactSettings(ntst=200, max_points=25,
                                                                  ds=0.05))
    print(f"doubled branch: {len(db.points)} points, {time.perf_counter() - t0:.0f} s, "
          f"T/(2 T1) at its first point {db.points[0].period / (2 * pd.period):.6f}, "
          f"stable: {sum(p.stable for p in db.points)} of {len(db.points)}")
    print("| U* | T | contacts | stable | integration: status, swings | T | A | peak force |")
    print("|---|---|---|---|---|---|---|---|")
    for p in db.points[::-max(1, len(db.points) // checks)][:checks]:
        r = settled_cycle(model, scene.replace(ustar=p.ustar), p.state, p.period)
        print(f"| {p.ustar:.5f} | {p.period:.6f} | {p.impacts} | {p.stable} | {r.status}, "
              f"{r.swings} | {abs(r.period / p.period - 1):.1e} | "
              f"{abs(r.tip_amplitude / p.tip_amplitude - 1):.1e} | "
              f"{abs(r.peak_force / p.peak_force - 1):.1e} |", flush=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, default=4)
    ap.add_argument("--scan", type=float, nargs="*", default=[],
                    help="M* values of the symmetric scan (none: skip)")
    ap.add_argument("--scan-ustar-max", type=float, default=12.0)
    ap.add_argument("--ns-curve", type=float, default=None, metavar="MSTAR")
    ap.add_argument("--ns-steps", type=int, default=12)
    ap.add_argument("--offset", type=float, default=0.02)
    ap.add_argument("--mstar", type=float, default=0.287)
    ap.add_argument("--ustar-max", type=float, default=9.25)
    ap.add_argument("--checks", type=int, default=3)
    ap.add_argument("--refine-ntst", type=int, default=0,
                    help="locate the special cycles once more on this many intervals")
    args = ap.parse_args(argv)
    if args.scan:
        scan(args.modes, args.scan, args.scan_ustar_max)
    if args.ns_curve is not None:
        ns_curve(args.modes, args.ns_curve, args.scan_ustar_max, args.ns_steps)
    if args.offset:
        off_centre(args.modes, args.mstar, args.offset, args.ustar_max, args.checks,
                   args.refine_ntst)


if __name__ == "__main__":
    main()
