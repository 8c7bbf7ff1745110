"""Every notebook runs top to bottom in a Jupyter kernel (nbclient), as a reader runs it:
no cell fails, every figure is shown, and the key numbers are right.

Each notebook in ``notebooks/`` is executed once (parametrized over the files, so
``pytest -n 2`` spreads them); a notebook with an entry in :data:`REPORTS` gets that cell
appended, which prints its key numbers as one JSON line for :data:`CHECKS`. The stored
notebooks carry cell ids and the outputs of one run top to bottom (:data:`REGENERATE`),
checked fast against their sources (every cell that prints or draws shows it, no error
or warning, figures of a modest size) and, where the notebook is executed, against the
fresh run's outputs: the same lines, numbers aside. Executing never writes the stored file.
"""
import ast
import base64
import importlib.metadata
import json
import re
import struct
import sys
import tomllib
from pathlib import Path

import nbclient
import numpy as np
import nbformat
import pytest

NOTEBOOKS = Path(__file__).resolve().parent.parent / "notebooks"
PATHS = sorted(NOTEBOOKS.glob("*.ipynb"))
PYPROJECT = NOTEBOOKS.parent / "pyproject.toml"

#: The command of README.md that executes the stored notebooks in place.
REGENERATE = ("jupyter nbconvert --to notebook --execute --inplace "
              "--ExecutePreprocessor.record_timing=False notebooks/*.ipynb")

#: A number as printed (sign, digits, decimals, exponent): masked where runs may differ.
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")

#: Limits of a stored notebook: a figure's width in pixels (inline at dpi 100), the
#: file's size, and the text one cell prints.
MAX_FIGURE_WIDTH, MAX_FILE_BYTES, MAX_CELL_TEXT = 1200, 600_000, 4000

#: A code cell draws when it calls pyplot or a plotting function (fsicas.plots.plot_*).
DRAWS = re.compile(r"\bplt\.|\bplot_\w+\(")

#: Appended for the test only: prints the notebook's key numbers as one JSON line.
REPORTS = {
    "quickstart": """
print("REPORT " + _json.dumps({
    "pressure_drop": float(steady.pressure_drop), "tip": float(tip),
    "Q": [float(q) for q in st.Q], "lam": [[float(v.real), float(v.imag)] for v in lam],
    "outcome": run.outcome.outcome, "status": branch.status,
    "period_on_branch": float(period_on_branch), "period": float(run.outcome.period)}))
""",
    "stability_map": """
print("REPORT " + _json.dumps({
    "n_eig": len(lam), "onset": onset.ustar, "omega": onset.omega,
    "growth": [growth(0.999 * onset.ustar), growth(1.001 * onset.ustar)],
    "points": [dict(p.to_json()) for p in boundary.points],
    "switches": [s.mstar for s in boundary.switches], "switches_located": [s.located for s in boundary.switches],
    "rel_n6_light": float(rel[mstars < 1].max())}))
""",
    "time_integration": """
print("REPORT " + _json.dumps({
    "ustar_crit": hopf.ustar, "omega": hopf.omega, "half_gap": half_gap,
    "runs": {str(u): r.outcome.to_json() for u, r in runs.items()},
    "impacting": imp.outcome.to_json(), "status": imp.trajectory.status}))
""",
    "limit_cycles": """
print("REPORT " + _json.dumps({
    "hopf": branch.hopf, "status": branch.status, "gap_ratio": branch.contact.gap_ratio,
    "stable": [bool(p.stable) for p in branch.points], "trivial": [trivial.real, trivial.imag],
    "light_hopf": light.hopf, "light_status": light.status,
    "folds": [f.ustar for f in light.folds], "fold_stable": [bool(f.stable) for f in light.folds],
    "run": run.outcome.to_json(), "T_branch": point.period, "A_branch": point.tip_amplitude}))
""",
    "palate_design": """
print("REPORT " + _json.dumps({
    "onset": sens.onset_flow * 60e3, "L": sens.parameters["L"].flow, "flows": flows.tolist(),
    "factors": factors.tolist(), "gap": gap.to_json(), "stiff": stiff.to_json(),
    "E0": palate.values["E"], "q0": sens.onset_flow}))
""",
    "studies": """
print("REPORT " + _json.dumps({
    "rows": len(rows), "errors": sum(1 for r in rows if r["error"]), "coef": coef.tolist(),
    "exact_E": sens.parameters["E"].flow, "exact_e": sens.parameters["e"].flow,
    "again": again == rows, "table": len(table), "header_points": header["points"]}))
""",
    "snore_sound": """
print("REPORT " + _json.dumps({
    "period": run.outcome.period, "f0": tone.fundamental_hz, "spl": tone.spl_db,
    "harmonics": list(tone.harmonics_pa), "sine": sine.harmonics_pa[0], "closed": closed,
    "snore_spl": snore.spl_db, "snore_f0": snore.fundamental_hz}))
""",
    "physical_units": """
print("REPORT " + _json.dumps({
    "onset": onset, "flows": flows, "pitches": pitches,
    "breaths": {k: {"outcome": r.outcome.outcome, "t_c": r.outcome.first_contact_time,
                    "flow_c": None if r.outcome.first_contact_time is None
                    else float(sc.l_per_min(sch.ustar_at(r.outcome.first_contact_time))),
                    "status": r.trajectory.status}
                for k, (s, sch, r) in breaths.items()}}))
""",
}


