"""Run the catalogue of bad inputs (:mod:`fsicas.cli.bad_inputs`) and write its table
into docs/reliability.md::

    python3 -m fsicas.cli.reliability [docs/reliability.md]

Each case runs the command line in-process, in a fresh folder, with every expensive
step (continuation, time integration, the pools of map and study points, the map's
linear boundary) replaced by a tripwire: a case that got past the checks is caught at
the start of the work, not after hours. Its verdict is one of :data:`VERDICTS`.
"""
from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import sys
import tempfile
import traceback
from pathlib import Path
from unittest import mock

from .bad_inputs import CASES, GROUPS, Case

__all__ = ["run_case", "run_all", "table", "write_table", "tripwires", "VERDICTS", "REFUSED",
           "SECONDS"]

#: The verdicts; :data:`REFUSED` is the one every case must get.
REFUSED = "refused, cause named"
VERDICTS = (REFUSED, "refused, cause not named", "traceback", "work started", "hang",
            "accepted", "NaN in JSON")
#: Seconds a case may take before it counts as a hang.
SECONDS = 20
_BEGIN, _END = "<!-- inputs table: begin -->", "<!-- inputs table: end -->"


class _WorkStarted(BaseException):
    """Raised by a tripwire (a BaseException: no ``except Exception`` swallows it)."""


class _Hang(BaseException):
    pass


_EXPENSIVE = ("continuation.ContinuationIterator.start",
              "fsicas.timedomain.integrators.Integrator.run",
              "fsicas.timedomain.impact_map.local_pool",
              "fsicas.timedomain.impact_map.stability_boundary",
              "fsicas.studies.run.local_pool")


@contextlib.contextmanager
def tripwires():
    """Every expensive step (:data:`_EXPENSIVE`) raises instead of working."""
    def tripped(*args, **kwargs):
        raise _WorkStarted
    with contextlib.ExitStack() as stack:
        for target in _EXPENSIVE:
            stack.enter_context(mock.patch(target, tripped))
        yield


def _write_files(case: Case, folder: Path) -> None:
    for name, content in case.files:
        content = content(folder) if callable(content) else content
        path = folder / name
        path.write_bytes(content) if isinstance(content, bytes) else path.write_text(content)


def _call(argv: list) -> tuple:
    """(exit status or the verdict of an escape, stdout, stderr) of ``fsicas argv``."""
    from . import main
    out, err = io.StringIO(), io.StringIO()

    def alarm(*_):
        raise _Hang
    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(SECONDS)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), tripwires():
            code = main(argv)
    except SystemExit as stop:                    # argparse: usage and message on stderr
        code = stop.code
    except _WorkStarted:
        code = "work started"
    except _Hang:
        code = "hang"
    except Exception:                             # noqa: BLE001 - that is the finding
        code, err = "traceback", io.StringIO(traceback.format_exc())
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    return code, out.getvalue(), err.getvalue()


def run_case(case: Case) -> tuple[str, str]:
    """(verdict, message) of ``case``, run in a fresh folder that is then removed."""
    cwd = os.getcwd()
    with tempfile.TemporaryDirectory() as folder:
        _write_files(case, Path(folder))
        os.chdir(folder)
        try:
            code, out, err = _call([*case.argv, "--json"])
        finally:
            os.chdir(cwd)
    return _verdict(case, code, out, err)


def _verdict(case: Case, code, out: str, err: str) -> tuple[str, str]:
    if isinstance(code, str):
        return code, err.strip().splitlines()[-1] if err.strip() else ""
    if any(word in out for word in ("NaN", "Infinity")):
        return "NaN in JSON", out[:200]
    if code != 2:
        return "accepted", out[:200]
    try:
        message = json.loads(out)["error"]
    except (ValueError, KeyError, TypeError):
        message = err.strip()
    named = case.named in message or case.named.replace("_", "-") in message
    return (REFUSED if named else "refused, cause not named"), message


def run_all(cases=CASES, say=None) -> list[tuple[Case, str, str]]:
    """(case, verdict, message) of every case; ``say(line)`` for each that is not refused."""
    results = []
    for case in cases:
        verdict, message = run_case(case)
        results.append((case, verdict, message))
        if say and verdict != REFUSED:
            say(f"{verdict}: {case.label}: {message}")
    return results


def table(results) -> str:
    """The Markdown table: per group, what it tries, how many cases, their verdicts."""
    lines = [f"The inputs tried ({len(results)} in all):", "",
             "| inputs | count | verdicts |", "| --- | --- | --- |"]
    for group, text in GROUPS.items():
        verdicts = [v for c, v, _ in results if c.group == group]
        counts = ", ".join(f"{v}: {verdicts.count(v)}" for v in VERDICTS if v in verdicts)
        lines.append(f"| {text} | {len(verdicts)} | {counts} |")
    return "\n".join(lines)


def write_table(results, page: Path) -> None:
    """Replace the text between the table's markers in ``page``."""
    text = page.read_text()
    head, rest = text.split(_BEGIN)
    _, tail = rest.split(_END)
    page.write_text(f"{head}{_BEGIN}\n{table(results)}\n{_END}{tail}")


def main(argv=None) -> int:
    """Run every case, print the ones not refused, rewrite the page's table; exit 1 if
    any case was not refused."""
    argv = sys.argv[1:] if argv is None else argv
    page = Path(argv[0] if argv else "docs/reliability.md")
    results = run_all(say=print)
    write_table(results, page)
    bad = sum(v != REFUSED for _, v, _ in results)
    print(f"{len(results)} inputs, {len(results) - bad} refused with the cause named; "
          f"table written to {page}")
    return 1 if bad else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
