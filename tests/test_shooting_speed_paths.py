"""The shooting Jacobian's speed paths (``ShootingSettings(sensitivities=..., threads=...)``)
against an independent reference: each segment integrated on its own by CVODES with
CasADi's forward sensitivities of ``ca.solve(M, F)`` (the non-free parameters as
constants, ``(T, p_free)`` as the differentiated parameters), as the block route was
first written. On a library system with a state-dependent mass matrix, on Van der Pol
and on the flutter model with the contact law through an impact (N = 4; N = 10 slow)."""

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest

import continuation as C
from fsicas import Scene
from fsicas.cycles.impacting import shooting_points
from fsicas.linear.adapter import PI, PI_SCALE, TIME_SCALE, flutter_field
from fsicas.linear.steady import steady_state
from fsicas.model import build_model

IMPACT = dict(contact=True, contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)


def reference_blocks(problem, X):
    """``(A, B)`` of every segment by the independent route (module docstring)."""
    vf, s, m = problem.vf, problem.settings, problem.segments
    p0, k = problem.params(X), problem.free_idx[0]
    x, q = ca.MX.sym("x", vf.n), ca.MX.sym("q", 2)
    p = ca.vertcat(*[q[1] if i == k else float(p0[i]) for i in range(len(p0))])
    rate = vf.F(x, p) if vf.M is None else ca.solve(vf.M(x, p), vf.F(x, p))
    integ = ca.integrator("ref", "cvodes", {"x": x, "p": q, "ode": q[0] / m * rate}, 0.0, 1.0,
                          {"abstol": s.abstol, "reltol": s.reltol})
    seg = integ.factory("ref_jac", ["x0", "p"], ["xf", "jac:xf:x0", "jac:xf:p"])
    q0 = [problem.period(X), X[-1]]
    out = [seg(xi, q0) for xi in problem.points(X)]
    return np.array([o[1].full() for o in out]), np.array([o[2].full() for o in out])


def monodromy_multipliers(A):
    """Eigenvalues of the product of the transfer matrices, sorted."""
    return np.sort_complex(np.linalg.eigvals(np.linalg.multi_dot(list(A[::-1]))
                                             if len(A) > 1 else A[0]))


def relative(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - b)) / np.max(np.abs(b)))


def paths(problem):
    """The same problem with each speed path of its settings."""
    make = lambda **kw: C.ShootingProblem(
        problem.vf, problem.points(problem.X0), problem.period(problem.X0),
        dict(zip(problem.vf.par_names, problem.params(problem.X0))), problem.free[0],
        settings=replace(problem.settings, **kw))
    return {"exact": problem, "exact2": make(threads=2), "fast": make(sensitivities="fast"),
            "fast2": make(sensitivities="fast", threads=2)}


def check(problem, fast_bound):
    """Every path's blocks and multipliers against the reference; threads change
    nothing; 'fast' within ``fast_bound`` (its inexact Newton matrix). Returns the
    blocks of every path and the reference's."""
    X = problem.X0
    A0, B0 = reference_blocks(problem, X)
    found = {name: pr.blocks(X) for name, pr in paths(problem).items()}
    for name, (A, B) in found.items():
        bound = 1e-10 if name.startswith("exact") else fast_bound
        assert relative(A, A0) < bound and relative(B, B0) < bound, name
    assert np.array_equal(found["exact"][0], found["exact2"][0])
    assert np.array_equal(found["fast"][1], found["fast2"][1])
    return found, (A0, B0)


