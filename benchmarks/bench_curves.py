"""Cost and convergence of the curves of special cycles in (M*, U*) (Fig. 4's scene).

1. Cost per point of a grazing curve (seed M* = 1) and of a fold-of-cycles curve (seed
   M* = 0.6) at N = 10: wall time per curve point.
2. Convergence of the grazing point at M* = 1 (U* of the first contact of the branch,
   which the grazing curve passes through): N = 10 against 20 and NTST = 20 against 40,
   each on quadrature tolerance 1e-8.

    python3 benchmarks/bench_curves.py [--points 20]

A few minutes on one core.
"""
from __future__ import annotations

import argparse
import os
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from fsicas import Scene  # noqa: E402
from fsicas.cycles.collocation import CycleSettings, continue_cycles  # noqa: E402
from fsicas.cycles.curves import CurveSettings, fold_curves, grazing_curve  # noqa: E402

SCENE = Scene(mstar=1.0, modes=10, zeta=0.01)


def curve_cost(kind: str, mstar: float, points: int) -> dict:
    scene = SCENE.replace(mstar=mstar)
    run = continue_cycles(scene, settings=CycleSettings(quadrature_tol=1e-6))
    settings = CurveSettings(mstar_min=mstar / 3, mstar_max=mstar * 3, max_points=points)
    trace = (lambda: grazing_curve(scene, run=run, settings=settings)) if kind == "grazing" \
        else (lambda: fold_curves(scene, run=run, settings=settings)[0])
    t0 = time.perf_counter()
    curve = trace()
    wall = time.perf_counter() - t0
    return {"kind": kind, "points": len(curve.points), "s_per_point": wall / len(curve.points)}


def contact_ustar(modes: int, ntst: int) -> tuple[float, float]:
    t0 = time.perf_counter()
    run = continue_cycles(SCENE.replace(modes=modes), settings=CycleSettings(ntst=ntst))
    (contact,) = run.branch.special("contact")
    return contact.record["ustar"], time.perf_counter() - t0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=20, help="curve points per direction")
    args = ap.parse_args(argv)
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    print(f"{'curve':8} {'points':>6} {'s/point':>8}")
    for kind, mstar in (("grazing", 1.0), ("fold", 0.6)):
        r = curve_cost(kind, mstar, args.points)
        print(f"{kind:8} {r['points']:6d} {r['s_per_point']:8.3f}")
    print("\ngrazing point at M* = 1 (first contact of the branch):")
    ref, t = contact_ustar(10, 20)
    print(f"N = 10, NTST = 20: U* = {ref:.10f}  ({t:.1f} s)")
    for modes, ntst in ((10, 40), (20, 20)):
        u, t = contact_ustar(modes, ntst)
        print(f"N = {modes}, NTST = {ntst}: U* = {u:.10f}  difference {u - ref:+.2e} "
              f"({(u - ref) / ref:+.1e} relative; {t:.1f} s)")


if __name__ == "__main__":
    main()
