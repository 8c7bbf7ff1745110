"""Where the time of a continuation point goes: model kernels, linear algebra, the rest.

Each workload continues a branch for ``--points`` points after a warm-up run (which
builds the systems) and times, by wrapping the functions
(``time.perf_counter``; a call inside an already timed one is not counted twice):

* **model kernels**: every CasADi call of the model's functions (``BufferedFunction``:
  the pointwise kernels at the collocation points, the lifted matrices' nonzeros, the
  residuals) and the lifted matrices' dense products (``LiftedBatch``), i.e. what the
  model itself costs at the points the analysis needs;
* **linear algebra**: the condensed solver (interval LUs and maps, the chain's QRs,
  solves, the interval products of the refinement), SuperLU, the Floquet
  condensation of a sparse Jacobian, the monodromy and the eigenvalues of the
  multipliers;
* **rest**: everything else (assembly of the Jacobian from the pointwise matrices,
  Newton/PALC bookkeeping, detection, measures, Python).

Workloads: ``brusselator:n`` (the chain of ``bench_cycles.py``, n states, NTST = 50,
bare step iterator plus multipliers), ``cycle:N`` (``fsicas.cycles.cycle_branch`` of
the flutter model, M* = 1, N modes, its defaults), ``impacting:N`` (the impacting
collocation branch at M* = 1 from the last contact-free cycle 3 eps from the wall,
k* = 1e8, eps/H = 1e-2, smoothing 0.1, NTST = 200, re-meshed at every point).

    python benchmarks/point_anatomy.py [--points 20] brusselator:4 cycle:10 impacting:10
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from collections import Counter
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # before NumPy: docs/continuation.md

sys.path.insert(0, str(Path(__file__).resolve().parent))

#: (module, attribute, category) of the timed functions
TIMED = [
    ("continuation._casadi.symbolic", "BufferedFunction.__call__", "kernels"),
    ("continuation._casadi.lifted", "LiftedBatch.__call__", "kernels"),
    ("continuation._linalg.stacks", "StackLU.of", "algebra"),
    ("continuation._linalg.stacks", "StackLU.solve", "algebra"),
    ("continuation._linalg.stacks", "BandStackLU.of", "algebra"),
    ("continuation._linalg.stacks", "BandStackLU.solve", "algebra"),
    ("continuation._cycles.intervals", "KinematicLU.of", "algebra"),
    ("continuation._cycles.intervals", "KinematicLU.solve", "algebra"),
    ("continuation._cycles.chain", "Chain.of", "algebra"),
    ("continuation._cycles.chain", "Chain.bordered", "algebra"),
    ("continuation._cycles.chain", "Chain.solve", "algebra"),
    ("continuation._cycles.condensed", "CollocationJacobian.collocation_times", "algebra"),
    ("scipy.sparse.linalg", "splu", "algebra"),
    ("continuation._driver.newton", "LU.solve", "algebra"),
    ("continuation._cycles.floquet", "transfer_matrices", "algebra"),
    ("continuation._cycles.floquet", "monodromy", "algebra"),
    ("numpy.linalg", "eigvals", "algebra"),
]


class Anatomy:
    """Wraps the :data:`TIMED` functions while in a ``with`` block; ``totals`` (s) per
    category, outermost calls only."""

    def __init__(self):
        self.totals, self._depth, self._saved = Counter(), 0, []

    def __enter__(self):
        import importlib
        for module, attr, category in TIMED:
            owner = importlib.import_module(module)
            *path, name = attr.split(".")
            for part in path:
                owner = getattr(owner, part)
            fun = getattr(owner, name)
            self._saved.append((owner, name, fun))
            setattr(owner, name, self._timed(fun, category))
        return self

    def __exit__(self, *exc):
        for owner, name, fun in reversed(self._saved):
            setattr(owner, name, fun)

    def _timed(self, fun, category):
        def call(*args, **kw):
            if self._depth:
                return fun(*args, **kw)
            self._depth += 1
            t0 = time.perf_counter()
            try:
                return fun(*args, **kw)
            finally:
                self.totals[category] += time.perf_counter() - t0
                self._depth -= 1
        return call


def brusselator(n: int, points: int):
    """``run(points)``: that many steps of the bench_cycles chain (continuing)."""
    from bench_cycles import hopf_start, stepper
    cyc, it = stepper(*hopf_start(n))
    state = {"step": it.start()}

    def run(k):
        for _ in range(k):
            state["step"] = it.advance(state["step"])
            cyc.multipliers(state["step"].X)
        return k
    return run


def cycle(N: int, points: int):
    from fsicas import Scene, build_model
    from fsicas.cycles import CycleSettings, cycle_branch
    from fsicas.linear.hopf import critical_velocity
    scene = Scene(mstar=1.0, modes=N)
    model = build_model(scene)
    hopf = critical_velocity(scene, model)
    return lambda k: len(cycle_branch(scene, model, hopf=hopf,
                                      settings=CycleSettings(max_points=k)).points)


def impacting(N: int, points: int):
    from fsicas import Scene, build_model
    from fsicas.cycles import CollocationImpactSettings, cycle_branch, impacting_cycles
    from fsicas.cycles.impacting import pre_contact_start
    scene = Scene(mstar=1.0, zeta=0.01, modes=N, contact=True, contact_stiffness=1e8,
                  contact_eps=1e-2, contact_smoothing=0.1)
    model = build_model(scene)
    start = pre_contact_start(cycle_branch(scene.replace(contact=False), ustar_max=12), 3.0)
    return lambda k: len(impacting_cycles(
        scene.replace(ustar=start.ustar), start, model=model, ustar_max=12,
        settings=CollocationImpactSettings(max_points=k)).points)


WORKLOADS = {"brusselator": brusselator, "cycle": cycle, "impacting": impacting}


def measure(spec: str, points: int) -> str:
    """One Markdown row: ms per point and the shares of the three categories."""
    kind, size = spec.split(":")
    run = WORKLOADS[kind](int(size), points)
    run(3)                                               # warm-up: build, load, compile
    with Anatomy() as anatomy:
        t0 = time.perf_counter()
        done = run(points)
        total = time.perf_counter() - t0
    k, a = anatomy.totals["kernels"] / total, anatomy.totals["algebra"] / total
    return (f"| {kind} | {size} | {done} | {1e3 * total / done:.1f} | {k:.0%} | {a:.0%} | "
            f"{k + a:.0%} | {1 - k - a:.0%} |")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("workloads", nargs="+", help="kind:size, kind in " + ", ".join(WORKLOADS))
    ap.add_argument("--points", type=int, default=20)
    args = ap.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.1f} ({os.cpu_count()} cores)")
    print("| workload | size | points | ms / point | model kernels | linear algebra | "
          "kernels + algebra | rest |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for spec in args.workloads:
        print(measure(spec, args.points), flush=True)


if __name__ == "__main__":
    main()
