"""Package boundaries: generic (no fsicas), plotting optional, public names only."""

import pathlib
import subprocess
import sys

import continuation as C


def test_no_fsicas_and_no_matplotlib_on_import():
    code = ("import sys, continuation; "
            "assert 'fsicas' not in sys.modules, 'fsicas imported'; "
            "assert 'matplotlib' not in sys.modules, 'matplotlib imported'")
    subprocess.run([sys.executable, "-c", code], check=True)
    src = pathlib.Path(C.__file__).parent
    for path in src.glob("*.py"):
        text = path.read_text()
        assert "import fsicas" not in text and "from fsicas" not in text, path


def test_public_names():
    assert set(C.__all__) == {
        "Branch", "ContinuationIterator", "ContinuationSettings", "EigenSettings",
        "EquilibriumProblem", "FoldCurveProblem", "HopfCurveProblem", "NewtonSettings",
        "PALC", "Problem", "SpecialPoint", "Step", "VectorField", "continuation",
        "first_lyapunov"}
