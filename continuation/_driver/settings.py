"""Immutable, validated settings: Newton, eigenvalues, PALC and continuation (those of
periodic orbits: ``_cycles.settings``).

All classes are frozen dataclasses checked at construction; "changing" one is
``dataclasses.replace(settings, ds=...)``. A bad value raises ``ValueError``
naming the field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping


def positive(obj, *names):
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"{type(obj).__name__}.{name} must be a positive finite "
                             f"number, got {value!r}")


def positive_int(obj, *names):
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, int) and not isinstance(value, bool) and value > 0):
            raise ValueError(f"{type(obj).__name__}.{name} must be a positive integer, "
                             f"got {value!r}")


@dataclass(frozen=True)
class NewtonSettings:
    """Newton corrector, at most ``max_iter`` iterations.

    Converged when ``||G(X)||_inf <= tol``, or when the last update is at
    round-off level, ``||dX||_inf <= xtol (1 + ||X||_inf)`` (a scale-aware test
    for badly scaled residuals whose round-off floor exceeds ``tol``; set
    ``xtol = 0`` to disable). The iteration aborts early when the residual
    exceeds ``divergence * (1 + initial residual)`` or is not finite.

    ``contraction``: the factors of a Jacobian are kept for the next step (chord) while
    each step shrinks the residual at least by this factor; 0 refactorizes at every
    step (Newton's method).
    """

    tol: float = 1e-10
    max_iter: int = 10
    divergence: float = 1e8
    xtol: float = 1e-13
    contraction: float = 1e-3

    def __post_init__(self):
        positive(self, "tol", "divergence")
        positive_int(self, "max_iter")
        if not (math.isfinite(self.xtol) and self.xtol >= 0):
            raise ValueError(f"NewtonSettings.xtol must be >= 0, got {self.xtol!r}")
        if not 0 <= self.contraction < 1:
            raise ValueError("NewtonSettings.contraction must be in [0, 1), got "
                             f"{self.contraction!r}")


@dataclass(frozen=True)
class EigenSettings:
    """Generalized eigenvalues ``J v = lambda M v`` at each point.

    Dense ``scipy.linalg.eig`` when ``n <= dense_max``; otherwise ``nev``
    eigenvalues closest to the real shift ``sigma`` by shift-invert Arnoldi on
    ``(J - sigma M)^{-1} M``. ``imag_tol`` separates real from complex ones.
    """

    nev: int = 8
    sigma: float = 0.0
    dense_max: int = 400
    imag_tol: float = 1e-9

    def __post_init__(self):
        positive_int(self, "nev", "dense_max")
        positive(self, "imag_tol")
        if not math.isfinite(self.sigma):
            raise ValueError(f"EigenSettings.sigma must be finite, got {self.sigma!r}")


@dataclass(frozen=True)
class PALC:
    """Pseudo-arclength continuation (Keller).

    Corrector: Newton on ``G(X) = 0``, ``tau_k . (X - X_k) - ds = 0``.
    Tangent ``'bordered'``: solve ``[G_X; tau_k^T] tau = e_{m+1}`` and normalize
    (orientation follows ``tau_k``); ``'secant'``: ``(X_{k+1} - X_k)/|.|``.
    """

    tangent: str = "bordered"

    def __post_init__(self):
        if self.tangent not in ("bordered", "secant"):
            raise ValueError(f"PALC.tangent must be 'bordered' or 'secant', got "
                             f"{self.tangent!r}")


@dataclass(frozen=True)
class ContinuationSettings:
    """Step control, stopping rules and detection switches of one continuation.

    ds : initial arclength step; ``ds_min <= |ds| <= ds_max``.
    direction : +1 or -1, sign of the initial change of the continuation parameter.
    max_steps : maximum number of computed points after the initial one.
    bounds : ``{name: (lo, hi)}``; the run stops when a free parameter leaves it.
    step_grow, step_shrink : factor applied after an easy step (Newton in at
        most ``easy_iterations`` iterations) / after a failed corrector.
    detect : compute test functions and locate special points.
    stop_at : kinds of special points (e.g. ``("hopf",)``) that end the run at the
        step past the first one found (status 'stopped'): nothing further is computed.
    locate_tol : arclength tolerance of the special-point location.
    eigen_step : with eigenvalues computed, the next step is also limited so that, by
        the rate of the last step, no complex eigenvalue moving towards the imaginary
        axis lands further past it than this fraction of its predicted distance to it
        (``_equilibria.eigen.step_limit``): a pair that crosses and crosses back within what would
        be one step (a narrow window) is met inside the window, not jumped over, while
        a pair that keeps its course is crossed in one step. 0 turns the limit off.
    max_turn : largest angle (radians) between the tangents of two successive points;
        a step turning more is rejected and retried shorter (0: off, the default). A
        step that jumps over a sharp fold lands on the far side with a tangent oriented
        by the old one, i.e. backwards, and the branch then retraces itself; the
        turn of the tangent gives it away.
    progress : show a tqdm progress bar (off by default).
    """

    ds: float = 0.01
    ds_min: float = 1e-7
    ds_max: float = 0.1
    direction: int = 1
    max_steps: int = 200
    bounds: Mapping[str, tuple] = field(default_factory=dict)
    newton: NewtonSettings = field(default_factory=NewtonSettings)
    eigen: EigenSettings = field(default_factory=EigenSettings)
    step_grow: float = 1.5
    step_shrink: float = 0.5
    easy_iterations: int = 3
    detect: bool = True
    stop_at: tuple = ()
    compute_eigenvalues: bool = True
    locate_tol: float = 1e-10
    locate_max_iter: int = 60
    eigen_step: float = 0.1
    max_turn: float = 0.0
    progress: bool = False

    def __post_init__(self):
        positive(self, "ds", "ds_min", "ds_max", "step_grow", "locate_tol")
        positive_int(self, "max_steps", "easy_iterations", "locate_max_iter")
        if not self.ds_min <= self.ds <= self.ds_max:
            raise ValueError(f"ContinuationSettings.ds must satisfy ds_min <= ds <= "
                             f"ds_max, got ds_min={self.ds_min}, ds={self.ds}, "
                             f"ds_max={self.ds_max}")
        if self.direction not in (1, -1):
            raise ValueError(f"ContinuationSettings.direction must be +1 or -1, got "
                             f"{self.direction!r}")
        if not (isinstance(self.eigen_step, (int, float)) and 0 <= self.eigen_step <= 1):
            raise ValueError("ContinuationSettings.eigen_step must be in [0, 1] (0: off), got "
                             f"{self.eigen_step!r}")
        if not (isinstance(self.max_turn, (int, float)) and 0 <= self.max_turn <= math.pi):
            raise ValueError("ContinuationSettings.max_turn must be an angle in [0, pi] "
                             f"(0: off), got {self.max_turn!r}")
        if not 0 < self.step_shrink < 1 or self.step_grow < 1:
            raise ValueError("ContinuationSettings.step_shrink must be in (0, 1) and "
                             f"step_grow >= 1, got {self.step_shrink}, {self.step_grow}")
        if not isinstance(self.newton, NewtonSettings):
            raise ValueError("ContinuationSettings.newton must be a NewtonSettings")
        if not isinstance(self.eigen, EigenSettings):
            raise ValueError("ContinuationSettings.eigen must be an EigenSettings")
        object.__setattr__(self, "bounds", MappingProxyType(_check_bounds(self.bounds)))
        if not (isinstance(self.stop_at, tuple) and all(isinstance(k, str) for k in self.stop_at)):
            raise ValueError("ContinuationSettings.stop_at must be a tuple of special-point "
                             f"kinds (str), got {self.stop_at!r}")


def _check_bounds(bounds) -> dict:
    checked = {}
    for name, pair in dict(bounds).items():
        try:
            lo, hi = (float(v) for v in pair)
        except (TypeError, ValueError):
            raise ValueError(f"ContinuationSettings.bounds[{name!r}] must be a pair "
                             f"(lo, hi), got {pair!r}") from None
        if not lo < hi:
            raise ValueError(f"ContinuationSettings.bounds[{name!r}] needs lo < hi, "
                             f"got ({lo}, {hi})")
        checked[str(name)] = (lo, hi)
    return checked
