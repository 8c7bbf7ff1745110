"""Scenes and integrator settings shared by the fsicas tests, as fixtures (pytest runs
with ``--import-mode=importlib``, so test modules import nothing local).

Each name says what the object is; derive variants with ``scene.replace(...)``.
"""
import subprocess
import sys

import pytest

from fsicas import Profile, Scene
from fsicas.timedomain.integrators import Settings


@pytest.fixture(scope="session")
def run_cli():
    """``run_cli(argv, cwd)``: the command line ``fsicas argv`` run as a subprocess
    (``python -m fsicas.cli``, this interpreter) in the folder ``cwd``, its
    ``CompletedProcess`` (stdout and stderr as text; 30 minutes at most)."""
    def run(argv, cwd):
        return subprocess.run([sys.executable, "-m", "fsicas.cli", *argv], cwd=cwd,
                              capture_output=True, text=True, timeout=1800)
    return run


@pytest.fixture(scope="session")
def damped_scene_u7() -> Scene:
    """M* = 1, U* = 7, zeta = 0.01, N = 10 (default walls): above the flutter onset
    (about 5.6); the growing oscillation reaches the wall."""
    return Scene(mstar=1.0, ustar=7.0, zeta=0.01, modes=10)


@pytest.fixture(scope="session")
def damped_scene_u6_5() -> Scene:
    """M* = 1, U* = 6.5, zeta = 0.01, N = 10: just above the onset, a contact-free
    limit cycle."""
    return Scene(mstar=1.0, ustar=6.5, zeta=0.01, modes=10)


@pytest.fixture(scope="session")
def asymmetric_channels_scene() -> Scene:
    """M* = 1, U* = 4, channel gaps 0.055 above and 0.045 below (default N): a
    statically bent steady state."""
    return Scene(mstar=1.0, ustar=4.0, channel1=Profile.constant(0.055),
                 channel2=Profile.constant(0.045))


@pytest.fixture(scope="session")
def outcome_settings() -> Settings:
    """Integrator settings for classifying runs: rtol 1e-8, atol 1e-10, samples every 1e-3."""
    return Settings(rtol=1e-8, atol=1e-10, dt_out=1e-3)


@pytest.fixture(scope="session")
def impact_settings() -> Settings:
    """Integrator settings that resolve impacts: rtol 1e-7, atol 1e-9, samples every
    1e-4, chunks of 0.5."""
    return Settings(rtol=1e-7, atol=1e-9, dt_out=1e-4, chunk=0.5)


@pytest.fixture(scope="session")
def period3_impacting_run():
    """M* = 1, U* = 7, N = 4, k* = 1e8, eps/H = 1e-2, smoothing 0.1: an IDAS run of 6 time
    units that settles on an impacting cycle of three tip swings, and that cycle as
    ``cycle_from_trajectory`` finds it (shared by the shooting and collocation tests)."""
    from types import SimpleNamespace

    from fsicas.cycles.impacting import cycle_from_trajectory
    from fsicas.model import build_model
    from fsicas.timedomain.run import run_case
    scene = Scene(mstar=1.0, ustar=7.0, zeta=0.01, modes=4, contact=True,
                  contact_stiffness=1e8, contact_eps=1e-2, contact_smoothing=0.1)
    model = build_model(scene)
    run = run_case(scene, t_end=6.0, model=model, perturbation=0.3,
                   settings=Settings(method="idas", rtol=1e-8, atol=1e-10, dt_out=2e-5))
    t, x = run.trajectory.t, run.trajectory.x
    state, period, swings = cycle_from_trajectory(model, t, x)
    y = model.tip_deflection(x[t > t[-1] - period])
    return SimpleNamespace(scene=scene, model=model, run=run, state=state, period=period,
                           swings=swings, amplitude=(y.max() - y.min()) / 2)


@pytest.fixture(scope="session")
def channel_pde_check():
    """``check(scene, model, x0, dp) -> [(h, u, p, scale)]`` per channel: the fields of the
    formal solution (cumulative Simpson on 8001 points) at t - dt, t, t + dt of a tight
    DOP853 integration (rtol 1e-13) of ``M xdot = F`` from ``x0`` at the pressure drop
    ``dp``, checked here to satisfy continuity and momentum by central differences in x
    and t (1e-5); the caller checks the end pressures (``p`` at x = 0 and 1, ``scale`` the
    size of ``h dp/dx``)."""
    import numpy as np
    import scipy.integrate
    from fsicas import flow_fields

    def check(scene, model, x0, dp, dt=2e-5):
        p = model.parameters(pressure_drop=dp)
        grid = np.linspace(0.0, 1.0, 8001)
        states = [x0 if t == 0.0 else scipy.integrate.solve_ivp(
            lambda _, z: model.xdot(z, p), (0.0, t), x0, method="DOP853", rtol=1e-13,
            atol=1e-15).y[:, -1] for t in (-dt, 0.0, dt)]
        before, now, after = (flow_fields(scene, z, model.xdot(z, p), dp, grid)
                              for z in states)
        grad = lambda a: np.gradient(a, grid, edge_order=2)
        out = []
        for c in range(2):
            h, u, pc = now.h[c], now.u[c], now.p[c]
            h_t = (after.h[c] - before.h[c]) / (2 * dt)
            flux_t = (after.h[c] * after.u[c] - before.h[c] * before.u[c]) / (2 * dt)
            momentum = scene.mstar * (flux_t + grad(h * u**2) + scene.friction * u * abs(u)) \
                + h * grad(pc)
            scale = np.max(np.abs(h * grad(pc)))
            assert np.max(np.abs(h_t + grad(h * u))) < 1e-5 * max(np.max(np.abs(h_t)), 1e-3)
            assert np.max(np.abs(momentum)) < 1e-5 * scale
            out.append((h, u, pc, scale))
        return out

    return check
