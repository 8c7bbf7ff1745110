"""The stability boundary (Hopf curves traced only where they can be lowest) against a
brute-force route: the leading real part of the generalized eigenvalues of an AD
Jacobian of the model's F (CasADi, dense SciPy QZ) scanned along U* at fixed M*, with
no continuation at all."""
import casadi as ca
import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from fsicas import Scene, build_model, steady_state
from fsicas.linear.boundary import stability_boundary


@pytest.fixture(scope="module")
def paper_n6():
    scene = Scene(mstar=1.0, ustar=5.0, modes=6)
    return scene, build_model(scene)


@pytest.fixture(scope="module")
def leading(paper_n6):
    """``leading(mstar, ustar) -> (max Re lambda, Im of that lambda)`` of the steady state."""
    scene, model = paper_n6
    x, p = ca.MX.sym("x", model.n_state), ca.MX.sym("p", model.rhs.size1_in(1))
    jac = ca.Function("J", [x, p], [ca.jacobian(model.rhs(x, p), x)])

    def at(mstar, ustar):
        st = steady_state(scene.replace(mstar=mstar, ustar=ustar), model)
        lam = scipy.linalg.eigvals(np.array(jac(st.x, st.p)), np.array(model.mass(st.x, st.p)))
        lam = lam[np.isfinite(lam)]
        k = int(np.argmax(lam.real))
        return float(lam[k].real), abs(float(lam[k].imag))

    return at


def brute_onset(leading, mstar, top, count=80):
    """First U* in (0.2, top) where the leading real part turns positive: a scan on
    ``count`` points, then Brent on the bracketing interval; with the frequency there."""
    grid = np.linspace(0.2, top, count)
    re = [leading(mstar, u)[0] for u in grid]
    k = next(i for i in range(count - 1) if re[i] < 0 <= re[i + 1])
    u = scipy.optimize.brentq(lambda s: leading(mstar, s)[0], grid[k], grid[k + 1],
                              xtol=1e-13, rtol=1e-13)
    return u, leading(mstar, u * (1 + 1e-9))[1]


@pytest.fixture(scope="module")
def boundary(paper_n6):
    scene, model = paper_n6
    return stability_boundary(scene, np.logspace(-1.5, 1.5, 7), model)


def test_every_boundary_point_is_the_brute_force_onset(boundary, leading):
    for p in boundary.points:
        u, omega = brute_onset(leading, p.mstar, 1.5 * p.ustar_crit)
        assert abs(p.ustar_crit - u) <= 1e-9 * u
        assert abs(p.omega - omega) <= 1e-7 * omega


def test_switches_separate_the_brute_force_branches(boundary, leading):
    """5 % on each side of every switch the brute-force onset has the frequency of the
    branch the switch names (the nearer of omega_below and omega_above: frequencies jump
    at every switch by far more than they drift along a branch over 5 % in M*)."""
    assert len(boundary.switches) >= 2
    nearer = lambda w, s: "below" if abs(w - s.omega_below) < abs(w - s.omega_above) else "above"
    for s in boundary.switches:
        _, left = brute_onset(leading, s.mstar / 1.05, 2.0 * s.ustar_above)
        _, right = brute_onset(leading, s.mstar * 1.05, 2.0 * s.ustar_above)
        assert nearer(left, s) == "below" and nearer(right, s) == "above"


def test_traced_curve_points_are_hopf_points(boundary, paper_n6):
    """Sampled points of every traced curve: at their (M*, U*) the AD Jacobian has an
    eigenvalue i omega (real part ~0 against omega) at the curve's frequency."""
    scene, model = paper_n6
    x, p = ca.MX.sym("x", model.n_state), ca.MX.sym("p", model.rhs.size1_in(1))
    jac = ca.Function("J", [x, p], [ca.jacobian(model.rhs(x, p), x)])
    for c in boundary.curves:
        for k in np.linspace(0, len(c.mstar) - 1, 4).astype(int):
            st = steady_state(scene.replace(mstar=float(c.mstar[k]), ustar=float(c.ustar[k])), model)
            lam = scipy.linalg.eigvals(np.array(jac(st.x, st.p)), np.array(model.mass(st.x, st.p)))
            near = lam[np.argmin(np.abs(lam - 1j * c.omega[k]))]
            assert abs(near.real) < 1e-5 * c.omega[k] and abs(near.imag - c.omega[k]) < 1e-5 * c.omega[k]


