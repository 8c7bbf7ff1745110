"""Energy balance of settled cycles and flow conservation (fsicas.timedomain.energy)."""
import numpy as np
import pytest

from fsicas import Scene
from fsicas.timedomain.energy import energy_balance, outlet_flow_rates
from fsicas.model.patch import penetration
from fsicas.timedomain.returns import poincare_returns
from fsicas.timedomain.run import run_case
from fsicas.timedomain.integrators import Settings


def settled(scene, t_end, dt_out):
    run = run_case(scene, t_end, settings=Settings(rtol=1e-10, atol=1e-12, dt_out=dt_out, chunk=0.5),
                   stop_early=False, quadrature_tol=None)    # the balance of the model's own F
    assert run.trajectory.status == "success", run.trajectory.message
    times, idx = poincare_returns(run.trajectory.t, run.trajectory.tip)
    return run, run.trajectory.t[idx[-3]], run.trajectory.t[idx[-2]]


def test_energy_balance_of_a_limit_cycle_without_contact():
    run, t_a, t_b = settled(Scene(mstar=1.0, ustar=6.5, zeta=0.01, modes=10), 6.0, 1e-3)
    assert run.outcome.outcome == "lco"
    eb = energy_balance(run.trajectory, t_a, t_b)
    assert eb.contact_work == 0.0 and eb.dissipation > 0 and eb.fluid_work > 0
    assert abs(eb.delta_energy) < 0.05 * eb.dissipation           # a settled cycle (nearly periodic)
    assert eb.relative_residual < 1e-4                              # measured 1e-5 (Simpson, dt 1e-3)
    # flow conservation: outlet total = inlet total; cycle means agree
    out = outlet_flow_rates(run.trajectory)
    tr = run.trajectory
    assert np.allclose(out.sum(axis=1), tr.x[:, -2:].sum(axis=1), rtol=1e-13, atol=0)
    # cycle means: ∫(outlet - inlet) dt = -s_c Φ(1)·Δq over the window (≈ 0 for a closed cycle)
    w = (tr.t >= t_a) & (tr.t <= t_b)
    n = run.model.n_modes
    dq = tr.x[w][-1, n:2 * n] - tr.x[w][0, n:2 * n]
    inflow = np.trapezoid(tr.x[w, -2:], tr.t[w], axis=0)
    for c, s in ((0, -1.0), (1, 1.0)):
        diff = np.trapezoid(out[w, c] - tr.x[w, -2 + c], tr.t[w])
        assert diff == pytest.approx(-s * run.model.tip.Phi[:, 1] @ dq, abs=1e-6 * inflow[c])
        assert abs(diff) < 1e-3 * inflow[c]


@pytest.mark.slow
def test_energy_balance_with_impacts():
    """Impacting cycle (k* = 1e7, eps/H = 1e-2): the balance holds over the cycle and over
    one impact, where the contact work is large (elastic energy stored in the wall)."""
    scene = Scene(mstar=1.0, ustar=7.0, zeta=0.01, modes=10, contact=True, contact_stiffness=1e7,
                  contact_eps=1e-2)
    run, t_a, t_b = settled(scene, 4.0, 2e-5)
    assert run.outcome.contact
    tr = run.trajectory
    eb = energy_balance(tr, t_a, t_b)
    assert eb.relative_residual < 1e-3                              # measured 2e-4
    w = np.flatnonzero((tr.t >= t_a) & (tr.t <= t_b))
    force = penetration(run.model, tr.x[w], tr.p).load
    on = np.flatnonzero(force > 0)
    assert on.size > 0
    k_max = on[0] + int(np.argmax(force[on[0]:on[0] + 200]))
    impact = energy_balance(tr, tr.t[w[on[0]] - 1], tr.t[w[k_max]])
    assert impact.contact_work < 0 and abs(impact.contact_work) > 0.05 * impact.dissipation
    assert abs(impact.residual) < 1e-2 * abs(impact.contact_work)
