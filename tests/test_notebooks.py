"""Every notebook runs top to bottom (code cells executed in order) and shows its key number."""
import json
from pathlib import Path

import pytest

NOTEBOOKS = Path(__file__).resolve().parent.parent / "notebooks"


def run_notebook(path) -> dict:
    namespace: dict = {}
    for cell in json.loads(path.read_text())["cells"]:
        if cell["cell_type"] == "code":
            exec(compile("".join(cell["source"]), str(path), "exec"), namespace)
    return namespace


def test_quickstart(capsys):
    ns = run_notebook(NOTEBOOKS / "quickstart.ipynb")
    assert ns["steady"].pressure_drop == pytest.approx(1.0 * 25 * (0.5 + 2 * 0.14 / 0.1), rel=1e-14)
    assert ns["tip"] > 0 and ns["st"].Q[0] > ns["st"].Q[1]
    lam = ns["lam"]
    assert len(lam) == 2 * 10 + 2  # M is non-singular: every eigenvalue is finite
    assert sorted(lam.imag) == pytest.approx(sorted(-lam.imag), abs=1e-9 * abs(lam).max())
    # two independent routes to the same limit cycle: integration and continuation
    assert ns["run"].outcome.outcome == "lco" and ns["branch"].status == "contact"
    assert ns["period_on_branch"] == pytest.approx(ns["run"].outcome.period, rel=1e-4)