def code_cells(nb) -> list:
    return [c for c in nb.cells if c.cell_type == "code"]


def stream_text(cell, name: str = "stdout") -> str:
    """What ``cell`` printed to ``name`` (stdout or stderr), its chunks joined."""
    return "".join(o.text for o in cell.outputs if o.output_type == "stream" and o.name == name)


def figures(cell) -> list:
    """The base64 PNGs ``cell`` shows."""
    return [o.data["image/png"] for o in cell.outputs
            if o.output_type == "display_data" and "image/png" in o.data]


def png_width(data: str) -> int:
    """Width in pixels of a base64 PNG: the first field of its IHDR chunk (bytes 16-20)."""
    return struct.unpack(">I", base64.b64decode(data[:32])[16:20])[0]


def shape(cell) -> tuple:
    """What a run of ``cell`` shows, numbers aside: its printed text with every number
    masked and the spaces dropped (array padding follows the numbers), and its figures."""
    return re.sub(r"\s+", "", NUMBER.sub("#", stream_text(cell))), len(figures(cell))


def imported_modules(nb) -> set:
    """Top-level names of the modules the code cells of ``nb`` import (magics skipped)."""
    names = set()
    for cell in code_cells(nb):
        source = "\n".join(line for line in cell.source.splitlines()
                           if not line.lstrip().startswith(("%", "!")))
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.Import):
                names |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names.add(node.module.split(".")[0])
    return names


def distribution(requirement: str) -> str:
    """The normalized distribution name of a requirement (``"dask[distributed]>=1"``: dask)."""
    return re.sub(r"[-_.]+", "-", re.match(r"[A-Za-z0-9_.-]+", requirement).group()).lower()


def execute(path: Path):
    """The executed notebook (with its report cell appended, if any) and its report."""
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)                       # cell ids and the rest of the schema
    report = REPORTS.get(path.stem)
    if report is not None:
        nb.cells.append(nbformat.v4.new_code_cell("import json as _json\n" + report))
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}}).execute()
    if report is None:
        return nb, None
    text = "".join(o.get("text", "") for o in nb.cells[-1].outputs if o.output_type == "stream")
    line = next(line for line in text.splitlines() if line.startswith("REPORT "))
    return nb, json.loads(line[len("REPORT "):])


def test_there_are_notebooks():
    assert {"quickstart", "stability_map", "time_integration", "limit_cycles",
            "physical_units"} <= {p.stem for p in PATHS}


