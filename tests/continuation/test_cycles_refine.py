"""``CycleProblem.refine``: the branch continues on the field it returns (a restart)."""

import casadi as ca
import numpy as np
import pytest

import continuation as C


def _stuart_landau(c: float) -> C.VectorField:
    """x' = mu x - y - c r^2 x, y' = x + mu y - c r^2 y: the cycle r = sqrt(mu / c), T = 2 pi."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    r2 = x[0] ** 2 + x[1] ** 2
    F = ca.vertcat(p[0] * x[0] - x[1] - c * r2 * x[0], x[0] + p[0] * x[1] - c * r2 * x[1])
    return C.VectorField(ca.Function("F", [x, p], [F]), None, ("mu",))


def _circle(radius):
    return lambda t: radius * np.c_[np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)]


def test_branch_continues_on_the_refined_field_across_remeshes():
    """A "coarse" field (c = 1.01) until mu > 0.5, then the exact one (c = 1): every point
    from there on lies on the exact cycle, and the re-meshed problems keep asking."""
    coarse, fine = _stuart_landau(1.01), _stuart_landau(1.0)
    asked = []

    def refine(problem, X):
        asked.append((problem.vf is fine, id(problem)))
        return fine if problem.vf is coarse and problem.params(X)[0] > 0.5 else None

    problem = C.CycleProblem(coarse, _circle(np.sqrt(0.2 / 1.01)), 2 * np.pi, {"mu": 0.2}, "mu",
                             settings=C.CollocationSettings(ntst=10, ncol=4, adapt_every=4))
    problem.refine = refine
    branch = C.continuation(problem, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.05, max_steps=40, bounds={"mu": (0.1, 1.0)}),
        record=lambda pr, X: {"on_fine": float(pr.vf is fine)})
    mu, on_fine = branch.par("mu"), branch.columns["on_fine"].astype(bool)
    switch = np.argmax(mu > 0.5)
    assert not on_fine[:switch + 1].any() and on_fine[switch + 1:].all() and on_fine.sum() > 3
    c = np.where(on_fine, 1.0, 1.01)
    assert np.allclose(branch.columns["amplitude"], 2 * np.sqrt(mu / c), rtol=1e-7, atol=0)
    assert len({k for is_fine, k in asked if is_fine}) >= 2      # kept after re-meshes
    assert branch.stats["restarts"] > on_fine.sum() // 2


def test_on_field_keeps_the_cycle_and_checks_the_field():
    coarse, fine = _stuart_landau(1.01), _stuart_landau(1.0)
    problem = C.CycleProblem(coarse, _circle(0.5), 2 * np.pi, {"mu": 0.25}, "mu",
                             settings=C.CollocationSettings(ntst=8, ncol=3))
    new, X = problem.on_field(fine, problem.X0)
    assert new.vf is fine and np.allclose(X, problem.X0, rtol=0, atol=1e-14)
    assert np.array_equal(new.mesh, problem.mesh)
    other = C.VectorField(ca.Function("F", [ca.SX.sym("x", 2), ca.SX.sym("p", 1)],
                                      [ca.SX.zeros(2)]), None, ("nu",))
    with pytest.raises(ValueError, match="parameters"):
        problem.on_field(other, problem.X0)


def test_refined_problems_keep_the_remesh_cadence(monkeypatch):
    """A field swap every third point does not reset the count towards the next re-mesh
    (``adapt_every = 4``; a swap due with a re-mesh goes first, the re-mesh follows at
    the next point): 12 points, 4 swaps, 3 re-meshes (none if the count reset)."""
    fields = [_stuart_landau(1.0), _stuart_landau(1.0)]
    meshes, asked = [], []
    remesh = C.CycleProblem.remesh
    monkeypatch.setattr(C.CycleProblem, "remesh",
                        lambda self, X, ntst=None: meshes.append(1) or remesh(self, X, ntst))

    def refine(problem, X):
        asked.append(1)
        return None if len(asked) % 3 else fields[problem.vf is fields[0]]

    problem = C.CycleProblem(fields[0], _circle(np.sqrt(0.2)), 2 * np.pi, {"mu": 0.2}, "mu",
                             settings=C.CollocationSettings(ntst=10, ncol=4, adapt_every=4))
    problem.refine = refine
    branch = C.continuation(problem, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.05, max_steps=12, bounds={"mu": (0.1, 1.0)}))
    assert len(branch.s) == 13 and branch.stats["restarts"] == 4 + len(meshes)
    assert len(meshes) >= 2
