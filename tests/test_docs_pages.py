"""Every ```python block of the user docs runs, and the numbers it asserts hold.

The blocks of one page run in order in one namespace (a page reads as one session), in a
scratch folder. docs/continuation.md has its own test (tests/continuation). The pages
in ``LONG`` take minutes (docs/cycles.md: branches through contact, 9 minutes at
N = 4) and run in the slow set.
"""
from __future__ import annotations

import pathlib
import re

import pytest

DOCS = pathlib.Path(__file__).parents[1] / "docs"
OWN_TEST = ("continuation.md",)
LONG = ("cycles.md",)


def python_blocks(page: pathlib.Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)


PAGES = [p for p in sorted(DOCS.glob("*.md")) if p.name not in OWN_TEST and python_blocks(p)]


def test_the_docs_have_examples():
    assert {"simulate.md", "design.md", "beam_fe.md"} <= {p.name for p in PAGES}


@pytest.mark.parametrize("page", [
    pytest.param(p, id=p.name, marks=[pytest.mark.slow] if p.name in LONG else [])
    for p in PAGES])
def test_docs_page_examples_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for index, block in enumerate(python_blocks(page)):
        exec(compile(block, f"{page.name}[python block {index}]", "exec"), namespace)
