"""Neimark-Sacker: a cycle whose transverse plane carries a rotating focus.

With rho = r - 1, v = (rho, z) and theta' = 1:  v' = (mu - |v|^2) v + beta K v,
K v = (-z, rho). The circle r = 1, z = 0 (period 2 pi) has the multipliers 1 and
exp(2 pi mu) exp(+- 2 pi i beta): a Neimark-Sacker bifurcation at mu = 0 exactly,
with rotation number beta.
"""

import casadi as ca
import numpy as np

import continuation as C

BETA = 0.3


def _torus_birth():
    X, p = ca.SX.sym("x", 3), ca.SX.sym("p", 1)
    x, y, z = X[0], X[1], X[2]
    r = ca.sqrt(x ** 2 + y ** 2)
    rho = r - 1
    g = p[0] - rho ** 2 - z ** 2
    drho, dz = g * rho - BETA * z, g * z + BETA * rho
    return ca.Function("F", [X, p], [ca.vertcat(drho * x / r - y, drho * y / r + x, dz)])


def test_neimark_sacker_located_at_analytic_value():
    prob = C.CycleProblem(_torus_birth(), lambda t: np.c_[np.cos(2 * np.pi * t),
                                                          np.sin(2 * np.pi * t), 0 * t],
                          6.0, {"mu": -0.2}, "mu", settings=C.CollocationSettings(ntst=20))
    br = C.continuation(prob, settings=C.ContinuationSettings(
        ds=0.05, ds_max=0.5, max_steps=30, bounds={"mu": (-1, 0.2)}))
    (ns,) = br.special("ns")
    assert ns.status == "converged" and abs(ns.params["mu"]) < 1e-10
    theta = np.angle(ns.data["multiplier_re"] + 1j * ns.data["multiplier_im"])
    assert abs(abs(theta) - 2 * np.pi * BETA) < 1e-8
    mu0 = br.par("mu")[0]
    ev = br.eigenvalues[0]
    expected = np.exp(2 * np.pi * mu0) * np.exp(2j * np.pi * BETA)
    assert np.min(np.abs(ev - expected)) < 1e-8 * abs(expected)
    assert not br.special("pd") and not br.special("fold")
    mu = br.par("mu")
    assert np.all(br.n_unstable[mu < -1e-3] == 0) and np.all(br.n_unstable[mu > 1e-3] == 2)
