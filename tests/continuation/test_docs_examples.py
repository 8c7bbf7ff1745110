"""Every ```python block of docs/continuation.md runs and its asserts hold."""

import pathlib
import re

import pytest

DOC = pathlib.Path(__file__).parents[2] / "docs" / "continuation.md"
BLOCKS = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.S)


def test_docs_have_examples():
    assert len(BLOCKS) >= 4


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_docs_example_runs(index):
    exec(compile(BLOCKS[index], f"{DOC.name}[block {index}]", "exec"), {})