def _mass_circle():
    """F = (b (1 - r^2) x - y, b (1 - r^2) y + x), M = (a + x) I; free parameter b."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 2)
    b, a = p[0], p[1]
    r2 = x[0] ** 2 + x[1] ** 2
    F = ca.Function("F", [x, p], [ca.vertcat(b * (1 - r2) * x[0] - x[1],
                                             b * (1 - r2) * x[1] + x[0])])
    M = ca.Function("M", [x, p], [(a + x[0]) * ca.SX.eye(2)])
    orbit = lambda t: 1.1 * np.c_[np.cos(2 * np.pi * np.atleast_1d(t)),
                                  np.sin(2 * np.pi * np.atleast_1d(t))]
    return C.ShootingProblem(F, orbit, 15.0, {"b": 0.7, "a": 2.5}, "b", M=M,
                             settings=C.ShootingSettings(segments=5))


def _van_der_pol():
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p", 1)
    F = ca.Function("F", [x, p], [ca.vertcat(x[1], p[0] * (1 - x[0] ** 2) * x[1] - x[0])])
    orbit = lambda t: np.c_[2 * np.cos(2 * np.pi * np.atleast_1d(t)),
                            -2 * np.sin(2 * np.pi * np.atleast_1d(t))]
    return C.ShootingProblem(F, orbit, 6.6, {"mu": 1.0}, "mu",
                             settings=C.ShootingSettings(segments=4))


@pytest.mark.parametrize("make", [_mass_circle, _van_der_pol])
def test_library_systems_all_paths_equal_the_reference(make):
    problem = make()
    _, (A0, _) = check(problem, fast_bound=1e-9)
    mu0 = monodromy_multipliers(A0)
    for name, pr in paths(problem).items():
        mu = np.sort_complex(pr.multipliers(pr.X0))
        assert relative(mu, mu0) < 1e-9, name


def impacting_problem(modes: int, segments: int) -> C.ShootingProblem:
    """Shooting points along the flow of the model with contact from the steady state
    with the tip displaced onto the wall contact layer (tip gap < eps): the first segment
    integrates through an impact."""
    scene = Scene(mstar=1.0, ustar=6.6, zeta=0.01, modes=modes, **IMPACT)
    model = build_model(scene)
    vf, st = flutter_field(model), steady_state(scene, model)
    values = dict(zip(model.parameter_names, st.p))
    params = dict(zip(vf.par_names, [st.pressure_drop / PI_SCALE, 0.0] +
                      [values[k] for k in vf.par_names[2:]]))
    x0 = st.x.copy()
    n = model.n_modes
    gap = scene.hstar / 2 - model.tip_deflection(x0)
    x0[n] += (gap - 0.5 * model.scene.contact_gap) / model.tip.phi[0, 1]
    shoot = C.ShootingSettings(segments=segments, abstol=1e-10, reltol=1e-10, floquet="product")
    orbit = shooting_points(vf, x0, 0.13 * TIME_SCALE, params, segments, shoot)
    return C.ShootingProblem(vf, orbit, 0.13 * TIME_SCALE, params, PI, settings=shoot)


def _model_paths(modes, fast_bound):
    problem = impacting_problem(modes, 3)
    X = problem.X0
    _, (A0, _) = check(problem, fast_bound)
    ref = monodromy_multipliers(A0)
    for name, pr in paths(problem).items():
        mu = np.sort_complex(pr.multipliers(X))
        bound = 1e-10 if name.startswith("exact") else fast_bound
        assert relative(mu, ref) < 10 * bound, name


def test_model_with_impact_n4_all_paths_equal_the_reference():
    """'exact' (with or without threads) equals the reference to 1e-10; 'fast' only to
    within the integration error, which its inexact Newton matrix changes: both routes
    are about 6e-9 from the truth through this impact (the test below), so the two may
    differ by up to twice that (measured 3.7e-9 with NumPy 2.4 / OpenBLAS 0.3.31 on an
    AMD EPYC, below 2e-9 elsewhere)."""
    _model_paths(4, fast_bound=1.2e-8)


def test_model_with_impact_n4_fast_path_is_as_accurate_as_exact():
    """Against the truth (the independent route at abstol = reltol = 1e-13), 'fast' at
    the default tolerance 1e-10 is as accurate as 'exact' (both ~6e-9 through this
    impact, measured), and its error is integration error: it falls with the tolerance."""
    problem = impacting_problem(4, 3)
    X = problem.X0
    tight = lambda **kw: C.ShootingProblem(
        problem.vf, problem.points(X), problem.period(X),
        dict(zip(problem.vf.par_names, problem.params(X))), problem.free[0],
        settings=replace(problem.settings, **kw))
    A0, B0 = reference_blocks(tight(abstol=1e-13, reltol=1e-13), X)
    mu0 = monodromy_multipliers(A0)

    def error(pr):
        A, B = pr.blocks(X)
        return max(relative(A, A0), relative(B, B0),
                   relative(np.sort_complex(pr.multipliers(X)), mu0))

    exact = error(problem)
    fast = error(tight(sensitivities="fast"))
    fast_tight = error(tight(sensitivities="fast", abstol=1e-12, reltol=1e-12))
    assert 1e-10 < exact < 3e-8                  # a real integration error, not round-off
    assert fast < 2 * exact
    assert fast_tight < exact / 10


@pytest.mark.slow
def test_model_with_impact_n10_all_paths_equal_the_reference():
    """Through this hard impact the 'fast' path's inexact Newton matrix moves the
    Jacobian by 1.2e-8 relative (measured), the 'exact' path stays at round-off."""
    _model_paths(10, fast_bound=5e-8)


def test_settings_are_validated():
    with pytest.raises(ValueError, match="sensitivities"):
        C.ShootingSettings(sensitivities="approximate")
    with pytest.raises(ValueError, match="threads"):
        C.ShootingSettings(threads=0)
