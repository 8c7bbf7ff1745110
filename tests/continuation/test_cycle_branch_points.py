"""Branch points of cycles: a symmetric cycle family that loses stability to cycles
breaking the symmetry (a pitchfork of cycles), detected, located and switched."""

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import continuation as C

E, A = 0.5, 0.3                      # angular speed 1 + E cos(theta); coupling of z to x
T = 2 * np.pi / np.sqrt(1 - E ** 2)
#: int_0^T x dt over the unit circle, x = cos(theta), theta' = 1 + E cos(theta)
X_MEAN = (2 * np.pi / E) * (1 - 1 / np.sqrt(1 - E ** 2)) / T
MU_BP = -A * X_MEAN                  # where exp(T (mu + A X_MEAN)), z's multiplier, is 1


def _symmetric_ring():
    """The unit circle r' = r (1 - r^2), theta' = 1 + E cos(theta), with
    z' = (mu + A x) z - z^3: z -> -z is a symmetry; the cycle with z = 0 has the
    multipliers 1, exp(-2 T) and exp(T (mu - MU_BP)), so cycles with z != 0 branch
    off at mu = MU_BP (a pitchfork; for mu > MU_BP, as -z^3 saturates them)."""
    u, p = ca.SX.sym("u", 3), ca.SX.sym("p", 1)
    x, y, z = u[0], u[1], u[2]
    r2 = x ** 2 + y ** 2
    w = 1 + E * x / ca.sqrt(r2)
    F = ca.vertcat((1 - r2) * x - w * y, (1 - r2) * y + w * x, (p[0] + A * x) * z - z ** 3)
    return ca.Function("F", [u, p], [F])


def _ring_orbit(t):
    """The z = 0 cycle, sampled at equal time: theta(t) from tan(theta/2) =
    sqrt((1 + E)/(1 - E)) tan(pi t) (the closed form of theta' = 1 + E cos theta)."""
    t = np.atleast_1d(t)
    theta = 2 * np.arctan(np.sqrt((1 + E) / (1 - E)) * np.tan(np.pi * t))
    return np.column_stack([np.cos(theta), np.sin(theta), np.zeros_like(t)])


@pytest.fixture(scope="module")
def symmetric_branch():
    problem = C.CycleProblem(_symmetric_ring(), _ring_orbit, T, {"mu": MU_BP - 0.1}, "mu",
                             settings=C.CollocationSettings(ntst=20, ncol=4))
    branch = C.continuation(problem, settings=C.ContinuationSettings(
        ds=0.02, ds_max=0.05, bounds={"mu": (MU_BP - 0.2, MU_BP + 0.1)}, max_steps=40))
    return problem, branch


def test_symmetry_breaking_is_a_branch_point_at_its_closed_form(symmetric_branch):
    problem, branch = symmetric_branch
    assert branch.status == "bound"
    (bp,) = branch.special("bp")
    assert not branch.special("fold")
    assert abs(bp.params["mu"] - MU_BP) < 1e-6
    assert abs(bp.data["multiplier_re"] - 1) < 1e-6 and bp.data["multiplier_im"] == 0
    stable = branch.stable
    mu = branch.par("mu")
    assert stable[mu < MU_BP - 1e-3].all() and not stable[mu > MU_BP + 1e-3].any()


def test_branch_point_located_by_newton_on_the_symmetric_cycles(symmetric_branch):
    """From its arclength location, Newton on the z = 0 cycles' square system
    (``locate_symmetry_breaking``, z -> -z) puts the branch point at MU_BP to 1e-9, its
    multiplier at +1 to 1e-12 apart from the trivial one (measured 2e-10 and 1e-15)."""
    problem, branch = symmetric_branch
    (bp,) = branch.special("bp")
    cycle, X = problem.at(bp)
    mirror = np.diag([1.0, 1.0, -1.0])
    sym, result = C.locate_symmetry_breaking(cycle, X, mirror, shift=0)
    assert result.converged and result.iterations <= 4
    assert abs(sym.par_dict(result.X)["mu"] - MU_BP) < 1e-9
    trivial, rest = C.symmetric_multipliers(sym, result.X, mirror, shift=0)
    assert abs(rest[0] - 1) < 1e-12 and abs(rest[1] / np.exp(-2 * T) - 1) < 1e-6


def test_switching_onto_the_symmetry_breaking_cycles(symmetric_branch):
    """The new branch: z != 0; its cycles are cycles of the field (integrated
    independently over one period from u(0), they return to it), stable, and near the
    branch point their z follows the averaged normal form."""
    problem, branch = symmetric_branch
    (bp,) = branch.special("bp")
    new = C.cycle_from_bp(problem, bp, amplitude=1e-2)
    broken = C.continuation(new, settings=C.ContinuationSettings(
        ds=0.02, ds_max=0.05, bounds={"mu": (MU_BP - 0.2, MU_BP + 0.1)}, max_steps=15,
        direction=1))
    assert broken.status == "max_steps" and len(broken) >= 10
    mu, period = broken.par("mu"), broken.columns["period"]
    assert np.all(mu > MU_BP - 1e-8)             # supercritical: the branch opens to the right
    assert np.min(np.abs(broken.x[1:, 2])) > 1e-3                    # z != 0
    field = _symmetric_ring()
    for u0, m, Tm in zip(broken.x[1:], mu[1:], period[1:]):
        sol = solve_ivp(lambda t, u: np.asarray(field(u, [m])).ravel(), (0, Tm), u0,
                        rtol=1e-11, atol=1e-12)
        assert np.max(np.abs(sol.y[:, -1] - u0)) < 1e-6
    # the new cycles are stable (the z = 0 ones past the branch point are not)
    assert broken.stable[1:].all()
    # near the pitchfork, z(0)^2 = (mu - MU_BP) / <c^2> (averaging, below) up to
    # O(mu - MU_BP) (measured 1.6 (mu - MU_BP))
    near = (mu > MU_BP) & (mu < MU_BP + 1e-3)
    assert near.sum() >= 3
    theta0 = np.arctan2(broken.x[near, 1], broken.x[near, 0])
    ratio = broken.x[near, 2] ** 2 / (mu[near] - MU_BP)
    expected = np.array([1 / _mean_square_growth(th) for th in theta0])
    assert np.all(np.abs(ratio / expected - 1) < 3 * (mu[near] - MU_BP))


def _mean_square_growth(theta0) -> float:
    """<c^2> over a period, c' = (MU_BP + A cos theta) c, c(0) = 1, theta(0) = theta0:
    with z = c(t) zeta, z' = (mu + A x) z - z^3 averages to
    zeta' = (mu - MU_BP) zeta - <c^2> zeta^3, so z(0)^2 -> (mu - MU_BP) / <c^2>."""
    def rhs(t, y):
        theta, c, _ = y
        return [1 + E * np.cos(theta), (MU_BP + A * np.cos(theta)) * c, c ** 2]
    sol = solve_ivp(rhs, (0, T), [theta0, 1.0, 0.0], rtol=1e-11, atol=1e-12)
    return sol.y[2, -1] / T
