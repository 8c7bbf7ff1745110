"""CLI command ``fsicas paper``: the main job (:func:`fsicas.paper.run_paper`)."""
from __future__ import annotations

from ..paper import PAPER_SCENE, run_paper, summary
from .meta import cli_meta, record
from .progress import reporter

__all__ = ["add_paper_command"]


def add_paper_command(sub) -> None:
    """Add the ``paper`` subcommand."""
    p = sub.add_parser("paper", help="reproduce the paper's core results on the embedded default")
    p.add_argument("--out", default="results", help="folder for the report and figures")
    p.add_argument("--quick", action="store_true", help="coarser grids (for a smoke test)")
    p.add_argument("--json", action="store_true", help="print the report as one JSON object")
    p.set_defaults(run=_cmd_paper)


def _cmd_paper(args) -> dict:
    """The main job: the paper's core numbers on its embedded default configuration; its
    stages are announced on stderr (stdout holds the result or JSON) unless ``--quiet``."""
    say = reporter(args)
    record(args, PAPER_SCENE)
    report = run_paper(out=args.out, quick=args.quick, meta=cli_meta(args),
                       progress=lambda text: say.stage(text, always=True))
    return report if args.json else {**summary(report), "written to": args.out}
