"""White-box on purpose: the detection of special points, piece by piece: the test
functions of Floquet multipliers (``continuation._cycles.floquet``), the events of a
periodic problem between two monitored points, the location's fallback to bisection
(``continuation._driver.locate``) and who asks the eigenvalue step limit
(``continuation._equilibria.eigen``)."""

from types import SimpleNamespace

import casadi as ca
import numpy as np

import continuation as C
from continuation._cycles.floquet import crossing, nearest_real
from continuation._driver.locate import _illinois
from continuation._driver.problem import PointInfo
from continuation._equilibria import eigen

from .conftest import window_oscillator


def test_crossing_changes_sign_with_the_multiplier_that_crosses():
    """Seen on an impacting branch: in one step a real multiplier went from 0.92 to 1.89
    while 0.79 stayed; the real multiplier nearest +1 (0.92, then 0.79) stays below 1,
    the crossing function changes sign; a complex pair never changes its sign."""
    before = np.array([0.92, 0.79, 0.3 + 0.5j, 0.3 - 0.5j])
    after = np.array([1.89, 0.79, 0.3 + 0.5j, 0.3 - 0.5j])
    assert nearest_real(before, 1.0) < 1 and nearest_real(after, 1.0) < 1
    assert crossing(before, 1.0) * crossing(after, 1.0) < 0
    pair = np.array([0.5, 1.2 + 0.1j, 1.2 - 0.1j])
    assert crossing(pair, 1.0) < 0 and crossing(pair, -1.0) > 0
    assert crossing(np.array([-1.5, 0.2]), -1.0) < 0 < crossing(np.array([-0.5, 0.2]), -1.0)


def test_events_of_multipliers_that_meet_on_the_real_axis(models):
    """Seen past a branch point at N = 4: a complex pair outside the circle met on the
    real axis below -1 (no Neimark-Sacker point: as many multipliers outside as before);
    a real multiplier through +1 is a branch point unless the branch turns (a fold)."""
    problem = C.CycleProblem(models.van_der_pol(), models.van_der_pol_guess, 6.6, {"mu": 1.0},
                             "mu", settings=C.CollocationSettings(ntst=4, ncol=2, backend="mx"))
    info = lambda fold, pd, ns, bp: PointInfo(np.zeros(0), {"fold": fold},  # noqa: E731
                                              {"pd": pd, "ns": ns, "bp": bp})
    assert problem.events(info(1, 0, 2, 0), info(1, 2, 0, 0)) == ["pd"]
    assert problem.events(info(1, 0, 2, 0), info(1, 0, 0, 0)) == ["ns"]
    assert problem.events(info(1, 0, 0, 0), info(1, 0, 0, 1)) == ["bp"]
    assert problem.events(info(1, 0, 0, 0), info(-1, 0, 0, 1)) == ["fold"]
    assert problem.events(info(1, 0, 0, 1), info(1, 0, 0, 2)) == ["bp"]


def test_location_bisects_where_the_corrector_fails():
    """Regula falsi on f(s) = s - 0.3 lands on the root at once; the corrector fails
    there (a stiff branch did so): the location bisects instead and still converges."""
    failed = []

    def evaluate(s):
        if abs(s - 0.3) < 1e-12 and not failed:
            failed.append(s)
            return None
        return (s, np.array([s]), np.array([1.0]), s - 0.3,
                SimpleNamespace(iterations=1, residual=0.0))
    found = _illinois(evaluate, evaluate(0.0), evaluate(1.0), True,
                      C.ContinuationSettings(locate_tol=1e-12))
    assert failed and found.converged and abs(found.s - 0.3) < 1e-12


def test_eigenvalue_step_limit_leaves_cycle_branches_alone(monkeypatch):
    """A cycle problem's monitor reports Floquet multipliers, not eigenvalues: the limit
    is never consulted for it (``Problem.step_limit``), while an equilibrium branch
    consults it at every point after the first."""
    calls = []
    real = eigen.step_limit
    monkeypatch.setattr(eigen, "step_limit", lambda *a: calls.append(1) or real(*a))
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 1)
    a = 0.5 * p[0]            # a damped oscillator beside Van der Pol: complex multipliers
    F = ca.Function("F", [x, p], [ca.vertcat(x[1], p[0] * (1 - x[0] ** 2) * x[1] - x[0],
                                             -a * x[2] - 1.3 * x[3], 1.3 * x[2] - a * x[3])])
    orbit = lambda t: np.c_[2 * np.cos(2 * np.pi * np.atleast_1d(t)),
                            -2 * np.sin(2 * np.pi * np.atleast_1d(t)),
                            np.zeros((np.size(t), 2))]
    cycles = C.continuation(
        C.CycleProblem(F, orbit, 6.6, {"mu": 1.0}, "mu", settings=C.CollocationSettings(ntst=20)),
        settings=C.ContinuationSettings(ds=0.2, ds_max=0.5, max_steps=6))
    assert len(cycles.s) == 7 and calls == []
    equilibria = C.continuation(C.EquilibriumProblem(window_oscillator(1e-4), [0.0, 0.0],
                                                     {"mu": 0.0}, "mu"),
                                settings=C.ContinuationSettings(ds=0.3, ds_max=0.3, max_steps=5))
    assert len(calls) == len(equilibria.s) - 1
