"""CLI command ``fsicas paper``: the main job (:func:`fsicas.paper.run_paper`)."""
from __future__ import annotations

import sys
import time

from ..paper import run_paper, summary

__all__ = ["add_paper_command"]


def add_paper_command(sub) -> None:
    """Add the ``paper`` subcommand."""
    p = sub.add_parser("paper", help="reproduce the paper's core results on the embedded default")
    p.add_argument("--out", default="results", help="folder for the report and figures")
    p.add_argument("--quick", action="store_true", help="coarser grids (for a smoke test)")
    p.add_argument("--json", action="store_true")
    p.set_defaults(run=_cmd_paper)


def _cmd_paper(args) -> dict:
    """The main job: the paper's core numbers on its embedded default configuration."""
    start = time.perf_counter()

    def progress(text: str) -> None:     # on stderr: stdout holds the result (or JSON)
        print(f"fsicas paper [{time.perf_counter() - start:6.1f} s] {text}", file=sys.stderr,
              flush=True)
    report = run_paper(out=args.out, quick=args.quick, progress=progress)
    return report if args.json else {**summary(report), "written to": args.out}
