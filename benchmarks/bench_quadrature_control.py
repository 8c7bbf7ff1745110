"""Quadrature control on the limit-cycle branch: run time against error.

The contact-free cycle branch of M* = 1, ζ = 0.01 (``fsicas.cycles.cycle_branch``, NTST =
20, NCOL = 4) from the Hopf point to the first wall contact, on fixed rules (the default
2N + 20 nodes, 4x and 16x that) and with the control (``CycleSettings.quadrature_tol``,
default 1e-8). The reference is the same branch on a fixed rule of 32x the default
nodes. The mesh is uniform by default (``--adapt-every 0``): every run then solves the
same discrete problem and the differences are the quadrature's alone (re-meshing at
different points of the branch would add mesh differences of ~1e-7).

Printed per run: wall time, branch points, the largest nodes used, and the relative
errors against the reference of the first-contact U* ("not located": the location
failed and the branch point past the contact is reported), of the period at contact, and of
the tip amplitude of the last point before contact (the reference there: that cycle
corrected at the same Π on the reference rule, same uniform mesh; with ``--adapt-every``
> 0 it includes the mesh difference too).

    python3 benchmarks/bench_quadrature_control.py [--modes 10] [--adapt-every 0]

``--impacting U*``: an impacting run instead (M* = 1, ζ = 0.01, k* = 1e8, eps/H = 1e-2,
``impacting_run``'s settings, t_end = 4 without an early stop), on fixed rules of
n = 40 · 2^k nodes (the flow's Gauss–Legendre nodes and the impact load's cell rule
of :mod:`fsicas.model.impact_rule`, which refine together), against the
rule of ``--reference`` nodes: wall time, the run's own ``quadrature_error`` estimate
and the relative errors of the period and of the peak force.

    python3 benchmarks/bench_quadrature_control.py --impacting 7 [--modes 10]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import continuation as C
import fsicas
from fsicas.cycles import CycleSettings, cycle_branch
from fsicas.cycles.gauge import PolynomialExtrema
from fsicas.cycles.impacting_collocation import (CollocationImpactSettings,
                                                 impacting_collocation_problem)
from fsicas.linear.hopf import critical_velocity
from fsicas.model import build_model
from fsicas.model.accuracy import QUADRATURE_TOL


def reference_amplitude(point, model, ntst: int) -> float:
    """Tip half-amplitude of the cycle through ``point`` corrected at its Π on ``model``
    (uniform mesh of ``ntst`` intervals, NCOL = 4)."""
    settings = CollocationImpactSettings(ntst=ntst, ncol=4, mesh_passes=0, adapt_every=0)
    problem = impacting_collocation_problem(model.scene, point.state, point.period,
                                            point.pressure_drop, model=model, settings=settings)
    fixed_pi = np.zeros(problem.X0.size)
    fixed_pi[-1] = 1.0
    X = C.correct(problem, problem.X0, fixed_pi, C.NewtonSettings(tol=1e-10)).X
    low, high = PolynomialExtrema(model).tip(problem, X)
    return (high - low) / 2


def run(scene, quad_nodes, tol, hopf, adapt_every):
    start = time.perf_counter()
    branch = cycle_branch(scene.replace(quad_nodes=quad_nodes), hopf=hopf,
                          settings=CycleSettings(adapt_every=adapt_every, quadrature_tol=tol))
    return branch, time.perf_counter() - start


def impacting(ustar: float, modes: int, nodes: list[int], reference: int) -> None:
    """The impacting table (module docstring)."""
    from fsicas.timedomain.impacting_run import impacting_run

    def once(n):
        start = time.perf_counter()
        run = impacting_run(ustar, modes, quad_nodes=n, quadrature_tol=None)
        return run, time.perf_counter() - start

    ref, _ = once(reference)
    o = ref.outcome
    print(f"U* = {ustar}, N = {modes}; reference {reference} nodes: T = {o.period:.10f}, "
          f"peak force {o.max_impact_force:.6g} F0, {o.impacts_per_cycle} impacts per cycle")
    print("| nodes | contact nodes | time [s] | quadrature_error | period error | "
          "peak-force error | impacts per cycle |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for n in nodes:
        run, seconds = once(n)
        r = run.outcome
        print(f"| {n} | {len(run.model.impact_rule.x)} | {seconds:.1f} | "
              f"{run.quadrature_error:.1e} | {abs(r.period / o.period - 1):.1e} | "
              f"{abs(r.max_impact_force / o.max_impact_force - 1):.1e} | "
              f"{r.impacts_per_cycle} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", type=int, default=10)
    parser.add_argument("--adapt-every", type=int, default=0)
    parser.add_argument("--impacting", type=float, default=None, metavar="USTAR")
    parser.add_argument("--nodes", type=int, nargs="+", default=[40, 80, 160, 320])
    parser.add_argument("--reference", type=int, default=640)
    args = parser.parse_args()
    if args.impacting is not None:
        return impacting(args.impacting, args.modes, args.nodes, args.reference)
    scene = fsicas.Scene(mstar=1.0, zeta=0.01, modes=args.modes)
    n = scene.n_quad
    hopf = critical_velocity(scene, build_model(scene))
    reference_model = build_model(scene.replace(quad_nodes=32 * n))
    reference, _ = run(scene, 32 * n, None, hopf, args.adapt_every)
    rel = lambda a, b: abs(a / b - 1)
    print(f"N = {args.modes}, reference: fixed {32 * n} nodes, first contact at U* = "
          f"{reference.contact.ustar:.10f}; mesh re-equidistributed every "
          f"{args.adapt_every} points (0: uniform)")
    print("| rule | time [s] | points | max nodes | first-contact U* | period at contact "
          "| amplitude before contact (gap/eps) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    rows = [(f"fixed {n} (default)", None, None), (f"fixed {4 * n}", 4 * n, None),
            (f"fixed {16 * n}", 16 * n, None),
            (f"controlled, tol {QUADRATURE_TOL:g}", None, QUADRATURE_TOL)]
    for label, nodes, tol in rows:
        branch, seconds = run(scene, nodes, tol, hopf, args.adapt_every)
        last, c = branch.points[-1], branch.contact
        located = "" if c.located else " (not located)"
        amplitude = rel(last.tip_amplitude,
                        reference_amplitude(last, reference_model, CycleSettings().ntst))
        print(f"| {label} | {seconds:.1f} | {len(branch.points)} | "
              f"{max(*branch.column('quadrature_nodes'), c.quadrature_nodes)} | "
              f"{rel(c.ustar, reference.contact.ustar):.1e}{located} | "
              f"{rel(c.period, reference.contact.period):.1e} | "
              f"{amplitude:.1e} ({last.gap_ratio:.2f}) |")


if __name__ == "__main__":
    main()