@pytest.mark.parametrize("path", PATHS, ids=lambda p: p.stem)
def test_stored_with_outputs(path):
    """Stored as one run top to bottom leaves it: unique cell ids, execution counts 1, 2,
    ... in order, the text of every cell that prints and the figure of every cell that
    draws, no error, traceback, warning or object address, and a modest size."""
    assert path.stat().st_size <= MAX_FILE_BYTES, f"{path.name}: {path.stat().st_size} bytes"
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    ids = [c.get("id") for c in nb.cells]
    assert all(ids) and len(set(ids)) == len(ids)
    assert nb.metadata.kernelspec.name == "python3"
    code = code_cells(nb)
    assert [c.execution_count for c in code] == list(range(1, len(code) + 1)), \
        f"{path.name} is not stored as one run top to bottom: {REGENERATE}"
    for cell in code:
        where, text = f"{path.name} cell {cell.id}", stream_text(cell)
        assert all(o.output_type in ("stream", "display_data", "execute_result")
                   for o in cell.outputs), f"{where} stores an error"
        assert not stream_text(cell, "stderr"), f"{where}: {stream_text(cell, 'stderr')[:400]}"
        assert not re.search(r"Traceback|\w+Warning: | at 0x[0-9a-f]+", text + str(cell.outputs)), where
        assert len(text) <= MAX_CELL_TEXT, f"{where} prints {len(text)} characters"
        if re.search(r"\bprint\(", cell.source):
            assert text, f"{where} prints but stores no text: {REGENERATE}"
        if DRAWS.search(cell.source):
            assert figures(cell), f"{where} draws but stores no figure: {REGENERATE}"
        assert all(png_width(f) <= MAX_FIGURE_WIDTH for f in figures(cell)), where


def test_the_notebooks_extra_installs_what_they_import():
    """``pip install -e ".[notebooks]"`` brings JupyterLab and every package a notebook
    imports (outside the standard library and fsicas): each is a core dependency or in
    the ``notebooks`` extra."""
    project = tomllib.loads(PYPROJECT.read_text())["project"]
    declared = {distribution(r) for r in
                project["dependencies"] + project["optional-dependencies"]["notebooks"]}
    assert {"jupyterlab", "ipykernel", "nbconvert"} <= declared
    providers = importlib.metadata.packages_distributions()
    for path in PATHS:
        modules = imported_modules(nbformat.read(path, as_version=4))
        for module in modules - set(sys.stdlib_module_names) - {"fsicas"}:
            found = {distribution(d) for d in providers.get(module, [])}
            assert found & declared, f"{path.name} imports {module} ({found or 'not installed'}), " \
                                     "which the notebooks extra does not install"


def test_the_readme_says_how_to_open_and_regenerate_them():
    readme = (NOTEBOOKS.parent / "README.md").read_text()
    assert 'python3 -m pip install -e ".[notebooks]" && jupyter lab notebooks/' in readme
    assert REGENERATE in readme


#: Notebooks whose run is a deep check (``-m slow``): snore_sound integrates a palate's
#: impacting snore, 143 s on 2 idle cores, a sixth of the default suite's budget.
SLOW = {"snore_sound"}


@pytest.mark.parametrize("path", [pytest.param(p, marks=pytest.mark.slow) if p.stem in SLOW
                                  else p for p in PATHS], ids=lambda p: p.stem)
