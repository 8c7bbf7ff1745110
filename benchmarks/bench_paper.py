"""Wall time of the main job, ``fsicas paper``, stage by stage.

Runs ``python3 -m fsicas paper --out DIR`` (``--quick`` with ``--quick``) in a fresh
process, in a temporary folder unless ``--out`` is given, and stamps each line the job
writes on stderr (the stage lines: the boundary of Figs. 2-3, its variants, the Fig. 4
map and curves, each impacting cycle of Figs. 6-9). Prints a Markdown table: each
stage line and the minutes from it to the next, then the total, with the machine's core
count and load average before and after. The job itself uses 2 worker processes for
the map, the curves and the cycles: run it on 2 otherwise idle cores. About 15
minutes.

    python3 benchmarks/bench_paper.py [--quick] [--out results]
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time

from common import machine


def stages(argv: list[str]) -> tuple[list[tuple[float, str]], float, int]:
    """``([(seconds since start, stderr line)], total seconds, exit status)``."""
    start = time.perf_counter()
    lines = []
    with subprocess.Popen([sys.executable, "-m", "fsicas", *argv], stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True) as job:
        for line in job.stderr:
            lines.append((time.perf_counter() - start, line.strip()))
            print(f"{lines[-1][0]:8.1f} s  {lines[-1][1]}", file=sys.stderr, flush=True)
    return lines, time.perf_counter() - start, job.returncode


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fsicas paper --quick")
    ap.add_argument("--out", default=None, help="keep the results there")
    args = ap.parse_args(argv)
    print(f"before: {machine()}")
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or tmp
        lines, total, status = stages(["paper", "--out", out] + (["--quick"] if args.quick
                                                                 else []))
    print("\n| stage (its line on stderr) | minutes |\n| --- | --- |")
    ends = [t for t, _ in lines[1:]] + [total]
    for (t, text), end in zip(lines, ends):
        print(f"| {text} | {(end - t) / 60:.1f} |")
    print(f"| total (exit status {status}) | {total / 60:.1f} |")
    print(f"\nafter: {machine()}")


if __name__ == "__main__":
    main()
