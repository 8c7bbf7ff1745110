"""Symmetry-breaking branch points of cycles located by Newton on the symmetric cycles'
square system (``locate_symmetry_breaking``), on a field with a closed-form answer."""

import casadi as ca
import numpy as np
import pytest

import continuation as C

E = 0.5                                  # angular speed 1 + E cos(2 theta)
T = 2 * np.pi / np.sqrt(1 - E ** 2)
#: int_0^T (lam - cos^2 theta) dt = 0: z's multiplier exp(int (lam - x^2) dt) is 1
LAM_BP = (1 + (np.sqrt(1 - E ** 2) - 1) / E) / 2
INVERSION, MIRROR = -np.eye(3), np.diag([1.0, 1.0, -1.0])


def _field(kappa=True, leak=0.0):
    """The unit circle r' = r (1 - r^2), theta' = 1 + E cos(2 theta), and
    z' = (lam - x^2) z - z^3 (+ x z^2 unless ``kappa``; ``leak`` z added to x').
    Without a leak it is equivariant under u -> -u; its cycle z = 0 keeps
    u(t + T/2) = -u(t), and (with ``kappa``) z -> -z.
    Its multipliers are 1, exp(-2 T) and exp(int_0^T (lam - cos^2 theta) dt), the
    last through +1 at LAM_BP with the Floquet solution (0, 0, c(t)), c(t + T/2) = c(t):
    it breaks both symmetries."""
    u, p = ca.SX.sym("u", 3), ca.SX.sym("p", 1)
    x, y, z = u[0], u[1], u[2]
    r2 = x ** 2 + y ** 2
    w = 1 + E * (x ** 2 - y ** 2) / r2
    dz = (p[0] - x ** 2) * z - z ** 3 + (0 if kappa else x * z ** 2)
    return ca.Function("F", [u, p], [ca.vertcat((1 - r2) * x - w * y + leak * z,
                                                (1 - r2) * y + w * x, dz)])


def _circle(t):
    t = np.atleast_1d(t)
    return np.column_stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), 0 * t])


def _cycle(ntst, kappa=False, lam=LAM_BP - 0.05, leak=0.0):
    """The z = 0 cycle, corrected at ``lam`` on a uniform mesh of ``ntst`` intervals."""
    problem = C.CycleProblem(_field(kappa, leak), _circle, T, {"lam": lam}, "lam",
                             settings=C.CollocationSettings(ntst=ntst, ncol=4))
    step = C.ContinuationIterator(problem, C.PALC(), C.ContinuationSettings()).start()
    return problem, step.X


def test_spatio_temporal_branch_point_at_its_closed_form():
    """From a cycle 0.05 below it, three Newton steps (a regular system) reach LAM_BP
    to 1e-8 on 20 intervals (measured 5e-10); on the half-shift symmetric mesh the cycle
    keeps u(t + T/2) = -u(t) to rounding; the symmetric multipliers put the
    symmetry-breaking one at +1 to 1e-12 apart from the trivial one, and the radial one
    at its closed form exp(-2 T) (the discretization's 1e-6)."""
    problem, X = _cycle(20)
    sym, result = C.locate_symmetry_breaking(problem, X, INVERSION, shift=0.5)
    assert result.converged and result.iterations <= 4
    assert abs(sym.par_dict(result.X)["lam"] - LAM_BP) < 1e-8
    assert sym.ntst == 20 and np.allclose(sym.mesh[10:], sym.mesh[:11] + 0.5, atol=1e-15)
    u = sym.nodes(result.X)
    assert np.max(np.abs(u[len(u) // 2:] + u[: len(u) // 2])) < 1e-12
    trivial, rest = C.symmetric_multipliers(sym, result.X, INVERSION, shift=0.5)
    assert abs(trivial - 1) < 1e-8 and abs(rest[0] - 1) < 1e-12
    assert abs(rest[1] / np.exp(-2 * T) - 1) < 1e-5
    full = sym.multipliers(result.X)
    assert np.allclose(np.sort(np.abs(full)), np.sort(np.abs(np.r_[trivial, rest])), rtol=1e-6)


def test_spatial_branch_point_converges_at_the_collocation_order():
    """The same point as a break of z -> -z (shift 0, on the start's mesh): LAM_BP to
    1.3e-6 / 5.5e-9 on 10 / 20 intervals, order 2 NCOL = 8 (measured 7.9)."""
    errors = []
    for ntst in (10, 20):
        problem, X = _cycle(ntst, kappa=True)
        sym, result = C.locate_symmetry_breaking(problem, X, MIRROR, shift=0)
        assert result.converged and result.iterations <= 4
        errors.append(abs(sym.par_dict(result.X)["lam"] - LAM_BP))
        trivial, rest = C.symmetric_multipliers(sym, result.X, MIRROR, shift=0)
        assert abs(rest[0] - 1) < 1e-12
    assert errors[1] < 1e-7 and np.log2(errors[0] / errors[1]) > 6


def test_symmetry_breaking_refuses_what_it_cannot_locate():
    problem, X = _cycle(10)
    with pytest.raises(ValueError, match="orthogonal involution"):
        C.locate_symmetry_breaking(problem, X, 2 * np.eye(3))
    with pytest.raises(ValueError, match="shift"):
        C.locate_symmetry_breaking(problem, X, INVERSION, shift=0.25)
    with pytest.raises(ValueError, match="does not keep the symmetry"):
        C.locate_symmetry_breaking(problem, X, MIRROR, shift=0.5)   # (x, y) -> (x, y)
    with pytest.raises(ValueError, match="not equivariant"):          # z drives x
        C.locate_symmetry_breaking(*_cycle(10, kappa=True, leak=0.1), MIRROR, shift=0)
    with pytest.raises(ValueError, match="one free parameter"):
        u, q = ca.SX.sym("u", 3), ca.SX.sym("q", 2)
        two = C.CycleProblem(ca.Function("F", [u, q], [_field()(u, q[0])]), _circle, T,
                             {"lam": 0.3, "b": 0.0}, ("lam", "b"))
        C.locate_symmetry_breaking(two, two.X0, INVERSION)
    with pytest.raises(ValueError, match="half-period shift"):
        C.symmetric_multipliers(C.CycleProblem(
            _field(), _circle, T, {"lam": 0.3}, "lam", settings=C.CollocationSettings(
                ntst=10, ncol=4), mesh=np.r_[0.0, np.sort(np.random.default_rng(0).uniform(
                    0, 1, 9)), 1.0]), X, INVERSION)


def test_keeps_symmetry_says_which_cycles_the_location_accepts():
    """The circle keeps u(t + T/2) = -u(t) and z -> -z (shift 0), not (x, y) -> (x, y)
    half a period later (it maps u(t) to -u(t): a defect of 2 max |u|); the verdict is
    that of ``locate_symmetry_breaking``, which refuses the third."""
    problem, X = _cycle(10)
    assert C.keeps_symmetry(problem, X, INVERSION)
    assert C.keeps_symmetry(problem, X, MIRROR, shift=0)
    assert not C.keeps_symmetry(problem, X, MIRROR)
    with pytest.raises(ValueError, match="orthogonal involution"):
        C.keeps_symmetry(problem, X, 2 * np.eye(3))
