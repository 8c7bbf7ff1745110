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
        "PALC", "Problem", "SpecialPoint", "Step", "VectorField", "continuation", "observing",
        "first_lyapunov", "hopf_point", "CollocationSettings", "MAX_NTST", "CycleProblem",
        "cycle_from_hopf", "ShootingProblem", "ShootingSettings",
        "cycle_from_pd", "cycle_from_bp", "lpc_from_gh", "ns_from_hh", "ns_from_zh", "equilibrium_from_bp", "correct", "Event", "Lifted", "Status", "Condition",
        "CycleCurveProblem", "CycleFold", "Extremum", "NeimarkSacker", "PeriodDoubling",
        "locate_cycle", "BufferedFunction", "locate_symmetry_breaking", "symmetric_multipliers",
        "keeps_symmetry", "CompiledSystem", "Birth", "Diagram", "DiagramNode",
        "bifurcation_diagram"}


def test_new_problem_kind_plugs_into_palc():
    """A user-defined problem kind (own CasADi builder) is continued by the same PALC:
    here the circle x^2 + p^2 = r^2 as 'G(Y, p) = 0' with a custom residual."""
    import casadi as ca
    import numpy as np

    class Circle(C.Problem):
        kind = "circle-test"

        @staticmethod
        def builder(vf):
            y, p, D = ca.SX.sym("y", 1), ca.SX.sym("p", 2), ca.SX.sym("D", 0)
            return C.CompiledSystem(y, p, D, y[0] ** 2 + p[0] ** 2 - p[1] ** 2, "circle")

    x, p = ca.SX.sym("x", 1), ca.SX.sym("p", 2)
    vf = C.VectorField(ca.Function("F", [x, p], [x]), None, ("p", "r"))
    prob = Circle(vf, ("p",), [1.0, 0.0], np.array([0.0, 2.0]))
    br = C.continuation(prob, settings=C.ContinuationSettings(
        ds=0.1, ds_max=0.2, max_steps=100, compute_eigenvalues=False))
    xs, ps = br.x[:, 0], br.par("p")
    assert np.allclose(xs**2 + ps**2, 4.0, atol=1e-10)
    assert br.special_points == []  # the base problem only tests for branch points
    assert np.unwrap(np.arctan2(ps, xs))[-1] > 2 * np.pi