def _window_growth(scene, model, mstar, u_lo, u_hi) -> float:
    """The largest growth rate of the oscillatory eigenvalues over U* in [u_lo, u_hi] at
    ``mstar`` (direct eigen-solves; bounded Brent over U*)."""
    from scipy.optimize import minimize_scalar
    from fsicas.linear.stability import linear_stability

    def growth(u):
        ev = np.asarray(linear_stability(scene.replace(mstar=mstar, ustar=float(u)),
                                         model).eigenvalues)
        return float(ev[np.abs(ev.imag) > 1e-6].real.max())
    best = minimize_scalar(lambda u: -growth(u), bounds=(u_lo, u_hi), method="bounded",
                           options={"xatol": 1e-9})
    return -best.fun


def test_fold_switches_are_where_the_unstable_window_closes():
    """The two fold switches of Fig. 2 below M* = 2 at N = 10, located on the Hopf curves
    (extremum of M* along the curve), against an independent route: the M* at which the
    largest growth rate over U* near the window is zero (direct eigen-solves, Brent in
    U*, then brentq in M*), to 1e-6 relative."""
    from scipy.optimize import brentq
    scene = Scene(modes=10)
    model = build_model(scene)
    boundary = stability_boundary(scene, np.geomspace(0.3, 2.2, 5), model)
    folds = [s for s in boundary.switches if abs(s.ustar_above - s.ustar_below) > 0.1]
    assert len(folds) == 2 and all(s.located for s in folds)
    for switch in folds:
        u = switch.ustar_below
        closes = lambda m: _window_growth(scene, model, m, 0.95 * u, 1.05 * u)
        m0 = switch.mstar
        independent = brentq(closes, 0.99 * m0, 1.01 * m0, xtol=1e-12)
        assert switch.mstar == pytest.approx(independent, rel=1e-6)
    assert [round(s.mstar, 5) for s in folds] == [0.39889, 1.75406]


def test_crossing_switch_is_a_double_hopf_point():
    """The crossing of two Hopf curves near M* = 28.4 at N = 10, located by Brent on the
    difference of their onsets: the steady state there has two imaginary pairs at the two
    frequencies (direct eigen-solve), to 1e-7 of their size."""
    from fsicas.linear.stability import linear_stability
    scene = Scene(modes=10)
    model = build_model(scene)
    boundary = stability_boundary(scene, np.geomspace(20.0, 40.0, 4), model)
    (switch,) = [s for s in boundary.switches if abs(s.ustar_above - s.ustar_below) < 1e-6]
    assert switch.located
    ev = np.asarray(linear_stability(scene.replace(mstar=switch.mstar, ustar=switch.ustar_below),
                                     model).eigenvalues)
    for omega in (switch.omega_below, switch.omega_above):
        lam = ev[np.argmin(np.abs(ev - 1j * omega))]
        assert abs(lam.real) < 1e-7 * abs(lam) and abs(lam.imag - omega) < 1e-6 * omega


@pytest.mark.slow     # 47 s: 400 refined M*; test_stability checks the sampling at 9 s
def test_onset_is_continuous_in_mstar_except_at_the_switches():
    """A dense boundary (400 M* in [0.01, 100], N = 10, each point refined): across a
    fold switch U*_c jumps by at least the switch's jump (the folding branch also rises
    steeply up to its fold); everywhere else a step between
    neighbouring M* (0.01 decades apart) is no larger than 5x the median of its six
    neighbouring steps (+ 1e-3 U*_c): no jump that is not a switch."""
    scene = Scene(modes=10)
    model = build_model(scene)
    mstars = np.geomspace(0.01, 100.0, 400)
    boundary = stability_boundary(scene, mstars, model)
    u = np.array([p.ustar_crit for p in boundary.points])
    assert np.all(np.isfinite(u)) and all(p.refined for p in boundary.points)
    folds = [s for s in boundary.switches if abs(s.ustar_above - s.ustar_below) > 1e-6]
    steps = np.diff(u)
    at_fold = [[s for s in folds if mstars[k] < s.mstar <= mstars[k + 1]]
               for k in range(len(steps))]
    assert sum(map(len, at_fold)) == len(folds)
    for k, inside in enumerate(at_fold):
        if inside:
            expected = sum(s.ustar_above - s.ustar_below for s in inside)
            # plus the steep (square-root) rise of the folding branch up to its fold
            assert np.sign(steps[k]) == np.sign(expected) and \
                abs(steps[k]) >= abs(expected), (mstars[k], steps[k])
            continue
        near = [abs(steps[j]) for j in range(max(k - 3, 0), min(k + 4, len(steps)))
                if j != k and not at_fold[j]]
        assert abs(steps[k]) <= 5 * np.median(near) + 1e-3 * u[k], (mstars[k], steps[k])
