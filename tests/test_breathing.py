"""Breathing: a slow inspiration sweeps through the instability; the linear theory predicts
where the oscillation amplitude turns (onset and offset with hysteresis)."""
import numpy as np
import pytest
import scipy.optimize

from fsicas import Scene, build_model, steady_state
from fsicas.timedomain.breathing import PressureSchedule
from fsicas.timedomain.integrators import Settings, simulate
from fsicas.linear.stability import eigenvalues


def test_breath_amplitude_turns_where_the_growth_rate_changes_sign():
    """Slowly varying U*(t): d ln A/dt ≈ Re λ(U*(t)), so the amplitude is smallest when
    U* rises through U*_c and largest when it falls back through U*_c; at equal U* the
    oscillation is far larger on the way down (hysteresis of the dynamic bifurcation)."""
    scene = Scene(mstar=1.0, ustar=6.4, zeta=0.01, modes=6)
    model = build_model(scene)
    rate = lambda u: eigenvalues(model, steady_state(scene.replace(ustar=u), model))[0].real
    u_c = scipy.optimize.brentq(rate, 4.0, 6.4, xtol=1e-10)
    period = 20.0
    schedule = PressureSchedule.breath(scene.ustar, period)
    traj = simulate(model, steady_state(scene, model), period, schedule=schedule, perturbation=0.1,
                    settings=Settings(method="cvodes", rtol=1e-10, atol=1e-18, dt_out=2e-3, chunk=1.0))
    # atol 1e-18 follows the amplitude over 4 decades; IDAS's Newton test would also hold
    # the algebraic derivatives z to it, below their round-off (IDA_CONV_FAIL)
    assert traj.status == "success"
    n = model.n_modes
    energy = np.sqrt(np.sum(traj.x[:, :n] ** 2 + (model.basis.omega * traj.x[:, n:2 * n]) ** 2, axis=1))
    window = 100                                               # 0.2 time units, > 1 cycle
    starts = np.arange(0, len(energy) - window, window)
    env = np.array([energy[k:k + window].max() for k in starts])
    t_env = traj.t[starts + window // 2]
    t_rise = period / np.pi * np.arcsin(u_c / scene.ustar)
    t_fall = period - t_rise
    rising, falling = (t_env > 2) & (t_env < period / 2), (t_env > period / 2) & (t_env < period - 2)
    t_min = t_env[rising][np.argmin(env[rising])]               # local minimum while U* rises
    t_max = t_env[falling][np.argmax(env[falling])]             # local maximum while U* falls
    assert t_min == pytest.approx(t_rise, abs=0.4)             # t_rise = 6.8
    assert t_max == pytest.approx(t_fall, abs=0.4)             # t_fall = 13.2
    up, down = np.interp([t_rise, t_fall], t_env, np.log10(env))
    assert down - up > 3                                       # same U*, 1000x larger going down
    assert np.allclose(schedule.ustar_at([t_rise, t_fall]), u_c, rtol=1e-12)
