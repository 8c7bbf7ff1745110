"""Period doubling: a cycle whose transverse plane turns by half a turn per period.

In cylindrical coordinates, theta' = 1 and the transverse vector v = (r - 1, z)
written in a frame e(theta/2) turning with half the angle, v = a e + b e_perp, obeys
a' = mu a - a^3, b' = -b. In Cartesian form (P = e e^T = [[1+c, s], [s, 1-c]]/2 with
c = x/r, s = y/r, K v = (-z, r - 1)):

    v' = mu P v - (v.P v) P v - (I - P) v + K v / 2.

The circle r = 1, z = 0 has multipliers 1, -exp(2 pi mu), -exp(-2 pi): a period
doubling at mu = 0 exactly. For mu > 0 the doubled cycle is a = sqrt(mu), b = 0:
(r - 1)^2 + z^2 = mu, period 4 pi, multipliers 1, exp(-8 pi mu), exp(-4 pi).
"""

import numpy as np
import pytest

import continuation as C


@pytest.fixture(scope="module")
def pd_branch(models):
    prob = C.CycleProblem(models.half_twisted(), lambda t: np.c_[np.cos(2 * np.pi * t),
                                                     np.sin(2 * np.pi * t), 0 * t],
                          6.0, {"mu": -0.3}, "mu",
                          settings=C.CollocationSettings(ntst=20, ncol=4))
    br = C.continuation(prob, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.5, max_steps=30, bounds={"mu": (-1, 0.3)}))
    return prob, br


def test_period_doubling_located_at_analytic_value(pd_branch):
    prob, br = pd_branch
    (pd,) = br.special("pd")
    assert pd.status == "converged" and abs(pd.params["mu"]) < 1e-10
    assert abs(pd.data["multiplier_re"] + 1) < 1e-10 and pd.data["multiplier_im"] == 0
    mu0 = br.par("mu")[0]
    assert np.allclose(np.sort(br.eigenvalues[0].real),
                       np.sort([1, -np.exp(2 * np.pi * mu0), -np.exp(-2 * np.pi)]), rtol=1e-8)
    assert list(br.n_unstable[br.par("mu") < -1e-3]) == [0] * int(np.sum(br.par("mu") < -1e-3))
    assert np.all(br.n_unstable[br.par("mu") > 1e-3] == 1)
    assert not br.special("ns") and not br.special("fold")


def test_doubled_branch_from_period_doubling(pd_branch):
    prob, br = pd_branch
    (pd,) = br.special("pd")
    new = C.cycle_from_pd(prob, pd, amplitude=0.05)
    assert new.ntst == 2 * prob.ntst
    b2 = C.continuation(new, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.3, max_steps=12, bounds={"mu": (-1, 0.3)}))
    assert b2.status == "max_steps" and b2.par("mu")[-1] > 0.05
    mu = b2.par("mu")
    assert np.all(mu > 0)
    assert np.max(np.abs(b2.columns["period"] - 4 * np.pi)) < 1e-9
    r = np.hypot(b2.x[:, 0], b2.x[:, 1])
    assert np.max(np.abs((r - 1) ** 2 + b2.x[:, 2] ** 2 - mu)) < 1e-8
    for m, ev in zip(mu, b2.eigenvalues):
        assert np.allclose(np.sort(ev.real), np.sort([1, np.exp(-8 * np.pi * m),
                                                      np.exp(-4 * np.pi)]), rtol=1e-6)
    assert b2.stable.all()


def test_doubled_branch_from_a_re_meshed_branch(models):
    """On an adapted branch the PD point lies on a mesh of its own (not the first
    problem's): the switch rebuilds its problem (``CycleProblem.at``) and runs that mesh
    through twice."""
    first = np.linspace(0.0, 1.0, 21) ** 1.6                       # far from equidistributed
    prob = C.CycleProblem(models.half_twisted(), lambda t: np.c_[np.cos(2 * np.pi * t),
                                                     np.sin(2 * np.pi * t), 0 * t],
                          6.0, {"mu": -0.3}, "mu", mesh=first,
                          settings=C.CollocationSettings(ntst=20, ncol=4, adapt_every=1))
    br = C.continuation(prob, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.5, max_steps=30, bounds={"mu": (-1, 0.3)}))
    (pd,) = br.special("pd")
    mesh = np.asarray(pd.data["mesh"])
    assert abs(pd.params["mu"]) < 1e-9 and np.max(np.abs(mesh - first)) > 0.05
    on_point, X = prob.at(pd)
    assert np.array_equal(on_point.mesh, mesh) and np.max(np.abs(on_point.residual(X))) < 1e-8
    new = C.cycle_from_pd(prob, pd, amplitude=0.05)
    assert np.allclose(new.mesh, np.r_[mesh, 1 + mesh[1:]] / 2, rtol=0, atol=1e-15)
    b2 = C.continuation(new, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.3, max_steps=8, bounds={"mu": (-1, 0.3)}))
    mu, r = b2.par("mu"), np.hypot(b2.x[:, 0], b2.x[:, 1])
    assert b2.status == "max_steps" and np.all(mu > 0)
    assert np.max(np.abs((r - 1) ** 2 + b2.x[:, 2] ** 2 - mu)) < 1e-8


def test_pd_switching_bad_input(pd_branch):
    prob, br = pd_branch
    with pytest.raises(ValueError, match="pd"):
        C.cycle_from_pd(prob, C.SpecialPoint("fold", 0, np.zeros(3), {"mu": 0.0},
                                             "converged", 0.0, {}))
    with pytest.raises(ValueError, match="amplitude"):
        C.cycle_from_pd(prob, br.special("pd")[0], amplitude=-1.0)


def test_cycle_branch_save_load_round_trip(pd_branch, tmp_path):
    """Multipliers, cycle columns, stability counts and the PD point (with its full
    unknown vector in data['X']) survive save/load."""
    prob, br = pd_branch
    path = tmp_path / "cycles.npz"
    br.save(path)
    back = C.Branch.load(path)
    assert back.kind == "cycle" and len(back) == len(br)
    assert all(np.array_equal(a, b) for a, b in zip(back.eigenvalues, br.eigenvalues))
    assert np.array_equal(back.columns["period"], br.columns["period"])
    assert np.array_equal(back.n_unstable, br.n_unstable)
    (pd,) = back.special("pd")
    assert np.allclose(pd.data["X"], br.special("pd")[0].data["X"])
