"""Linear stability: run time against error for N in {10, 20, 40}.

Rows: one eigen-analysis (steady state + generalized eigenproblem) at M* = 1, U* = 5,
error of the flutter eigenvalue (the pair near 45.6i);
one critical velocity (Hopf location through continuation) at M* = 1; the full flutter
boundary over M* in [0.01, 100] (``--points`` log-spaced values, refined, with all mode
switches). Errors are against a converged reference (N = 60 for the first two; the
largest N run for the boundary, median and max over the points).

    python benchmarks/bench_stability.py [--modes 10 20 40] [--points 41] [--ref-modes 60]
"""
from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from fsicas import Scene, build_model, steady_state
from fsicas.linear.boundary import stability_boundary
from fsicas.linear.hopf import critical_velocity
from fsicas.linear.stability import eigenvalues


def timed(fn, repeat=1):
    best, out = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def flutter_eigenvalue(scene, model, near):
    """The eigenvalue nearest ``near`` (the flutter mode; with zeta = 0 the largest real
    part can belong to a lightly damped high mode that differs between N)."""
    lam = eigenvalues(model, steady_state(scene, model))
    return lam[np.argmin(np.abs(lam - near))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", type=int, nargs="+", default=[10, 20, 40])
    parser.add_argument("--points", type=int, default=41)
    parser.add_argument("--ref-modes", type=int, default=60)
    args = parser.parse_args()
    base = Scene(mstar=1.0, ustar=5.0)
    ref_scene = base.replace(modes=args.ref_modes)
    ref_model = build_model(ref_scene)
    ref_lam = flutter_eigenvalue(ref_scene, ref_model, 45.6j)
    ref_hopf = critical_velocity(ref_scene, ref_model, ustar_max=8.0)
    mstars = np.logspace(-2, 2, args.points)
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    print("| N | build s | eig s | eig rel. err | U*_c s (1st / cached) | U*_c rel. err | "
          "omega rel. err | boundary s | points | switches |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    boundaries = {}
    for n in args.modes:
        scene = base.replace(modes=n)
        t_build, model = timed(lambda: build_model(scene))
        t_eig, lam = timed(lambda: flutter_eigenvalue(scene, model, ref_lam), repeat=5)
        t_hopf1, hopf = timed(lambda: critical_velocity(scene, model, ustar_max=8.0))
        t_hopf2, _ = timed(lambda: critical_velocity(scene.replace(mstar=1.1), model, ustar_max=8.0))
        t_bound, boundaries[n] = timed(lambda: stability_boundary(scene, mstars, model))
        b = boundaries[n]
        print(f"| {n} | {t_build:.3f} | {t_eig:.4f} | {abs(lam - ref_lam) / abs(ref_lam):.1e} | "
              f"{t_hopf1:.2f} / {t_hopf2:.2f} | {abs(hopf.ustar - ref_hopf.ustar) / ref_hopf.ustar:.1e} | "
              f"{abs(hopf.omega - ref_hopf.omega) / ref_hopf.omega:.1e} | {t_bound:.1f} | "
              f"{len(b.points)} | {len(b.switches)} |")
    finest = boundaries[max(args.modes)]
    print("\nboundary U*_c error against N =", max(args.modes), "(same M* values; points on the "
          "same branch only):")
    for n, b in boundaries.items():
        if b is finest:
            continue
        err = [abs(p.ustar_crit - q.ustar_crit) / q.ustar_crit
               for p, q in zip(b.points, finest.points)
               if p.ustar_crit and q.ustar_crit and p.dominant_mode == q.dominant_mode]
        print(f"  N = {n}: median {np.median(err):.1e}, max {np.max(err):.1e} over {len(err)} points")


if __name__ == "__main__":
    main()
