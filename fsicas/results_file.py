"""An append-only results file (JSON lines) that a long run writes as it goes and resumes.

The first line is a header record ``{"header": {...}}`` with everything the results
depend on (scene, settings); the other lines are one record each. Opening the file
(:class:`ResultsFile`, a context manager):

- takes an exclusive lock (``fcntl.flock``, POSIX): a second run on the same file is
  refused at once instead of computing every point twice;
- repairs a torn last line (a process killed mid-write): the partial record is cut
  off before anything is appended;
- writes the header into a new or empty file, and refuses a file whose header differs
  (naming the differing keys) or that has records but no header, so results made with
  other settings are never mixed or reused;
- refuses, before it writes or cuts a byte, anything that is not a results file: a
  folder, a FIFO or a device, or a file whose first line is not a header record (a
  user's notes, a figure), which is left exactly as it was;
- refuses a record (a line but the torn last one) that is not a JSON object with the
  ``fields`` the run reads back, of their types, naming the file and the line, and
  leaves the file as it was.

Each record is appended by one ``write`` of the whole line to a file opened with
``O_APPEND``, so a record is either in the file whole or (after a kill) repaired away.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

from . import strict_json

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None

__all__ = ["ResultsFile", "read_records", "is_results_file", "check_results_path"]

_HEADER_START = b'{"header"'
_KIND_WORDS = {(int, float): "a number", (int,): "an integer", (str,): "a string"}


def _normal(value):
    """``value`` as JSON would give it back (tuples as lists, ...)."""
    return json.loads(json.dumps(value))


def is_results_file(path) -> bool:
    """Whether ``path`` is a regular file that is empty or starts with a header record
    (also a header torn by a kill, which opening repairs)."""
    path = Path(path)
    if not path.is_file():
        return False
    with open(path, "rb") as fh:
        start = fh.read(len(_HEADER_START))
    return start == b"" or start == _HEADER_START


def check_results_path(path) -> None:
    """ValueError, before any write, if an existing ``path`` is not a results file."""
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        return
    if not path.is_file():
        raise ValueError(f"{path} is not a regular file (a folder, a FIFO or a device): "
                         "name a new file for the results")
    if not is_results_file(path):
        raise ValueError(f"{path} exists and is not a results file of fsicas: it has no "
                         "header record on its first line saying how its contents were "
                         "made; it was left as it is: name a new file for the results")


def read_records(path) -> tuple[dict | None, list[dict]]:
    """(header, records) of a results file; unparsable lines (a torn tail) are skipped."""
    header, records = None, []
    path = Path(path)
    if not path.exists():
        return header, records
    for line in path.read_text().splitlines():
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            continue
        if isinstance(row, dict) and "header" in row and header is None and not records:
            header = row["header"]
        elif isinstance(row, dict):
            records.append(row)
    return header, records


class ResultsFile:
    """``with ResultsFile(path, header) as f:`` ... ``f.records`` (the records already
    there), ``f.append(record)``; ``f.repaired``: bytes of a torn last line cut off.
    ``written_by`` (e.g. :func:`fsicas.provenance.provenance`) is stored beside the header
    of a new file and not compared on resume; ``fields``: ``{key: type}`` every record
    must hold (checked when the file is opened)."""

    def __init__(self, path, header: dict, written_by: dict | None = None,
                 fields: dict | None = None):
        self.path, self.header = Path(path), _normal(header)
        self.written_by, self.fields = written_by, dict(fields or {})
        self.records: list[dict] = []
        self.repaired = 0
        self._fd = None

    def __enter__(self) -> "ResultsFile":
        check_results_path(self.path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_APPEND, 0o644)
        try:
            self._lock()
            self.repaired = self._repair()
            header, self.records = self._read()
            self._check(header)
            if header is None:
                first = {"header": self.header}
                self.append(first if self.written_by is None else {**first, "written_by": self.written_by})
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)        # releases the lock
            self._fd = None

    def append(self, record: dict) -> None:
        """Append ``record`` as one line, in one write (NaN and infinities as null:
        :mod:`fsicas.strict_json`)."""
        os.write(self._fd, (strict_json.dumps(record) + "\n").encode())

    def _lock(self) -> None:
        if fcntl is None:
            return
        try:
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ValueError(f"{self.path} is being written by another run (it holds the "
                             "file's lock): wait for it to finish or choose another output "
                             "file") from None

    def _repair(self) -> int:
        """Cut a partial last line (no final newline); the number of bytes removed."""
        size = os.fstat(self._fd).st_size
        if size == 0:
            return 0
        data = self.path.read_bytes()
        if data.endswith(b"\n"):
            return 0
        keep = data.rfind(b"\n") + 1
        os.ftruncate(self._fd, keep)
        return size - keep

    def _read(self) -> tuple[dict | None, list[dict]]:
        """(header, records), every line checked (the torn tail is repaired before)."""
        header, records = None, []
        for number, line in enumerate(self.path.read_bytes().splitlines(), start=1):
            if not line.strip():
                continue
            try:
                row = json.loads(line)
            except ValueError:
                row = None
            if number == 1 and isinstance(row, dict) and "header" in row:
                header = row["header"]
                continue
            problem = _record_problem(row, self.fields)
            if problem:
                raise ValueError(f"{self.path} line {number}: {problem}; the file was left as "
                                 "it is: delete that line (its point is computed again) or "
                                 "choose another output file")
            records.append(row)
        return header, records

    def _check(self, header) -> None:
        if header is None:
            if self.records:
                raise ValueError(f"{self.path} holds {len(self.records)} records but no header "
                                 "saying how they were made, so they cannot be reused: choose "
                                 "another output file or delete this one")
            return
        if header != self.header:
            keys = sorted(k for k in set(header) | set(self.header)
                          if header.get(k) != self.header.get(k))
            detail = "; ".join(f"{k}: file {_differences(header.get(k), self.header.get(k))}"
                               for k in keys)
            raise ValueError(f"{self.path} was written with other settings ({detail}): its "
                             "records cannot be reused; choose another output file or delete "
                             "this one")


def _differences(old, new) -> str:
    """The differing entries of two header values (dicts compared key by key)."""
    if isinstance(old, dict) and isinstance(new, dict):
        keys = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
        return ", ".join(f"{k} = {old.get(k)!r} here {new.get(k)!r}" for k in keys)
    return f"{old!r} here {new!r}"


def _record_problem(row, fields: dict) -> str | None:
    """What is wrong with a record read back (None if nothing): not a JSON object, a
    field of ``fields`` missing or not of its type (a boolean is not a number)."""
    if not isinstance(row, dict):
        return "not a record (a JSON object on one line)"
    for key, kind in fields.items():
        kinds = kind if isinstance(kind, tuple) else (kind,)
        if key not in row:
            return f"the record has no {key!r}"
        if not isinstance(row[key], kinds) or isinstance(row[key], bool) and bool not in kinds:
            return f"the record's {key!r} is {row[key]!r}, not {_KIND_WORDS.get(kinds, kinds)}"
    return None
