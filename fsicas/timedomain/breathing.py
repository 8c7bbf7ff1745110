"""Prescribed pressure drop in time: constant, ramp, sinusoidal inspirations, or whole
breaths through zero flow (inspiration then expiration).

A schedule prescribes the *quasi-steady* mean inlet velocity ``U(t)`` and drives the
model with the pressure drop that would hold that velocity in a steady state,

    Δp(t) = c · U(t)|U(t)|,        c = Δp_ss(U_ref) / (U_ref |U_ref|),

with ``Δp_ss`` the steady state's pressure drop at the reference velocity (the constant
value, the end of a ramp, or the peak of a breath). For a straight symmetric channel the
steady pressure drop is exactly ``M* U|U| ((K0+KL)/2 + 2f/H*)`` in both directions, so
Δp(t) is exactly the steady pressure drop of U(t) at every t, through U = 0 as well; for
other geometries it is exact at U_ref and a quasi-steady quadratic law elsewhere (for
reversed flow through other walls the steady Δp differs from -Δp of the forward flow). The actual flow rate lags Δp(t) through the
fluid inertia (that lag and the beam's own growth time make onset and offset differ).

Kinds (``U(t)``):

- ``constant``: ``U(t) = U``;
- ``ramp``: ``U(t) = U0 + (U1 − U0) min(t / duration, 1)``;
- ``breath``: ``U(t) = U_peak |sin(π t / period)|``: an inspiration of the given period
  (one breath from rest to the peak and back), repeated;
- ``tidal``: ``U(t) = U_in max(sin(2π t/period), 0) − U_ex max(−sin(2π t/period), 0)``:
  whole breaths, an inspiration up to U_in (``ustar``) then an expiration down to −U_ex
  (``expiration``), through zero flow twice per period. u|u| is C¹ there (only its
  second derivative jumps), so the integrators' step control goes through the reversal
  without special treatment (tests/test_direction.py).

Time enters the integrator as an input (the schedule is a CasADi expression of t, one
compiled integrator serves any schedule of the same kind); no piecewise-constant chunks.
The schedule's seven numbers ``(c, U_a, U_b, duration, U_s, period, U_w)`` are passed to
the integrator as parameters: ``U(t) = U_a + U_b min(t/duration, 1) + U_s |sin(π t/period)|
+ U_w sin(π t/period)`` (a tidal breath: half-period ``period/2``,
``U_s = (U_in − U_ex)/2``, ``U_w = (U_in + U_ex)/2``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

import casadi as ca
import numpy as np

from ..scene import MAX_ABS_USTAR

__all__ = ["PressureSchedule", "ScheduleKind", "schedule_expression", "N_SCHEDULE_PARAMS"]

N_SCHEDULE_PARAMS = 7
#: U*(t) shape (module docstring): "constant", "ramp" from ustar_start to ustar over
#: duration, "breath" periodic up to the peak ustar, "tidal" up to ustar and down to
#: -expiration in each period.
ScheduleKind = Literal["constant", "ramp", "breath", "tidal"]
_KINDS = get_args(ScheduleKind)


@dataclass(frozen=True)
class PressureSchedule:
    """U*(t) prescription; see the module docstring. ``duration``/``period`` > 0."""

    kind: ScheduleKind = "constant"
    ustar: float = 0.0            # constant value, ramp end U1, or breath peak
    ustar_start: float = 0.0      # ramp start U0
    duration: float = 1.0         # ramp duration
    period: float = 1.0           # breath period
    expiration: float = 0.0       # tidal: expiration peak speed U_ex >= 0

    def __post_init__(self):
        if self.kind not in _KINDS:
            raise ValueError(f"schedule kind must be one of {_KINDS}, got {self.kind!r}")
        for name in ("ustar", "ustar_start", "duration", "period", "expiration"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"schedule {name} must be a finite number, got {value!r}")
        for name in ("ustar", "ustar_start", "expiration"):
            if abs(getattr(self, name)) > MAX_ABS_USTAR:
                raise ValueError(f"schedule {name} must lie in [-{MAX_ABS_USTAR:g}, "
                                 f"{MAX_ABS_USTAR:g}] (as Scene.ustar), got {getattr(self, name)}")
        if self.kind == "tidal" and (self.ustar < 0 or self.expiration < 0
                                     or self.ustar == self.expiration == 0):
            raise ValueError(f"a tidal breath takes the peak speeds of inspiration (ustar) "
                             f"and expiration, >= 0 and not both 0, got {self.ustar}, "
                             f"{self.expiration}")
        if self.duration <= 0 or self.period <= 0:
            raise ValueError(f"schedule duration and period must be > 0, got "
                             f"{self.duration}, {self.period}")

    @classmethod
    def constant(cls, ustar: float) -> "PressureSchedule":
        return cls("constant", ustar=ustar)

    @classmethod
    def ramp(cls, ustar_start: float, ustar_end: float, duration: float) -> "PressureSchedule":
        return cls("ramp", ustar=ustar_end, ustar_start=ustar_start, duration=duration)

    @classmethod
    def breath(cls, peak: float, period: float) -> "PressureSchedule":
        return cls("breath", ustar=peak, period=period)

    @classmethod
    def tidal(cls, inspiration: float, expiration: float, period: float) -> "PressureSchedule":
        """Whole breaths: up to U* = ``inspiration``, then down to -``expiration``."""
        return cls("tidal", ustar=inspiration, expiration=expiration, period=period)

    @property
    def reference_ustar(self) -> float:
        """The U* at which Δp is taken from the steady state (a tidal breath's
        inspiration peak, or its expiration peak -U_ex without inspiration)."""
        if self.kind == "tidal" and self.ustar == 0:
            return -self.expiration
        return self.ustar

    def vector(self, coefficient: float) -> np.ndarray:
        """The seven schedule parameters for a given ``c`` (module docstring)."""
        if self.kind == "constant":
            return np.array([coefficient, self.ustar, 0.0, 1.0, 0.0, 1.0, 0.0])
        if self.kind == "ramp":
            return np.array([coefficient, self.ustar_start, self.ustar - self.ustar_start,
                             self.duration, 0.0, 1.0, 0.0])
        if self.kind == "tidal":
            return np.array([coefficient, 0.0, 0.0, 1.0, (self.ustar - self.expiration) / 2,
                             self.period / 2, (self.ustar + self.expiration) / 2])
        return np.array([coefficient, 0.0, 0.0, 1.0, self.ustar, self.period, 0.0])

    def ustar_at(self, t) -> np.ndarray:
        """Quasi-steady U*(t) (NumPy)."""
        t = np.asarray(t, dtype=float)
        _, a, b, d, s, per, w = self.vector(1.0)
        wave = np.sin(np.pi * t / per)
        return a + b * np.minimum(t / d, 1.0) + s * np.abs(wave) + w * wave


def schedule_expression(t, sched):
    """CasADi Δp(t) from the schedule parameters ``sched`` (7-vector)."""
    c, a, b, d, s, per, w = (sched[i] for i in range(N_SCHEDULE_PARAMS))
    wave = ca.sin(np.pi * t / per)
    u = a + b * ca.fmin(t / d, 1.0) + s * ca.fabs(wave) + w * wave
    return c * u * ca.fabs(u)
