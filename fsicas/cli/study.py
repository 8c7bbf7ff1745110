"""CLI command ``fsicas study STUDY.toml``: one analysis over a grid or a random sample
of parameters (:mod:`fsicas.studies`, docs/studies.md) on local processes or a Dask
scheduler, saved as it goes (``NAME.jsonl`` beside the table) and resumed by running the
same command again; the table is ``--out`` (``.csv`` or ``.parquet``).
"""
from __future__ import annotations

from pathlib import Path

from ..studies import check_table_path, load_study, run_study, summarize
from ..workers import OVERSUBSCRIBE_HELP, check_workers, dask_executor
from .meta import cli_meta, record
from .progress import reporter

__all__ = ["add_study_command"]


def add_study_command(sub) -> None:
    """Add the ``study`` subcommand."""
    p = sub.add_parser("study", help="one analysis (onset, outcome, sound) over a grid or a random "
                       "sample of scene or physical parameters, resumable, as one table")
    p.add_argument("study", metavar="STUDY.toml", help="the study (docs/studies.md)")
    p.add_argument("--out", metavar="TABLE", help="the table, .csv or .parquet (default: "
                   "beside the study file, NAME.csv); its results file NAME.jsonl beside it")
    p.add_argument("--workers", type=int, default=None,
                   help="local processes (default: the cores)")
    p.add_argument("--oversubscribe", action="store_true", help=OVERSUBSCRIBE_HELP)
    p.add_argument("--dask", metavar="ADDRESS", help="run the points on a Dask scheduler "
                   "(tcp://host:8786; needs the 'parallel' extra)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(run=_cmd_study, human=_print_study)


def _cmd_study(args) -> dict:
    check_workers(args.workers, args.oversubscribe)
    study = load_study(args.study)
    table = check_table_path(args.out or Path(args.study).with_suffix(".csv"))
    record(args, None, analysis=study.analysis, points=len(study.points),
           settings=study.settings)
    progress = reporter(args)
    if args.dask:
        with dask_executor(args.dask) as executor:
            rows = run_study(study, table, executor=executor, progress=progress.bars)
    else:
        rows = run_study(study, table, workers=args.workers, progress=progress.bars)
    errors = sum(1 for r in rows if r["error"])
    return {"study": study.to_json(), "table": str(table), "rows": len(rows),
            "errors": errors, "summary": summarize(rows), "meta": cli_meta(args)}


def _print_study(result: dict) -> None:
    s = result["study"]
    print(f"{s['source']}: {s['description']}" if s["description"] else s["source"])
    print(f"  {result['rows']} points of the {s['analysis']} analysis in {result['table']}"
          + (f" ({result['errors']} could not be computed: see their 'error' column)"
             if result["errors"] else ""))
    _print_summary(result["summary"])


def _print_summary(summary: dict) -> None:
    """Each numeric column: its median, 5 %-95 % spread and extremes; each text column's
    values with their counts."""
    numeric = {k: c for k, c in summary["columns"].items() if "median" in c}
    if numeric:
        width = max(map(len, numeric))
        print(f"  {'':{width}}  {'median':>11}  {'5 % - 95 %':>25}  {'min - max':>25}")
    for name, c in numeric.items():
        print(f"  {name:{width}}  {c['median']:11.4g}  {c['p05']:11.4g} - {c['p95']:<11.4g}"
              f"  {c['min']:11.4g} - {c['max']:<11.4g}".rstrip())
    for name, c in summary["columns"].items():
        if "values" in c:
            print(f"  {name}: " + ", ".join(f"{k} {n}" for k, n in c["values"].items()))
