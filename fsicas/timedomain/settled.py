"""A continued cycle checked by time integration: where does a run from its state settle?

From a cycle's state (phase 0) at its U*, ``periods`` of its period are integrated (IDAS
at ``rtol``, ``samples`` outputs per period). On the run's Poincaré returns (upward
crossings of the tip through its mean, dense output: :mod:`fsicas.timedomain.returns`)
the last cycle is the last ``k`` returns, ``k`` the tip swings of the continued cycle
(its period over the mean time between returns); measured on it:

* ``period``: the time over those k returns;
* ``drift``: ``|x_last - x_(last - k)|_inf / (largest peak-to-peak of a state)``, the
  miss of the state's return after one period: small where the run has settled on a
  cycle of that period (a stable cycle), growing where it leaves it (an unstable one);
* ``tip_amplitude``: half the tip's range over that period (samples), ``min_gap``,
  ``peak_force``: the largest total impact load over it / F0
  (:func:`fsicas.model.patch.penetration`, the exact law, as the branches measure).

``status``: "settled" (drift below ``tol``), "unsettled" (above) or "failed" (the
integration failed or the run has fewer than ``k + 1`` returns; ``message`` says why).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..checks import finite_number, require
from ..linear.steady import steady_state
from ..model.assembly import Model
from ..model.contact import gaps, reference_force
from ..model.patch import penetration
from ..scene import Scene
from .integrators import Settings, simulate
from .returns import cycles, xdot_rows

__all__ = ["SettledCycle", "settled_cycle", "mirror_distance"]

SettledStatus = Literal["settled", "unsettled", "failed"]


@dataclass(frozen=True)
class SettledCycle:
    """The last cycle of a run from a continued cycle's state (module docstring)."""

    status: SettledStatus
    period: float = float("nan")
    swings: int = 0
    drift: float = float("nan")
    tip_amplitude: float = float("nan")
    min_gap: float = float("nan")
    peak_force: float = float("nan")
    message: str = ""


def settled_cycle(model: Model, scene: Scene, state, period: float, *, periods: int = 30,
                  rtol: float = 1e-10, samples: int = 4000, tol: float = 1e-6) -> SettledCycle:
    """Integrate ``periods`` periods from ``state`` on ``model`` at ``scene.ustar`` and
    measure the last period (module docstring). ``period`` in units of T."""
    period = finite_number("period", period)
    require(period > 0, f"period must be > 0, got {period}")
    require(isinstance(periods, int) and periods >= 2, f"periods must be an integer >= 2, "
            f"got {periods!r}")
    dt = period / samples
    traj = simulate(model, steady_state(scene, model), periods * period, x0=state,
                    settings=Settings(rtol=rtol, atol=rtol * 1e-2, dt_out=dt, chunk=period))
    if traj.status != "success":
        return SettledCycle("failed", message=f"the integration failed: {traj.message}")
    start = int(np.searchsorted(traj.t, traj.t[-1] - 3.5 * period))
    t, X = traj.t[start:], traj.x[start:]
    cyc = cycles(t, X, model, lambda i: xdot_rows(model, X[i], traj.p,
                                                   traj.pressure_drop[start + np.asarray(i)]))
    if cyc is None or cyc.times.size < 2:
        return SettledCycle("failed", message="fewer than two returns of the tip over the "
                            "last periods: the run decayed or left the cycle")
    k = max(1, int(round(period / np.mean(np.diff(cyc.times)))))
    if cyc.times.size < k + 1:
        return SettledCycle("failed", message=f"fewer than {k + 1} returns of the tip")
    last = slice(cyc.index[-1 - k], cyc.index[-1] + 1)
    drift = float(np.max(np.abs(cyc.points[-1] - cyc.points[-1 - k])) / cyc.size)
    y = model.tip_deflection(X[last])
    load = penetration(model, X[last], traj.p).load
    return SettledCycle("settled" if drift < tol else "unsettled",
                        float(cyc.times[-1] - cyc.times[-1 - k]), k, drift,
                        float(np.ptp(y) / 2), float(gaps(model, X[last]).min()),
                        float(load.max() / reference_force(model)))


def mirror_distance(model: Model, scene: Scene, state, period: float, *,
                    rtol: float = 1e-11) -> float:
    """How far a cycle is from the channel's symmetry: half a period after ``state`` (at
    ``scene``'s U*; IDAS at ``rtol``), the distance of the run from the mirror image
    ``R x = (-r, -r', Q2, Q1)`` of ``state`` (beam reflected, channels swapped), relative
    to ``max |state|``. Zero for a symmetric cycle, ``u(t + T/2) = R u(t)``, of a
    symmetric channel; of order one for one that breaks the symmetry."""
    state = np.asarray(state, dtype=float)
    n = model.scene.modes
    require(state.shape == (2 * n + 2,), f"state must have {2 * n + 2} entries")
    require(finite_number("period", period) > 0, f"period must be positive, got {period!r}")
    mirror = model.mirror @ state
    traj = simulate(model, steady_state(scene, model), period / 2, x0=state,
                    settings=Settings(method="idas", rtol=rtol, atol=rtol * 1e-2,
                                      dt_out=period / 2000))
    if traj.status != "success":
        raise RuntimeError(f"the half-period integration failed: {traj.message}")
    return float(np.max(np.abs(traj.x[-1] - mirror)) / np.max(np.abs(state)))
