"""Scenes and integrator settings shared by the fsicas tests, as fixtures (pytest runs
with ``--import-mode=importlib``, so test modules import nothing local).

Each name says what the object is; derive variants with ``scene.replace(...)``.
"""
import pytest

from fsicas import Profile, Scene
from fsicas.timedomain.integrators import Settings


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
