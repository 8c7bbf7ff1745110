"""Every command of the ```bash blocks of docs/*.md runs, and every ```toml block is read.

Each line of a bash block that starts with ``fsicas`` is one command (a trailing ``#``
comment dropped). By default each command is checked to be accepted by the command
line's parser, and the files and ``--physical`` configurations it names to exist and be
read (in a scratch folder that holds a link to the repository's ``examples/``, as a user
in a clone of the repository has them). Each command is also run there
(``python -m fsicas.cli``): exit status 0 and, with ``--json``, one JSON object on stdout.
Those runs take 5 s (``modes``) to minutes (a study of 200 onsets), so they are in the
slow set. A command that needs what a test cannot provide (a
Dask scheduler) is written in a ```text block, beside a sentence that says what it needs.

A ```toml block is a file for the reader of its page (``TOML_READERS``); one whose first
line names a shipped file (``# examples/NAME.toml: ...``) holds that file's values.
"""
from __future__ import annotations

import json
import pathlib
import re
import shlex
import tomllib

import pytest

from fsicas.cli import build_parser
from fsicas.physical import load_physical
from fsicas.studies.spec import load_study

ROOT = pathlib.Path(__file__).parents[1]
DOCS = ROOT / "docs"
TOML_READERS = {"studies.md": load_study, "units.md": load_physical}
"""The reader of each page's ```toml blocks."""


def blocks(page: pathlib.Path, language: str) -> list[tuple[int, str]]:
    """``(line, text)`` of each ```language block of ``page`` (line of its opening fence)."""
    text = page.read_text()
    return [(text.count("\n", 0, m.start()) + 1, m.group(1))
            for m in re.finditer(rf"```{language}\n(.*?)```", text, flags=re.S)]


def doc_commands() -> list[tuple[str, list[str]]]:
    """``("page:line", words after fsicas)`` of every fsicas line of the docs' bash blocks."""
    found = []
    for page in sorted(DOCS.glob("*.md")):
        for start, block in blocks(page, "bash"):
            for offset, line in enumerate(block.splitlines(), start=start + 1):
                if line.startswith("fsicas "):
                    found.append((f"{page.name}:{offset}", shlex.split(line, comments=True)[1:]))
    return found


COMMANDS = doc_commands()
TOMLS = [(page, line, text) for page in sorted(DOCS.glob("*.md"))
         for line, text in blocks(page, "toml")]


@pytest.fixture
def clone(tmp_path, monkeypatch):
    """A scratch folder as the working folder, with the repository's ``examples/``."""
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_docs_have_commands():
    pages = {where.split(":")[0] for where, _ in COMMANDS}
    assert {"beam.md", "cycles.md", "design.md", "sound.md", "studies.md", "units.md"} <= pages
    assert all(words for _, words in COMMANDS)


@pytest.mark.parametrize("where, words", COMMANDS, ids=[w for w, _ in COMMANDS])
def test_docs_command_is_accepted(where, words, clone):
    try:
        build_parser().parse_args(words)
    except SystemExit as stop:
        pytest.fail(f"{where}: the parser refuses `fsicas {shlex.join(words)}` ({stop})")
    named = [w for w in words if w.endswith(".toml")]
    assert all(pathlib.Path(w).is_file() for w in named), f"{where}: {named}"
    if "--physical" in words:
        load_physical(words[words.index("--physical") + 1])


@pytest.mark.slow
@pytest.mark.parametrize("where, words", COMMANDS, ids=[w for w, _ in COMMANDS])
def test_docs_command_runs(where, words, clone, run_cli):
    done = run_cli(words, clone)
    assert done.returncode == 0, f"{where}: {done.stderr[-2000:]}"
    if "--json" in words:
        assert isinstance(json.loads(done.stdout), dict)


def test_the_docs_have_toml_files():
    assert {page.name for page, _, _ in TOMLS} == set(TOML_READERS)


@pytest.mark.parametrize("page, line, text", TOMLS, ids=[f"{p.name}:{n}" for p, n, _ in TOMLS])
def test_docs_toml_block_is_read(page, line, text, clone):
    values = tomllib.loads(text)
    named = re.match(r"# (examples/\S+\.toml)", text)
    if named:
        assert values == tomllib.loads((ROOT / named.group(1)).read_text())
    (clone / "block.toml").write_text(text)
    TOML_READERS[page.name](str(clone / "block.toml"))
