"""The onset is the first loss of stability whatever its kind: static divergence (a real
eigenvalue crossing zero) checked against a direct route — the determinant of dF/dx at
the closed-form steady state, its sign change bisected — and the real eigenvalues."""
import numpy as np
import pytest
import scipy.optimize

from fsicas import Profile, Scene, build_model, steady_state
from fsicas.linear.hopf import critical_velocity, first_hopf
from fsicas.linear.stability import eigenvalues

#: H* = 0.2, KL = 0, M* = 30: the straight state diverges before it flutters.
DIVERGING = Scene(hstar=0.2, kl=0.0, mstar=30.0)


def _det_jacobian(scene, model, ustar) -> float:
    """det dF/dx at the steady state (closed form q = 0, Q1 = Q2 = U* H*/2), scaled."""
    st = steady_state(scene.replace(ustar=ustar), model)
    sign, logdet = np.linalg.slogdet(np.array(model.jac_rhs(st.x, st.p)))
    return float(sign)


def _bisect_det(scene, model, lo, hi) -> float:
    """The sign change of det dF/dx in (lo, hi), bisected to 1e-12."""
    f = lambda u: _det_jacobian(scene, model, u)
    assert f(lo) != f(hi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) == f(lo) else (lo, mid)
    return 0.5 * (lo + hi)


@pytest.fixture(scope="module")
def diverging():
    model = build_model(DIVERGING)
    return model, critical_velocity(DIVERGING, model)


def test_divergence_before_flutter_is_the_onset(diverging):
    model, onset = diverging
    assert onset.kind == "divergence" and onset.omega == 0.0
    assert onset.bifurcation == "branch point" and onset.symmetry_breaking
    # the direct route: det dF/dx changes sign at a real eigenvalue crossing zero
    grid = np.linspace(0.3, 2.3, 41)
    signs = [_det_jacobian(DIVERGING, model, u) for u in grid]
    k = next(i for i in range(len(grid) - 1) if signs[i] != signs[i + 1])
    assert onset.ustar == pytest.approx(_bisect_det(DIVERGING, model, grid[k], grid[k + 1]),
                                        rel=1e-9, abs=0)
    # stable just below, a positive real eigenvalue (antisymmetric mode) just above
    below = eigenvalues(model, steady_state(DIVERGING.replace(ustar=onset.ustar * 0.999), model))
    above = eigenvalues(model, steady_state(DIVERGING.replace(ustar=1.5), model))
    assert below[0].real < 0
    assert above[0].real > 0 and above[0].imag == 0
    assert onset.to_json()["kind"] == "divergence"


def test_the_first_hopf_point_is_still_found_past_a_divergence(diverging):
    model, onset = diverging
    hopf = first_hopf(DIVERGING, model)
    assert hopf.kind == "flutter" and hopf.ustar > onset.ustar
    # Re lambda of a complex pair changes sign there (direct eigenvalue scan)
    rate = lambda u: max(l.real for l in eigenvalues(
        model, steady_state(DIVERGING.replace(ustar=u), model)) if abs(l.imag) > 1e-6)
    assert rate(hopf.ustar * 0.999) < 0 < rate(hopf.ustar * 1.001)


def test_a_steady_failure_beyond_the_onset_does_not_hide_it():
    """Asymmetric channel: no steady state near U* = 40, yet the onset is low."""
    scene = Scene(hstar=0.2, kl=0.0, mstar=1.0, channel1=Profile.constant(0.11),
                  channel2=Profile.constant(0.09))
    model = build_model(scene)
    onset = critical_velocity(scene, model, ustar_max=40.0)
    assert onset.kind == "flutter"
    rate = lambda u: eigenvalues(model, steady_state(scene.replace(ustar=u), model))[0].real
    lo, hi = onset.ustar * 0.99, onset.ustar * 1.01
    assert rate(lo) < 0 < rate(hi)
    assert scipy.optimize.brentq(rate, lo, hi, xtol=1e-13) == pytest.approx(onset.ustar, rel=1e-8)