def test_notebook(path):
    stored = path.read_bytes()
    nb, out = execute(path)
    assert path.read_bytes() == stored                  # executing never writes the file
    code = code_cells(nb)
    for old, new in zip(code_cells(nbformat.reads(stored.decode(), as_version=4)), code):
        assert shape(old) == shape(new), \
            f"{path.name} cell {old.id}: the stored outputs are not its source's: {REGENERATE}"
    errors = [(c.id, o.ename, o.evalue) for c in code for o in c.outputs if o.output_type == "error"]
    assert not errors
    figures = [o for c in code for o in c.outputs
               if o.output_type == "display_data" and "image/png" in o.data]
    drawing = [c for c in code if DRAWS.search(c.source)]
    assert len(figures) >= len(drawing)            # every figure is shown inline
    for cell in drawing:
        assert any(o.output_type == "display_data" and "image/png" in o.data
                   for o in cell.outputs), f"{path.name} cell {cell.id} draws but shows no figure"
    if path.stem in CHECKS:
        CHECKS[path.stem](out)


def check_palate_design(out):
    # the elasticity is the slope of the recomputed onsets at L = 30 mm (central
    # difference over +-10 %, second order: agrees to the curvature, a few per cent)
    flows, factors = np.array(out["flows"]), np.array(out["factors"])
    i = int(np.argmin(abs(factors - 1)))
    slope = np.log(flows[i + 1] / flows[i - 1]) / np.log(factors[i + 1] / factors[i - 1])
    assert out["L"] == pytest.approx(slope, rel=0.05)
    assert flows[i] == pytest.approx(out["onset"], rel=1e-9)
    for name in ("gap", "stiff"):
        d = out[name]
        assert d["onset_flow_after_l_min"] == pytest.approx(10.0, rel=1e-9)
        assert d["verified"]["stable_below"] and d["verified"]["unstable_above"]
    ratio = (10.0 / 60e3) / out["q0"]
    assert out["stiff"]["after"] == pytest.approx(out["E0"] * ratio ** 2, rel=1e-9)


def check_studies(out):
    assert out["rows"] == out["table"] == out["header_points"] == 60 and out["errors"] == 0
    assert out["coef"][1] == pytest.approx(0.5, abs=1e-4)        # Q ~ sqrt(E); the fit's bias
    assert out["exact_E"] == pytest.approx(0.5, abs=1e-12)
    assert out["coef"][2] == pytest.approx(out["exact_e"], rel=0.1)   # a range average
    assert out["again"]


def check_snore_sound(out):
    # the looped cycle is the run's last, the outcome's period its settled estimate: they
    # agree to the settling (3e-7 here); T = 10 ms; symmetric channels: the sound repeats
    # each half cycle, its fundamental is 2/T
    assert out["f0"] == pytest.approx(2 / (out["period"] * 0.01), rel=1e-5)
    assert out["sine"] == pytest.approx(out["closed"], rel=1e-6)
    assert int(np.argmax(out["harmonics"])) == 1          # symmetric channels: 2nd harmonic
    assert 0 < out["snore_spl"] < out["spl"] and out["snore_f0"] > 0


def check_quickstart(out):
    assert out["pressure_drop"] == pytest.approx(1.0 * 25 * (0.5 + 2 * 0.14 / 0.1), rel=1e-14)
    assert out["tip"] > 0 and out["Q"][0] > out["Q"][1]
    lam = [complex(*v) for v in out["lam"]]
    assert len(lam) == 2 * 10 + 2                   # M is non-singular: every eigenvalue is finite
    imag = sorted(v.imag for v in lam)
    assert imag == pytest.approx(sorted(-v for v in imag), abs=1e-9 * max(abs(v) for v in lam))
    # two independent routes to the same limit cycle: integration and continuation
    assert out["outcome"] == "lco" and out["status"] == "contact"
    assert out["period_on_branch"] == pytest.approx(out["period"], rel=1e-4)


