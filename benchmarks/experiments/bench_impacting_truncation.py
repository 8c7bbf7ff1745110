"""Modal truncation of the paper's impacting points (1a-c, Figs. 6-9): N against N.

Each row is one :func:`fsicas.timedomain.impacting_run.impacting_run` with the main job's
settings (M* = 1, ζ = 0.01, H* = 1/10, k* = 1e8, eps/H = 1e-2, t_end = 4 without an early
stop, settled to 2e-2, the quadrature controlled to its default) at U* and N modes.
Printed per run: outcome and status, period (the mean return time when not periodic),
peak impact force / F0, impacts per cycle, the least gap over the measured cycles / eps
(the impact load's exact rule, :func:`fsicas.model.patch.penetration`), mean flow-rate
reduction, convergence (how closely the last 4 cycles agree), the run's quadrature error
estimate and nodes, t reached and wall time. Then, per U*, the relative differences of
period, peak force and flow reduction between successive N (relative to the larger N).

    python3 benchmarks/experiments/bench_impacting_truncation.py [--ustar 7 8.5 10] [--modes 10 20 40] [--jsonl rows.jsonl]
    python3 benchmarks/experiments/bench_impacting_truncation.py --table rows.jsonl   # the saved rows

One run per (U*, N), in this process, one after another (N = 40 takes minutes).
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

from fsicas.model.patch import penetration
from fsicas.timedomain.impacting_run import impacting_run


def min_gap_ratio(run) -> float:
    """The least gap over the run's measured cycles (its last 4 periods, else its last
    quarter) in units of eps: ``1 - max depth / eps``."""
    t, period = run.trajectory.t, run.outcome.period
    span = 4 * period if period else (t[-1] - t[0]) / 4
    last = t >= t[-1] - span
    depth = penetration(run.model, run.trajectory.x[last], run.steady.p).depth
    return float(1 - depth.max() / run.scene.contact_gap)


def measure(ustar: float, modes: int) -> dict:
    """One row of the table."""
    start = time.perf_counter()
    run = impacting_run(ustar, modes)
    seconds = time.perf_counter() - start
    j = run.to_json()
    return {"ustar": ustar, "modes": modes, "outcome": j["outcome"], "status": run.status,
            "period": j["period"], "peak_force": j["max_impact_force"],
            "impacts": j["impacts_per_cycle"], "min_gap": min_gap_ratio(run),
            "flow": j["mean_flow_reduction"], "convergence": j["convergence"],
            "quadrature_error": j["quadrature_error"], "nodes": j["quadrature_nodes"],
            "t_reached": j["t_end_reached"], "seconds": seconds}


def _g(value, fmt: str) -> str:
    return "-" if value is None or (isinstance(value, float) and not np.isfinite(value)) \
        else format(value, fmt)


def print_row(r: dict) -> None:
    print(f"| {r['ustar']:g} | {r['modes']} | {r['outcome']} | {r['status']} | "
          f"{_g(r['period'], '.6f')} | {_g(r['peak_force'], ',.0f')} | {_g(r['impacts'], 'g')} | "
          f"{_g(r['min_gap'], '.3f')} | {_g(r['flow'], '.4f')} | {_g(r['convergence'], '.2g')} | "
          f"{r['quadrature_error']:.1e} ({r['nodes']}) | {r['t_reached']:.3f} | "
          f"{r['seconds']:.0f} |", flush=True)


def print_differences(rows: list[dict]) -> None:
    """Per U*, |X_a - X_b| / |X_b| of period, peak force and flow reduction for
    successive N (a < b)."""
    print("\n| U* | N vs N' | period | peak force | flow reduction |")
    print("| --- | --- | --- | --- | --- |")
    for ustar in dict.fromkeys(r["ustar"] for r in rows):
        same = sorted((r for r in rows if r["ustar"] == ustar), key=lambda r: r["modes"])
        for a, b in zip(same, same[1:]):
            cells = [_g(abs(a[k] - b[k]) / abs(b[k]), ".1e") if a[k] and b[k] else "-"
                     for k in ("period", "peak_force", "flow")]
            print(f"| {ustar:g} | {a['modes']} vs {b['modes']} | {' | '.join(cells)} |")


def print_header() -> None:
    print("| U* | N | outcome | status | period | peak force / F0 | impacts "
          "per cycle | min gap / eps | flow reduction | convergence | quadrature error "
          "(nodes) | t reached | time [s] |")
    print("|" + " --- |" * 13)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ustar", type=float, nargs="+", default=[7.0, 8.5, 10.0])
    parser.add_argument("--modes", type=int, nargs="+", default=[10, 20, 40])
    parser.add_argument("--jsonl", default=None, help="also append each row to this file")
    parser.add_argument("--table", default=None, metavar="JSONL",
                        help="print the table of the rows saved in this file, run nothing")
    args = parser.parse_args(argv)
    print_header()
    if args.table:
        with open(args.table) as f:
            rows = sorted((json.loads(line) for line in f), key=lambda r: (r["ustar"], r["modes"]))
        for r in rows:
            print_row(r)
        return print_differences(rows)
    rows = []
    for ustar in args.ustar:
        for modes in args.modes:
            rows.append(measure(ustar, modes))
            print_row(rows[-1])
            if args.jsonl:
                with open(args.jsonl, "a") as f:
                    f.write(json.dumps(rows[-1]) + "\n")
    print_differences(rows)


if __name__ == "__main__":
    main()