@pytest.fixture(scope="module")
def diverging_boundary(diverging):
    from fsicas.linear.boundary import stability_boundary
    model, _ = diverging
    return model, stability_boundary(DIVERGING, [1.0, 30.0, 100.0], model)


def test_the_boundary_holds_the_divergence_curve(diverging_boundary):
    """Above M* ~ 10 the boundary is the divergence: each point at the sign change of
    det dF/dx (bisected directly), and M* U*^2 constant along it (the steady problem
    depends on M* U*^2 only: a closed-form scaling)."""
    model, b = diverging_boundary
    p30, p100 = b.points[1], b.points[2]
    assert p30.kind == p100.kind == "divergence" and p30.refined and p30.omega == 0.0
    direct = _bisect_det(DIVERGING, model, 1.2, 1.45)
    assert p30.ustar_crit == pytest.approx(direct, rel=1e-9, abs=0)
    assert 100.0 * p100.ustar_crit ** 2 == pytest.approx(30.0 * direct ** 2, rel=1e-9)
    assert b.points[0].kind == "flutter"
    assert any(c.kind == "divergence" for c in b.curves)
    assert b.to_json()["points"][1]["kind"] == "divergence"


def test_the_switch_to_divergence_is_where_the_onset_changes_kind(diverging_boundary):
    model, b = diverging_boundary
    (switch,) = [s for s in b.switches if s.omega_above == 0.0]
    """A fold of the flutter window (U* jumps): the onsets on either side, by
    one-parameter continuations, change kind there (U*_below ~ sqrt distance to the fold)."""
    below = critical_velocity(DIVERGING.replace(mstar=switch.mstar * (1 - 1e-5)), model)
    above = critical_velocity(DIVERGING.replace(mstar=switch.mstar * (1 + 1e-5)), model)
    assert below.kind == "flutter" and above.kind == "divergence"
    assert below.ustar == pytest.approx(switch.ustar_below, rel=5e-3)
    assert above.ustar == pytest.approx(switch.ustar_above, rel=1e-4)


def test_the_deflected_branch_of_the_pitchfork(diverging):
    """At M* = 30 the deflected states join the two pitchforks of the window of
    divergence: the branch ends at the second one (det dF/dx bisected directly); its
    states and their mirrors R x are steady (residual of F), stable (direct eigenvalues)
    where the straight state is unstable, and near the first pitchfork tip^2 grows
    linearly in U* (the pitchfork normal form)."""
    from fsicas.linear.deflected import deflected_branch
    from fsicas.linear.stability import generalized_eigen
    model, onset = diverging
    branch = deflected_branch(DIVERGING, model, onset, ustar_max=4.0)
    assert branch.status == "event" and branch.stable.all()
    closing = _bisect_det(DIVERGING, model, 1.5, 1.7)
    assert branch.ustar.min() > onset.ustar and branch.ustar.max() < closing
    assert abs(branch.ustar[-1] - closing) < 1e-3 * closing
    assert 0.015 < np.abs(branch.tip_deflection).max() < 0.02
    R = model.mirror
    for k in np.linspace(0, len(branch.ustar) - 1, 5).astype(int):
        x = branch.states[k]
        p = model.parameters(DIVERGING, pressure_drop=branch.pressure_drop[k])
        assert max(np.abs(np.array(model.rhs(x, p))).max(),
                   np.abs(np.array(model.rhs(R @ x, p))).max()) < 1e-8
        lam, _ = generalized_eigen(model.jac_rhs(x, p), model.mass(x, p))
        assert lam[0].real < 0
    ratio = branch.tip_deflection[1:4] ** 2 / (branch.ustar[1:4] - onset.ustar)
    assert np.ptp(ratio) < 0.05 * ratio.mean()
