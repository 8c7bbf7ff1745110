"""Cost of the palate design tools against the onset they differentiate.

Per N (the soft_palate preset): the time of one onset (``critical_velocity`` on a built
model), of its sensitivities on top of it (``onset_sensitivity``: the exact derivatives
by the implicit-function solve on the Hopf system, and the channel heights' by two
relocated onsets per height on rebuilt models), of the whole ``palate_sensitivity``
(build included), and of a design
query (``design_for_flow``, gap to 10 L/min: its onset evaluations and the time per
evaluation). Medians of ``--repeats`` runs, the parts interleaved.

    python3 benchmarks/bench_design.py [--modes 6 10 20] [--repeats 3]

A few minutes on one core.
"""
from __future__ import annotations

import argparse
import os
import time
import warnings

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import fsicas  # noqa: E402
from fsicas.linear.sensitivity import onset_sensitivity  # noqa: E402


def timed(fun):
    t0 = time.perf_counter()
    out = fun()
    return time.perf_counter() - t0, out


def row(modes: int, repeats: int) -> dict:
    palate = fsicas.load_physical("soft_palate")
    scene = palate.scene(None, modes=modes)
    model = fsicas.build_model(scene)
    hopf = fsicas.critical_velocity(scene, model)
    t = {k: [] for k in ("onset", "derivatives", "sensitivity", "design")}
    evaluations = 0
    for _ in range(repeats):
        t["onset"].append(timed(lambda: fsicas.critical_velocity(scene, model))[0])
        t["derivatives"].append(timed(lambda: onset_sensitivity(scene, model, hopf))[0])
        t["sensitivity"].append(timed(lambda: fsicas.palate_sensitivity(palate, modes=modes))[0])
        dt, d = timed(lambda: fsicas.design_for_flow(palate, fsicas.parse_flow("10L/min"), "gap",
                                                     modes=modes))
        t["design"].append(dt)
        evaluations = d.evaluations
    out = {k: float(np.median(v)) for k, v in t.items()}
    out["evaluations"] = evaluations
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs="*", default=[6, 10, 20])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    print(f"load average {os.getloadavg()[0]:.1f} ({os.cpu_count()} cores)")
    print("| N | onset [ms] | onset_sensitivity [ms] | "
          "palate_sensitivity [s] | design query [s] | evaluations | per evaluation [ms] |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for modes in args.modes:
        r = row(modes, args.repeats)
        print(f"| {modes} | {1e3 * r['onset']:.1f} | {1e3 * r['derivatives']:.0f} | "
              f"{r['sensitivity']:.2f} | {r['design']:.2f} | "
              f"{r['evaluations']} | {1e3 * r['design'] / max(r['evaluations'], 1):.0f} |",
              flush=True)


if __name__ == "__main__":
    main()
