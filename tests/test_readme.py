"""The README's commands run, and every number its comments quote is what they print.

Each ``fsicas ...`` line of the README's bash blocks whose comment (on the line or on the
comment lines below it) quotes numbers is run with ``--json``; every quoted number must
equal a number of the JSON to the digits it is quoted with (in the unit of the JSON or a
factor of 1000 from it: "3.68 mm" against 0.003677 m). Definitions in a comment
(``H*/2 = 0.05``) and figure numbers are context, not output, and are skipped. Commands that take minutes
are ``slow``.
"""
from __future__ import annotations

import json
import math
import pathlib
import re
import shlex

import pytest

ROOT = pathlib.Path(__file__).parents[1]
README = (ROOT / "README.md").read_text()
LONG_COMMANDS = ("study", "grazing", "lco", "cycles", "paper", "map")
"""Subcommands that take minutes: run in the slow set."""

_NUMBER = re.compile(r"(?<![\w.*/])([-+]?\d+(?:\.(\d+))?(?:e([-+]?\d+))?)(?![\w.]*[a-zA-Z_(])")
_CONTEXT = re.compile(r"\S+\s*=\s*[-+]?[\d.]+(?:e[-+]?\d+)?|Figs?\.\s*[\d–-]+")


def quoted_numbers(comment: str) -> list[tuple[float, float]]:
    """The numbers of a comment with their half-unit of the last digit quoted."""
    text = _CONTEXT.sub(" ", comment)
    out = []
    for match in _NUMBER.finditer(text):
        token, decimals, exponent = match.groups()
        places = len(decimals or "") - int(exponent or 0)
        out.append((float(token), 0.5 * 10.0 ** -places))
    return out


def readme_commands() -> list[tuple[str, str]]:
    """``(command, comment)`` of the README's fsicas lines whose comments quote numbers."""
    found = []
    for block in re.findall(r"```bash\n(.*?)```", README, flags=re.S):
        lines = block.splitlines()
        for i, line in enumerate(lines):
            if not line.startswith("fsicas "):
                continue
            command, _, comment = line.partition("#")
            for follow in lines[i + 1:]:
                if not follow.lstrip().startswith("#"):
                    break
                comment += " " + follow.lstrip()[1:]
            if quoted_numbers(comment):
                found.append((command.strip(), comment))
    return found


def json_numbers(value) -> list[float]:
    """Every finite number of a JSON value (nested), leaves only."""
    if isinstance(value, bool) or value is None:
        return []
    if isinstance(value, (int, float)):
        return [float(value)] if math.isfinite(value) else []
    items = value.values() if isinstance(value, dict) else value if isinstance(value, list) else []
    return [x for item in items for x in json_numbers(item)]


def _matches(quoted: float, half_unit: float, printed: list[float]) -> bool:
    return any(abs(scale * x - quoted) <= half_unit * (1 + 1e-9)
               for x in printed for scale in (1.0, 1e3, 1e-3))


def _argv(command: str) -> list[str]:
    """The command's words, with paths of files in the repository made absolute."""
    words = shlex.split(command)[1:]
    words = [str(ROOT / w) if (ROOT / w).is_file() else w for w in words]
    return words if "--json" in words else words + ["--json"]


COMMANDS = readme_commands()


def test_the_readme_quotes_numbers_of_its_commands():
    assert len(COMMANDS) >= 5
    assert quoted_numbers("period 0.1309, amplitude 0.0477 (H*/2 = 0.05), settled to 3e-6") \
        == [(0.1309, 5e-5), (0.0477, 5e-5), (3e-6, 5e-7)]
    assert quoted_numbers("median 2.89 L/min (1.73-4.93)") == [(2.89, 5e-3), (1.73, 5e-3),
                                                              (4.93, 5e-3)]


@pytest.mark.parametrize("command, comment", [
    pytest.param(c, m, id=c, marks=[pytest.mark.slow] if c.split()[1] in LONG_COMMANDS else [])
    for c, m in COMMANDS])
def test_readme_command_prints_the_quoted_numbers(command, comment, tmp_path, run_cli):
    done = run_cli(_argv(command), tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    printed = json_numbers(json.loads(done.stdout))
    missing = [q for q, half in quoted_numbers(comment) if not _matches(q, half, printed)]
    assert not missing, f"{command}: quoted {missing} not in its output"


@pytest.mark.parametrize("index", range(len(re.findall(r"```python\n", README))))
def test_readme_python_block_runs(index):
    block = re.findall(r"```python\n(.*?)```", README, flags=re.S)[index]
    exec(compile(block, f"README.md[python block {index}]", "exec"), {})
