"""Branch result object: save/load round trip, plotting, iterator, progress bar."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import continuation as C  # noqa: E402
from continuation.plotting import plot_branch  # noqa: E402


@pytest.fixture(scope="module")
def brusselator_branch():
    import casadi as ca
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    A, B = p[0], p[1]
    F = ca.Function("F", [x, p], [ca.vertcat(A - (B + 1) * x[0] + x[0]**2 * x[1],
                                             B * x[0] - x[0]**2 * x[1])])
    prob = C.EquilibriumProblem(F, [2.0, 0.5], {"A": 2.0, "B": 1.0}, "B")
    return prob, C.continuation(prob, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.2, max_steps=40, bounds={"B": (0, 7)}))


def test_branch_contents(brusselator_branch):
    _, br = brusselator_branch
    assert br.kind == "equilibrium" and br.free == ("B",) and br.par_names == ("A", "B")
    assert br.x.shape == (len(br), 2) and br.params.shape == (len(br), 2)
    assert np.all(np.diff(br.s) > 0) and br.s[0] == 0
    assert np.all(br.residual <= 1e-10)
    assert br.stats["steps"] == len(br) - 1 and br.stats["located"] == 1
    assert [p.kind for p in br.special_points] == ["hopf"]
    # stability from the generalized eigenvalues: trace B - 1 - A^2 changes sign at B = 5
    assert np.array_equal(br.stable, br.par("B") < 5)


def test_save_load_round_trip(brusselator_branch, tmp_path):
    _, br = brusselator_branch
    path = tmp_path / "branch.npz"
    br.save(path)
    back = C.Branch.load(path)
    for name in ("x", "params", "s", "ds", "iterations", "residual"):
        assert np.array_equal(getattr(back, name), getattr(br, name))
    assert all(np.array_equal(a, b) for a, b in zip(back.eigenvalues, br.eigenvalues))
    assert back.tests.keys() == br.tests.keys()
    assert (back.status, back.message, back.free) == (br.status, br.message, br.free)
    (h0,), (h1,) = br.special("hopf"), back.special("hopf")
    assert np.array_equal(h0.x, h1.x) and h0.params == h1.params and h0.data == h1.data


def test_load_rejects_other_files(tmp_path):
    path = tmp_path / "other.npz"
    np.savez(path, header=np.array('{"format": "something"}'))
    with pytest.raises(ValueError, match="not a"):
        C.Branch.load(path)


def test_plot_styles_and_markers(brusselator_branch):
    import matplotlib.pyplot as plt
    _, br = brusselator_branch
    fig, ax = plt.subplots()
    plot_branch(br, y=0, ax=ax)
    styles = [ln.get_linestyle() for ln in ax.lines]
    assert "-" in styles and "--" in styles          # stable and unstable parts
    assert [t.get_text() for t in ax.texts] == ["H"]
    assert ax.get_xlabel() == "B"
    plt.close(fig)
    with pytest.raises(ValueError, match="axis spec"):
        plot_branch(br, y=1.5)


def test_iterator_is_the_engine(brusselator_branch):
    prob, br = brusselator_branch
    it = C.ContinuationIterator(prob, C.PALC(), C.ContinuationSettings(
        ds=0.05, ds_max=0.2, max_steps=5))
    steps = list(it)
    assert len(steps) == 6 and it.status == "max_steps"
    assert np.allclose(steps[3].X, np.append(br.x[3], br.par("B")[3]))
    for s in steps:  # each tangent is a unit null vector of G_X
        assert np.linalg.norm(prob.jacobian(s.X) @ s.tau) < 1e-10
        assert abs(np.linalg.norm(s.tau) - 1) < 1e-14


def test_secant_tangent_gives_same_branch(brusselator_branch):
    prob, br = brusselator_branch
    sec = C.continuation(prob, C.PALC(tangent="secant"), C.ContinuationSettings(
        ds=0.05, ds_max=0.2, max_steps=40, bounds={"B": (0, 7)}))
    (h,) = sec.special("hopf")
    assert abs(h.params["B"] - 5) < 1e-12 and abs(h.data["omega"] - 2) < 1e-12


def test_progress_bar_quiet_by_default(brusselator_branch, capsys):
    prob, _ = brusselator_branch
    C.continuation(prob, settings=C.ContinuationSettings(max_steps=5))
    out = capsys.readouterr()
    assert out.out == "" and out.err == ""
    C.continuation(prob, settings=C.ContinuationSettings(max_steps=5, progress=True))
    assert "continuation" in capsys.readouterr().err


def test_failed_empty_branch_round_trip(tmp_path):
    import casadi as ca
    x, p = ca.SX.sym("x", 1), ca.SX.sym("p", 1)
    F = ca.Function("F", [x, p], [x**2 + 1 + p**2])
    br = C.continuation(C.EquilibriumProblem(F, [0.5], {"mu": 0.0}, "mu"))
    br.save(tmp_path / "empty.npz")
    back = C.Branch.load(tmp_path / "empty.npz")
    assert back.status == "failed" and len(back) == 0 and back.x.shape == (0, 1)
    assert back.failure["residual"] == br.failure["residual"] >= 1.0
    assert back.message == br.message
