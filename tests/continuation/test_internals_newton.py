"""White-box on purpose: Newton's method of ``continuation._driver.newton`` (its stopping
rules, chord steps, the report of a system that cannot be evaluated) and the
factorizations of a PALC step, against the roots the systems were built from and
matrices assembled independently."""

import numpy as np
import pytest
import scipy.sparse as sp

import continuation as C
import continuation._driver.newton as newton_module
import continuation._driver.palc as palc_module
from continuation._driver.newton import newton

from .conftest import brusselator_cycles


def test_round_off_floor_handled_by_step_criterion():
    """A residual with a noise floor 1e-6 >> tol and a stiff Jacobian 1e12: the
    updates reach round-off level, which the xtol criterion accepts (and reports
    the true residual); with xtol = 0 the solve fails with its residual."""

    def residual(X):
        return 1e12 * (X - 0.3) + 1e-6 * np.cos(1e20 * X)

    def jacobian(X):
        return sp.csc_matrix([[1e12]])

    ok = newton(residual, jacobian, np.array([1.0]), C.NewtonSettings())
    assert ok.converged and ok.residual > 1e-10 and "round-off" in ok.message
    assert abs(ok.X[0] - 0.3) < 1e-15
    bad = newton(residual, jacobian, np.array([1.0]), C.NewtonSettings(xtol=0.0))
    assert not bad.converged and bad.residual > 1e-10
    assert f"{bad.residual:.3e}" in bad.message


def test_system_that_cannot_be_evaluated_is_a_failed_newton():
    """A residual that raises LinAlgError beyond X = 2 (as an extended system's inner
    solve does away from its point): Newton reports a failure naming it (a branch into
    that region: ``test_problem``)."""

    def residual(X):
        if X[0] > 2.0:
            raise np.linalg.LinAlgError("no root here")
        return np.array([X[0] ** 2 - 9.0])

    bad = newton(residual, lambda X: sp.csc_matrix([[2 * X[0]]]), np.array([1.0]),
                 C.NewtonSettings())
    assert not bad.converged and "could not be evaluated: no root here" in bad.message


def _random_system(seed, n=200):
    rng = np.random.default_rng(seed)
    A = (sp.random(n, n, density=0.03, random_state=seed) + 2.0 * sp.identity(n)).tocsc()
    return A, rng.standard_normal(n)


def _cubic_system(n=30, seed=5):
    """``H(x) = A x + x^3 / 10 - b`` with the root ``x*`` built in, its Jacobian sparse."""
    A, _ = _random_system(seed, n)
    x_star = np.random.default_rng(seed + 1).standard_normal(n)
    b = A @ x_star + 0.1 * x_star ** 3
    H = lambda x: A @ x + 0.1 * x ** 3 - b                              # noqa: E731
    J = lambda x: (A + sp.diags(0.3 * x ** 2)).tocsc()                   # noqa: E731
    return H, J, x_star


@pytest.mark.parametrize("start", [1e-3, 1.0])
def test_chord_steps_reach_the_root_as_accurately_as_newton(start):
    """Near the root (1e-3) the first step's factors serve all later steps (one
    Jacobian); far from it (1.0) the steps are Newton's until one contracts by 1e-3,
    then chord steps. Either way the root the system was built from is met to
    round-off, as by Newton's method (contraction 0), with no more Jacobians; for step
    control the run of chord steps counts as one Newton iteration (``effort``)."""
    H, J, x_star = _cubic_system()
    x0 = x_star + start * np.random.default_rng(7).standard_normal(x_star.size)
    chord = newton(H, J, x0, C.NewtonSettings(tol=1e-10))
    plain = newton(H, J, x0, C.NewtonSettings(tol=1e-10, contraction=0.0))
    assert chord.converged and plain.converged
    assert plain.jacobians == plain.iterations == plain.effort
    scale = np.max(np.abs(x_star))
    for res in (chord, plain):
        assert np.max(np.abs(res.X - x_star)) < 1e-13 * scale
    assert chord.jacobians < plain.jacobians and chord.iterations <= plain.iterations + 1
    assert chord.effort == chord.jacobians + 1            # the chord run counts once
    if start < 0.01:
        assert chord.jacobians == 1 < chord.iterations


def test_cycle_step_factorizes_at_the_predictor_and_for_the_tangent(monkeypatch):
    """On a smooth cycle branch a step costs two factorizations: the corrector's at the
    predictor (the next Newton iterations are chord steps on it) and the tangent's at
    the new point, whose factors are those of ``[G_X(X); tau_k^T]`` there (checked by
    solving with the matrix assembled independently, sparse) and give ``G_X tau = 0``."""
    cyc, it = brusselator_cycles()
    step = it.start()
    calls = []
    fresh_factors = newton_module.factorize
    for module in (newton_module, palc_module):
        monkeypatch.setattr(module, "factorize", lambda A: calls.append(1) or fresh_factors(A))
    for k in range(4):
        D = cyc.system.D.copy()                        # phase reference of the step
        calls.clear()
        new = it.advance(step)
        assert len(calls) == 2 and new.iterations >= 2    # chord steps in the corrector
        D_new, cyc.system.D = cyc.system.D, D
        A = C.Problem.bordered_jacobian(cyc, new.X, step.tau)          # sparse, assembled
        v = np.random.default_rng(k).standard_normal(new.X.size)
        assert np.max(np.abs(new.lu.solve(A @ v) - v)) < 1e-10 * np.max(np.abs(v))
        assert np.max(np.abs(cyc.jacobian(new.X) @ new.tau)) < 1e-12
        cyc.system.D, step = D_new, new
