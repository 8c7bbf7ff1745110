"""Symmetry breaking of the impacting cycles in the symmetric channel, and the period
doublings it opens.

    python benchmarks/experiments/symmetry_breaking.py [--modes 10] [--mstar 1] [--ustar-max 7.6]
        [--points 60] [--checks 3] [--doubled] [--refine-ntst 0] [--out runs/symmetry]

k* = 1e8, eps/H = 1e-2, smoothing 0.1, zeta = 0.01, NTST = 200. The period-1 impacting
branch from the first contact (``impacting_cycles``) to ``--ustar-max``, its
branch points ("bp": a real multiplier through +1 where the branch does not turn), the
branch of asymmetric cycles from the first (``symmetry_broken_branch``, ``--points``
points) with its special cycles (located again on ``--refine-ntst`` intervals where
given; the switched branches run on the branch's NTST), with ``--doubled`` the branch of
twice the period from each of its period doublings (``period_doubled_branch``), and at
``--checks`` of the stable cycles of each a time integration (``settled_cycle``, IDAS
1e-10, 30 periods: period, amplitude, peak force against the cycle's) and the distance,
half a period on,
from the state's mirror image R x = (-r, -r', Q2, Q1) (zero for a symmetric cycle).
Branches are saved to ``--out`` (JSON) and read back on a rerun.
"""
from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # before NumPy: docs/continuation.md

from fsicas import Scene  # noqa: E402
from fsicas.cycles import (CollocatedImpactBranch, CollocationImpactSettings,  # noqa: E402
                           impacting_cycles, period_doubled_branch,
                           symmetry_broken_branch)
from fsicas.model import build_model  # noqa: E402
from fsicas.timedomain.settled import mirror_distance, settled_cycle  # noqa: E402

IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)


def computed(path: Path, compute) -> CollocatedImpactBranch:
    """The branch saved at ``path``, else ``compute()`` saved there; prints its cost."""
    if path.exists():
        return CollocatedImpactBranch.load(path)
    t0 = time.perf_counter()
    branch = compute()
    branch.save(path)
    print(f"{path.name}: {len(branch.points)} points in {time.perf_counter() - t0:.0f} s, "
          f"{branch.status}")
    return branch


#: the multiplier each kind of special cycle puts on the unit circle (None: |mu| = 1)
TARGET = {"fold": 1.0, "bp": 1.0, "pd": -1.0, "ns": None}


def specials(name, branch) -> None:
    for p in branch.special:
        m, target = p.critical_multiplier, TARGET[p.kind]
        off = abs(abs(m) - 1) if target is None else abs(m - target)
        print(f"  {name}: {p.kind} at U* = {p.ustar:.6f}, critical multiplier "
              f"{m:.6f} ({off:.1e} off, flow defect {p.flow_defect:.1e}, NTST = {p.ntst}, "
              f"NCOL = {p.ncol}; located by Newton: {p.located})")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, default=10)
    ap.add_argument("--mstar", type=float, default=1.0)
    ap.add_argument("--ustar-max", type=float, default=7.6)
    ap.add_argument("--points", type=int, default=60)
    ap.add_argument("--checks", type=int, default=3)
    ap.add_argument("--doubled", action="store_true")
    ap.add_argument("--refine-ntst", type=int, default=0,
                    help="locate the special cycles again on this many intervals")
    ap.add_argument("--out", default="runs/symmetry")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    tag = f"N{args.modes}_M{args.mstar:g}" + (f"_R{args.refine_ntst}" if args.refine_ntst else "")
    scene = Scene(mstar=args.mstar, zeta=0.01, modes=args.modes, **IMPACT)
    settings = CollocationImpactSettings(ntst=200, max_points=400, ds=0.05, max_turn=0.3,
                                         refine_ntst=args.refine_ntst)
    model = build_model(scene)                    # independent of U*: one build
    main_branch = computed(out / f"symmetric_{tag}.json", lambda: impacting_cycles(
        scene, model=model, ustar_max=args.ustar_max, settings=settings))
    specials("symmetric", main_branch)
    bps = [p for p in main_branch.special if p.kind == "bp"]
    if not bps:
        print("no branch point below --ustar-max")
        return
    broken = computed(out / f"asymmetric_{tag}.json", lambda: symmetry_broken_branch(
        main_branch.scene, bps[0], model=model, ustar_min=0.0, ustar_max=args.ustar_max,
        settings=replace(settings, max_points=args.points)))
    specials("asymmetric", broken)
    checks(broken, model, args.checks)
    if not args.doubled:
        return
    doublings = {round(p.ustar, 4): p for p in broken.special if p.kind == "pd"}
    for u, pd in sorted(doublings.items()):
        doubled = computed(out / f"doubled_{tag}_U{u:g}.json", lambda: period_doubled_branch(
            broken.scene, pd, model=model, ustar_min=0.0, ustar_max=args.ustar_max,
            settings=replace(settings, max_points=40)))
        specials(f"doubled at U* = {u:g}", doubled)
        checks(doubled, model, args.checks)


def checks(branch, model, count) -> None:
    """Time integration from ``count`` of the branch's stable cycles (a table)."""
    scene = branch.scene
    stable = [p for p in branch.points if p.stable]
    print(f"{len(stable)} of {len(branch.points)} cycles stable")
    print("| U* | T | against integration (T, A, peak force) | swings | mirror distance |")
    print("|---|---|---|---|---|")
    for p in stable[::max(1, len(stable) // max(count, 1))][:count]:
        run = settled_cycle(model, scene.replace(ustar=p.ustar), p.state, p.period)
        rel = lambda a, b: abs(a / b - 1) if b else float("nan")  # noqa: E731
        print(f"| {p.ustar:.6f} | {p.period:.7f} | {rel(run.period, p.period):.1e}, "
              f"{rel(run.tip_amplitude, p.tip_amplitude):.1e}, "
              f"{rel(run.peak_force, p.peak_force):.1e} ({run.status}) | {run.swings} | "
              f"{mirror_distance(model, scene.replace(ustar=p.ustar), p.state, p.period):.1e}"
              " |", flush=True)

if __name__ == "__main__":
    main()
