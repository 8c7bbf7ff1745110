"""Which contact law holds the beam: the smallest penalty stiffness k* per case.

For the paper's impacting cases (M* = 1, ζ = 0.01; U* = 7, 8.5, 10) and eps/H in
{1e-3, 1e-2}, a time integration from the perturbed steady state over ``--t-end`` (the
runs of Figs. 6-9: ``fsicas.timedomain.impacting_run``) either keeps every gap open
(the law holds the beam) or fails with a closed gap (h_c <= 0: the flow model is singular
there). The threshold is bracketed in log10 k* by bisection between 1e5 and 1e9 (a law
that holds at k* also holds above it, checked at the bracket's ends); then the period,
impacts per cycle and peak impact force of the runs at the held bracket end times 1, 10
and 100 show how the settled motion depends on k* above the threshold. The paper's
own law (k* = 1e6, eps/H = 1e-3) is reported against it.

    python benchmarks/experiments/contact_thresholds.py [--modes 10 20] [--steps 4] [--workers 2]
        [--out thresholds.jsonl]

Each finished cell is appended to ``--out`` (one JSON line) as soon as it is done, and a
rerun with the same file computes only the cells not in it (same steps and t_end).
"""
from __future__ import annotations

import argparse
import json
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from fsicas.timedomain.impacting_run import impacting_run  # noqa: E402

USTARS, EPS = (7.0, 8.5, 10.0), (1e-3, 1e-2)
LOW, HIGH = 5.0, 9.0            # log10 k* bracket


def run(ustar, modes, exponent, eps, t_end) -> dict:
    r = impacting_run(ustar, modes, dict(contact_stiffness=10 ** exponent, contact_eps=eps),
                      t_end=t_end, tol=0.1).to_json()
    return {"holds": r["status"] != "failed", "period": r["period"],
            "impacts": r["impacts_per_cycle"], "force": r["max_impact_force"],
            "outcome": r["outcome"], "settled": r["settled"]}


def threshold(job) -> dict:
    """The bracket ``(failed, held)`` of log10 k* and the runs above it."""
    ustar, modes, eps, steps, t_end = job
    low, high = LOW, HIGH
    if not run(ustar, modes, high, eps, t_end)["holds"]:
        return {"ustar": ustar, "modes": modes, "eps": eps, "bracket": (high, None), "above": []}
    if run(ustar, modes, low, eps, t_end)["holds"]:
        high = low = None
    for _ in range(steps if low is not None else 0):
        mid = 0.5 * (low + high)
        low, high = (low, mid) if run(ustar, modes, mid, eps, t_end)["holds"] else (mid, high)
    start = LOW if high is None else high
    above = [{"k": 10 ** (start + d), **run(ustar, modes, start + d, eps, t_end)}
             for d in (0.0, 1.0, 2.0)]
    return {"ustar": ustar, "modes": modes, "eps": eps, "bracket": (low, high), "above": above}


def key(job) -> tuple:
    """A cell's identity in the results file: (U*, N, eps/H, steps, t_end)."""
    return tuple(float(v) for v in job)


def saved(path: Path) -> dict:
    """The cells already in ``path``; a torn last line (a killed run) is cut off first,
    so that the next cell is appended on a line of its own."""
    if not path.exists():
        return {}
    text = path.read_text()
    if text and not text.endswith("\n"):
        text = text[:text.rfind("\n") + 1]
        path.write_text(text)
    return {tuple(d.pop("key")): d for d in map(json.loads, text.splitlines())}


def cell(r) -> str:
    low, high = r["bracket"]
    if high is None and low is not None:
        return f"> 1e{low:g}"
    if high is None:
        return f"<= 1e{LOW:g}"
    return f"1e{low:.2f} - 1e{high:.2f}"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs="*", default=[10])
    ap.add_argument("--steps", type=int, default=4, help="bisection steps (0.25 decade at 4)")
    ap.add_argument("--t-end", type=float, default=4.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="contact_thresholds.jsonl",
                    help="cells saved as they finish; a rerun skips those in it")
    args = ap.parse_args(argv)
    jobs = [(u, n, e, args.steps, args.t_end) for n in args.modes for e in EPS for u in USTARS]
    done = saved(Path(args.out))
    with ProcessPoolExecutor(args.workers) as pool, open(args.out, "a") as out:
        futures = {pool.submit(threshold, job): job for job in jobs if key(job) not in done}
        for future in as_completed(futures):
            done[key(futures[future])] = result = future.result()
            out.write(json.dumps({"key": list(key(futures[future])), **result}) + "\n")
            out.flush()
    results = [done[key(job)] for job in jobs]
    print(f"{'N':>3} {'eps/H':>6} {'U*':>5}  {'k* threshold (fails - holds)':30} "
          f"k*: period, impacts/cycle, peak force/F0, outcome")
    for r in results:
        above = "; ".join(f"{a['k']:.0e}: {a['period'] or float('nan'):.5f}, {a['impacts']}, "
                          f"{a['force'] or 0:.3g}, {a['outcome']}" for a in r["above"])
        print(f"{r['modes']:3d} {r['eps']:6.0e} {r['ustar']:5.1f}  {cell(r):30} {above}")
    paper = [run(u, n, 6.0, 1e-3, args.t_end)["holds"] for n in args.modes for u in USTARS]
    print(f"\nthe paper's law k* = 1e6, eps/H = 1e-3 holds the beam in {sum(paper)} of "
          f"{len(paper)} cases")


if __name__ == "__main__":
    main()
