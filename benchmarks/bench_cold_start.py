"""A first run against a later one: `lco`, `simulate` and `onset` with empty caches (cold)
and with the caches a previous run left (warm), alternating in one run.

Each command runs in a new process (``python -m fsicas ... --json``). Cold: fresh,
empty ``FSICAS_CACHE`` and ``CONTINUATION_CACHE`` directories; warm: the directories a
first, untimed run of the same command filled. With ``--compiled``, a third column:
warm with every collocation kernel compiled (``CONTINUATION_BACKEND=compiled``, its
libraries built by the untimed run), what a cache of compiled kernels would gain. Printed: the median wall time of each, and
cold/warm (the median of the pairwise ratios), as a Markdown table.

    python benchmarks/bench_cold_start.py [--repeats 3] [--compiled] [--only lco]

Takes about 6 minutes at 3 repeats on a shared 2-core machine (9 with --compiled).
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

COMMANDS = {
    "lco": ["lco", "--mstar", "1", "--zeta", "0.01"],
    "simulate": ["simulate", "--mstar", "1", "--ustar", "6.5", "--zeta", "0.01",
                 "--t-end", "20"],
    "onset": ["onset"],
}


def run(args: list, cache: Path, label: str, backend: str | None = None) -> float:
    """Wall seconds of ``fsicas ARGS --json`` in a new process with its caches in
    ``cache`` (the command must succeed; the time is printed on stderr with ``label``)."""
    env = {**os.environ, "FSICAS_CACHE": str(cache / "fsicas"),
           "CONTINUATION_CACHE": str(cache / "continuation")}
    env.pop("CONTINUATION_BACKEND", None)
    if backend:
        env["CONTINUATION_BACKEND"] = backend
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "fsicas", *args, "--json"], env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    seconds = time.perf_counter() - start
    print(f"  {args[0]} {label}: {seconds:.1f} s", file=sys.stderr, flush=True)
    if done.returncode != 0:
        raise SystemExit(f"fsicas {' '.join(args)} failed ({done.returncode}):\n"
                         f"{done.stderr[-2000:]}")
    return seconds


def measure(args: list, repeats: int, compiled: bool, root: Path) -> dict:
    """``{"cold": [...], "warm": [...], ("compiled": [...])}`` seconds, alternating."""
    warm, full = root / "warm", root / "compiled"
    run(args, warm, "first")                          # fills the caches
    if compiled:
        run(args, full, "first, compiled", "compiled")
    times = {"cold": [], "warm": [], **({"compiled": []} if compiled else {})}
    for i in range(repeats):
        with tempfile.TemporaryDirectory(dir=root) as fresh:
            times["cold"].append(run(args, Path(fresh), "cold"))
        times["warm"].append(run(args, warm, "warm"))
        if compiled:
            times["compiled"].append(run(args, full, "warm, compiled", "compiled"))
    return times


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--compiled", action="store_true",
                        help="also warm with every collocation kernel compiled")
    parser.add_argument("--only", choices=sorted(COMMANDS), nargs="*")
    opts = parser.parse_args(argv)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load {load:.1f} at start; {opts.repeats} repeats; medians in seconds")
    head = "| command | cold | warm | cold/warm |" + (" warm, compiled |" if opts.compiled
                                                      else "")
    print(head)
    print("|" + " --- |" * (head.count("|") - 1))
    with tempfile.TemporaryDirectory(prefix="cold-start-") as tmp:
        for name in opts.only or COMMANDS:
            root = Path(tmp) / name
            root.mkdir()
            t = measure(COMMANDS[name], opts.repeats, opts.compiled, root)
            ratio = statistics.median(c / w for c, w in zip(t["cold"], t["warm"]))
            row = (f"| `fsicas {' '.join(COMMANDS[name])}` | {statistics.median(t['cold']):.1f}"
                   f" | {statistics.median(t['warm']):.1f} | {ratio:.2f} |")
            if opts.compiled:
                row += f" {statistics.median(t['compiled']):.1f} |"
            print(row, flush=True)


if __name__ == "__main__":
    main()
