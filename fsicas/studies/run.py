"""Run a study on local processes or a Dask cluster, saving as it goes, and write its table.

Every finished point is appended at once to a results file (JSON lines,
:class:`fsicas.results_file.ResultsFile`: locked, a torn line from a kill repaired, a
header that must match, with a digest of all the points), keyed by its index; a rerun
computes only the points that are not there, so a study killed at any moment (SIGKILL
included) resumes without losing, repeating or mixing rows. The table (``.csv`` or ``.parquet``) is written from
the results file at the end, one row per point in the study's order: a plain CSV that
any reader loads (the study's header is the results file's first line), or Parquet with
the header in its schema metadata too.
"""
from __future__ import annotations

import contextlib
import csv
import json
from concurrent.futures import Executor
from pathlib import Path

from tqdm import tqdm

from ..provenance import provenance
from ..results_file import ResultsFile, check_results_path
from ..workers import finished, local_pool
from .analyses import study_point
from .spec import Study

__all__ = ["run_study", "write_table", "check_table_path", "results_path", "TABLE_FORMATS"]

TABLE_FORMATS = (".csv", ".parquet")


def results_path(table: Path) -> Path:
    """The results file (JSON lines) beside a table: ``NAME.jsonl``."""
    return table.with_suffix(".jsonl")


def check_table_path(table) -> Path:
    """The table's path, checked before any work: a known format, a folder that exists."""
    table = Path(table)
    if table.suffix not in TABLE_FORMATS:
        raise ValueError(f"--out {str(table)!r}: the table must end in "
                         f"{' or '.join(TABLE_FORMATS)}")
    if not table.parent.is_dir():
        raise ValueError(f"--out {str(table)!r}: the folder {str(table.parent)!r} does not exist")
    if table.suffix == ".parquet":
        _pyarrow()
    if table.exists() and not _is_table(table):
        raise ValueError(f"--out {str(table)!r}: the file exists and is not a table of a "
                         "fsicas study; it was left as it is: name a new file")
    check_results_path(results_path(table))
    return table


def _is_table(path: Path) -> bool:
    """A regular file that is empty or starts as :func:`write_table` writes it."""
    if not path.is_file():
        return False
    with open(path, "rb") as fh:
        head = fh.read(6)
    return head in (b"", b"PAR1") or head.startswith((b"index", b"# {"))   # (older tables: "# {")


def run_study(study: Study, table, *, workers: int | None = None,
              executor: Executor | None = None, progress: bool | None = None) -> list[dict]:
    """Compute every point of ``study`` not yet in the results file beside ``table``,
    then write ``table``; returns the rows in the study's order. ``workers``: local
    processes (default the cores); ``executor``: any ``concurrent.futures`` executor
    instead (e.g. a Dask ``Client.get_executor()``), used as it is and not shut down.
    ``progress``: a bar on stderr (None: on a terminal only)."""
    table = check_table_path(table)
    with ResultsFile(results_path(table), study.header, provenance(),
                     fields={"index": int}) as out, \
            contextlib.ExitStack() as stack:
        done = {row["index"]: row for row in out.records}
        todo = [i for i in range(len(study.points)) if i not in done]
        if todo and executor is None:
            executor = stack.enter_context(local_pool(workers))
        futures = [executor.submit(study_point, study, i) for i in todo]
        bar = stack.enter_context(tqdm(total=len(study.points), initial=len(done),
                                       desc="study", unit="point", disable=_quiet(progress)))
        for row in finished(futures, out.path):
            out.append(row)
            done[row["index"]] = row
            bar.update()
    rows = [done[i] for i in range(len(study.points))]
    write_table(rows, table, study.to_json())
    return rows


def _quiet(progress: bool | None):
    return None if progress is None else not progress


def write_table(rows: list[dict], table: Path, header: dict) -> None:
    """``rows`` as one tidy table (columns: the union of the rows' keys, in first-seen
    order, ``index`` first): a plain CSV (the header is the first record of the results
    file beside it), or Parquet with the header in its metadata too."""
    columns = list(dict.fromkeys(k for row in rows for k in row))
    text = json.dumps(header, sort_keys=True)
    if table.suffix == ".parquet":
        pa, pq = _pyarrow()
        data = {c: [row.get(c) for row in rows] for c in columns}
        pq.write_table(pa.table(data).replace_schema_metadata({"fsicas_study": text}), table)
        return
    with open(table, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns, restval="", extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: ("" if v is None else v) for k, v in row.items()})


def _pyarrow():
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise ValueError("a .parquet table needs pyarrow (pip install pyarrow); or write "
                         ".csv") from None
    return pa, pq
