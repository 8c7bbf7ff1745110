"""Every notebook runs top to bottom in a Jupyter kernel (nbclient), as a reader runs it:
no cell fails, every figure is shown, and the key numbers are right."""
import json
from pathlib import Path

import nbclient
import nbformat
import pytest

NOTEBOOKS = Path(__file__).resolve().parent.parent / "notebooks"

#: Appended for the test only: prints the notebook's key numbers as one JSON line.
REPORT = """
import json as _json
print("REPORT " + _json.dumps({
    "pressure_drop": float(steady.pressure_drop), "tip": float(tip),
    "Q": [float(q) for q in st.Q], "lam": [[float(v.real), float(v.imag)] for v in lam],
    "outcome": run.outcome.outcome, "status": branch.status,
    "period_on_branch": float(period_on_branch), "period": float(run.outcome.period)}))
"""


def execute(path: Path):
    """The executed notebook (with the report cell appended) and its report."""
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)                       # cell ids and the rest of the schema
    nb.cells.append(nbformat.v4.new_code_cell(REPORT))
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}}).execute()
    text = "".join(o.get("text", "") for o in nb.cells[-1].outputs if o.output_type == "stream")
    line = next(line for line in text.splitlines() if line.startswith("REPORT "))
    return nb, json.loads(line[len("REPORT "):])


def test_quickstart():
    nb, out = execute(NOTEBOOKS / "quickstart.ipynb")
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    figures = [o for o in outputs if o.output_type == "display_data" and "image/png" in o.data]
    plotting = [c for c in nb.cells if c.cell_type == "code" and "plt." in c.source]
    assert len(figures) >= len(plotting) >= 1       # every figure is shown inline
    assert out["pressure_drop"] == pytest.approx(1.0 * 25 * (0.5 + 2 * 0.14 / 0.1), rel=1e-14)
    assert out["tip"] > 0 and out["Q"][0] > out["Q"][1]
    lam = [complex(*v) for v in out["lam"]]
    assert len(lam) == 2 * 10 + 2                   # M is non-singular: every eigenvalue is finite
    imag = sorted(v.imag for v in lam)
    assert imag == pytest.approx(sorted(-v for v in imag), abs=1e-9 * max(abs(v) for v in lam))
    # two independent routes to the same limit cycle: integration and continuation
    assert out["outcome"] == "lco" and out["status"] == "contact"
    assert out["period_on_branch"] == pytest.approx(out["period"], rel=1e-4)
