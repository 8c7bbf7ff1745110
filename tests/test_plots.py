"""Plotting is free of side effects on the user's Matplotlib session; only the CLI
selects the file backend."""
import os
import subprocess
import sys

import matplotlib
import pytest

from fsicas import Scene, build_model, linear_stability
from fsicas.cli import main

#: A backend a user could have chosen; not the CLI's Agg, so a library call of
#: ``matplotlib.use("Agg")`` would show.
USER_BACKEND = "pdf"


@pytest.fixture
def user_backend():
    """The session's backend set to USER_BACKEND for the test, restored afterwards."""
    before = matplotlib.get_backend()
    matplotlib.use(USER_BACKEND)
    yield USER_BACKEND
    matplotlib.use(before)


def test_importing_and_drawing_keeps_the_users_backend(user_backend, tmp_path):
    import fsicas.plots
    from fsicas.plots import plot_eigenvalues
    scene = Scene(modes=3)
    plot_eigenvalues(linear_stability(scene, build_model(scene)), scene, tmp_path / "eig.png")
    assert (tmp_path / "eig.png").stat().st_size > 0
    assert matplotlib.get_backend() == user_backend
    assert fsicas.plots.pyplot().get_backend() == user_backend


def test_a_fresh_session_keeps_its_backend_after_drawing(tmp_path):
    """In a new interpreter whose default backend comes from MPLBACKEND (as a notebook's
    does from its kernel), importing fsicas.plots and drawing leaves it unchanged."""
    code = ("import matplotlib, fsicas.plots as fp; from fsicas import Scene, build_model, "
            "linear_stability; s = Scene(modes=3); "
            f"fp.plot_eigenvalues(linear_stability(s, build_model(s)), s, {str(tmp_path / 'e.png')!r}); "
            "print(matplotlib.get_backend())")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          env={**os.environ, "MPLBACKEND": USER_BACKEND})
    assert done.stdout.strip() == USER_BACKEND


def test_cli_selects_the_file_backend_when_it_writes_a_figure(user_backend, tmp_path, capsys):
    assert main(["modes", "--modes", "2", "--json"]) == 0
    assert matplotlib.get_backend() == user_backend            # no figure: left alone
    assert main(["eig", "--modes", "3", "--plot", str(tmp_path / "e.png"), "--json"]) == 0
    assert matplotlib.get_backend().lower() == "agg"
    assert (tmp_path / "e.png").stat().st_size > 0



def test_return_period_of_an_unsettled_run_is_its_last_tip_return():
    """The period shown for a run without a settled cycle: the last interval between
    upward tip crossings, here of a signal whose period drifts from 0.10 to 0.11."""
    from types import SimpleNamespace

    import numpy as np

    from fsicas.plots.timedomain import return_period
    t = np.linspace(0.0, 2.0, 200001)
    period = 0.10 + 0.005 * t                          # instantaneous period
    phase = np.cumsum(np.r_[0.0, np.diff(t) / period[1:]])
    run = SimpleNamespace(trajectory=SimpleNamespace(t=t, tip=np.sin(2 * np.pi * phase)))
    k = np.flatnonzero(np.diff(np.floor(phase)) > 0)  # completed cycles
    expected = t[k[-1]] - t[k[-2]]
    assert abs(return_period(run) - expected) < 1e-4
    flat = SimpleNamespace(trajectory=SimpleNamespace(t=t, tip=np.zeros_like(t)))
    assert return_period(flat) is None