def check_stability_map(out):
    assert out["n_eig"] == 22
    # docs/stability.md, N = 10: U*_c = 5.490136531, omega = 45.613307908 at M* = 1
    assert out["onset"] == pytest.approx(5.490136531, rel=1e-7)
    assert out["omega"] == pytest.approx(45.613307908, rel=1e-7)
    below, above = out["growth"]
    assert below < 0 < above                        # the direct eigen-solves bracket the onset
    points = {round(p["mstar"], 4): p for p in out["points"]}
    assert all(p["refined"] for p in points.values())
    assert points[1.0]["ustar_crit"] == pytest.approx(5.4901, abs=1e-4)
    assert points[0.01]["ustar_crit"] == pytest.approx(11.3567, abs=1e-4)
    assert points[0.01]["criticality"] == "subcritical"
    assert points[1.0]["criticality"] == "supercritical"
    # the four switches below M* = 10 of docs/stability.md
    assert out["switches"] == pytest.approx([0.398887, 1.754058, 4.314685, 8.633159], rel=1e-3)
    assert all(out["switches_located"])
    assert out["rel_n6_light"] < 1e-3


def check_time_integration(out):
    runs = out["runs"]
    assert [runs[u]["outcome"] for u in ("5.0", "6.2", "8.0")] == ["decay", "lco", "contact"]
    assert float("5.0") < out["ustar_crit"] < float("6.2")
    lco = runs["6.2"]
    assert lco["settled"] and not lco["contact"] and lco["tip_amplitude"] < out["half_gap"]
    assert lco["omega"] == pytest.approx(out["omega"], rel=0.1)
    assert runs["8.0"]["first_contact_time"] > 0
    imp = out["impacting"]
    assert out["status"] == "success" and imp["outcome"] == "impacting_lco"
    assert 1.0 in imp["contact_positions"] and imp["impacts_per_cycle"] >= 1
    assert 0.9 < imp["tip_amplitude"] / out["half_gap"] < 1.0
    assert 0 < imp["mean_flow_reduction"] < 1


def check_limit_cycles(out):
    assert out["status"] == "contact" and out["gap_ratio"] == pytest.approx(1.0, abs=1e-6)
    assert out["hopf"]["criticality"] == "supercritical" and all(out["stable"])
    assert complex(*out["trivial"]) == pytest.approx(1.0, abs=1e-6)
    # subcritical: the cycles start below U*_c, unstable, and turn stable at a fold
    assert out["light_hopf"]["criticality"] == "subcritical" and out["light_status"] == "contact"
    assert len(out["folds"]) == 1 and out["folds"][0] < out["light_hopf"]["ustar_crit"]
    # integration and collocation: the same cycle
    run = out["run"]
    assert run["outcome"] == "lco"
    assert run["period"] == pytest.approx(out["T_branch"], rel=1e-5)
    assert run["tip_amplitude"] == pytest.approx(out["A_branch"], rel=max(1e-4, 2 * run["convergence"]))


def check_physical_units(out):
    onset = out["onset"]
    # docs/units.md: 3.789 L/min and 4.667 Hz with N = 6, 10, 20; margin -16.21 L/min at 20 L/min
    assert onset["onset_flow_l_min"] == pytest.approx(3.789247, rel=1e-5)
    assert onset["frequency_hz"] == pytest.approx(4.667389, rel=1e-5)
    assert onset["margin_flow_l_min"] == pytest.approx(-16.21, abs=0.01)
    assert onset["flutters_at_reference"] and onset["criticality"] == "subcritical"
    assert out["flows"][1] == pytest.approx(onset["onset_flow_l_min"], rel=1e-9)   # gap 2 mm
    assert all(a < b for a, b in zip(out["flows"], out["flows"][1:]))
    low, high = out["breaths"]["5 L/min"], out["breaths"]["8 L/min"]
    assert low["t_c"] is None and low["status"] == "success"
    assert high["outcome"] == "impacting_nonperiodic" and high["status"] == "success"
    assert onset["onset_flow_l_min"] < high["flow_c"] < 8.0


CHECKS = {"quickstart": check_quickstart, "stability_map": check_stability_map,
          "palate_design": check_palate_design, "studies": check_studies,
          "snore_sound": check_snore_sound,
          "time_integration": check_time_integration, "limit_cycles": check_limit_cycles,
          "physical_units": check_physical_units}
