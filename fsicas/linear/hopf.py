"""The onset: the first loss of stability of the steady branch in U*, through
``continuation`` — a Hopf point (flutter) or a real eigenvalue crossing zero (static
divergence, :mod:`fsicas.linear.divergence`).

The model is handed to the library through the adapter of :mod:`fsicas.linear.adapter`
(parameters Π = Δp/(M* PI_SCALE) and log10 M*, time in units of T/TIME_SCALE). The
steady branch is continued in Π from a small U*; each Hopf point found is located by the
library (Newton on the Hopf system), with its first Lyapunov coefficient l1 (< 0:
supercritical, a small stable cycle is born; > 0: subcritical, a jump to large amplitude
with hysteresis). The curves of onsets in (M*, U*) are in :mod:`fsicas.linear.curves`.

Reversed flow (U* < 0, ``Scene.direction`` "reverse") is searched the same way towards
negative U* and Π: ``ustar_start``, ``ustar_max`` and ``ustar_stop`` are speeds |U*| in
the scene's direction, and the onsets found carry the signed U*.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from typing import ClassVar, Literal

import numpy as np

import continuation as C

from ..model.assembly import Model, build_model
from ..scene import Scene
from .adapter import (LOG_M, PI, PI_SCALE, TIME_SCALE, dense, flutter_field, pi_interval, pi_of,
                      speed)
from .divergence import (DIVERGENCE_KINDS, DivergencePoint, divergence_between,
                         divergence_point_from)
from .stability import generalized_eigen
from .truncation import truncation_error, truncation_warning
from .steady import SteadyStateError, steady_state

__all__ = ["start_speed", "Criticality", "HopfPoint", "Onset", "CriticalVelocityError", "ModalTruncationWarning",
           "flutter_problem", "steady_branch", "hopf_points", "first_hopf", "critical_velocity",
           "first_onset", "onset_points",
           "ONSET_KINDS", "USTAR_START", "dominant_mode", "hopf_point_from", "eigenvector_q"]

#: Sign of the first Lyapunov coefficient at a Hopf point: l1 < 0 "supercritical" (a small
#: stable cycle is born), l1 > 0 "subcritical" (a jump to large amplitude, hysteresis).
Criticality = Literal["supercritical", "subcritical"]


class CriticalVelocityError(RuntimeError):
    """The steady branch could not be followed or was unstable where it starts; ``speed``:
    |U*| by which stability was lost with no special point located (first_onset retries)."""
    def __init__(self, message: str, speed: float | None = None):
        super().__init__(message)
        self.speed = speed


class ModalTruncationWarning(UserWarning):
    """The onset is not resolved by the modes kept: none was found below the search
    bound, or the flutter mode is the last mode kept (more modes may move it)."""


def _finite(value: float) -> float | None:
    return None if math.isnan(value) else value


def warn_if_truncated(scene: Scene, hopf, ustar_max: float) -> None:
    """A :class:`ModalTruncationWarning` when ``hopf`` (the onset found with
    ``scene.modes`` modes below ``ustar_max``) may be an artefact of the truncation:
    none found, or its truncation error (``hopf.truncation``) above the tolerance."""
    if hopf is None:
        warnings.warn(f"no onset of instability below U* = {ustar_max:g} (the search bound) at M* = "
                      f"{scene.mstar:g} with N = {scene.modes} modes: either it lies higher or "
                      "the modes kept do not resolve it (the flutter mode rises with M*); "
                      "check with a higher bound and more modes",
                      ModalTruncationWarning, stacklevel=3)
    elif (note := truncation_warning(scene, hopf, hopf.truncation)) is not None:
        warnings.warn(note, ModalTruncationWarning, stacklevel=3)


@dataclass(frozen=True)
class HopfPoint:
    """A located Hopf point of the steady branch."""

    mstar: float
    ustar: float
    pressure_drop: float
    omega: float
    freq_ratio: float
    l1: float
    dominant_mode: int
    precision: float
    x: np.ndarray = field(repr=False)
    point: object = field(repr=False, default=None)
    #: relative change of U* with twice the modes (:mod:`fsicas.linear.truncation`)
    truncation: float = math.nan

    kind: ClassVar[str] = "flutter"

    @property
    def supercritical(self) -> bool:
        return self.l1 < 0

    @property
    def criticality(self) -> Criticality:
        """"supercritical" (l1 < 0) or "subcritical" (otherwise, also for l1 = NaN)."""
        return "supercritical" if self.supercritical else "subcritical"

    def to_json(self) -> dict:
        return {"kind": self.kind, "mstar": self.mstar, "ustar_crit": self.ustar,
                "pressure_drop": self.pressure_drop,
                "omega": self.omega, "freq_ratio": self.freq_ratio, "l1": self.l1,
                "criticality": self.criticality,
                "dominant_mode": self.dominant_mode, "truncation": _finite(self.truncation)}


#: The onset of instability of the steady branch: flutter or divergence (``.kind``).
Onset = HopfPoint | DivergencePoint


def flutter_problem(scene: Scene, model: Model, ustar_start: float) -> C.EquilibriumProblem:
    """Equilibrium problem in Π from the steady state at the speed ``ustar_start`` in
    ``scene``'s direction."""
    st = steady_state(scene.replace(ustar=scene.flow_sign * ustar_start), model)
    vf = flutter_field(model)
    names = vf.par_names
    values = dict(zip(model.parameter_names, st.p))
    params = {PI: st.pressure_drop / (scene.mstar * PI_SCALE), LOG_M: math.log10(scene.mstar)}
    params.update({k: values[k] for k in names[2:]})
    return C.EquilibriumProblem(vf, st.x, params, PI)


def _settings(pi_start: float, pi_max: float, max_steps: int = 1000,
              stop_at: tuple = (), pi_stop: float | None = None,
              low_start: bool = False) -> C.ContinuationSettings:
    """Steps of at most pi_max/150 in Π (≈ U*^2): a pocket of stability between two Hopf
    points closer than one step would leave the unstable count unchanged and be missed,
    and two Hopf points in one step (near a crossing of Hopf curves) would be confused.
    The branch ends at ``pi_stop`` (default ``pi_max``); it runs towards negative Π
    when ``pi_max`` < 0 (reversed flow). With ``low_start`` (reversed flow, whose onsets
    lie at speeds ∝ M*^-1/2 from |U*| = 0.01 on) the first step is at most ``|pi_start|``:
    a first step of ``pi_max/600`` leapt over a whole window of divergence (M* = 1,
    H* = 0.05: unstable for |U*| in (0.2385, 1.5788), the step went from 0.01 to 3.77);
    from there the steps grow by the library's step control, limited by the eigenvalues'
    approach to the axis."""
    ds_max = abs(pi_max) / 150
    stop = pi_max if pi_stop is None or abs(pi_stop) >= abs(pi_max) else pi_stop
    ds = min(ds_max / 4, max(abs(pi_start), 1e-9 * abs(pi_max))) if low_start else ds_max / 4
    return C.ContinuationSettings(ds=ds, ds_min=1e-10 * abs(pi_max), ds_max=ds_max,
                                  max_steps=max_steps, bounds={PI: pi_interval(0.0, stop)},
                                  locate_tol=1e-12, stop_at=stop_at,
                                  direction=1 if pi_max > 0 else -1)


def dominant_mode(model: Model, q_part: np.ndarray) -> int:
    """1-based in-vacuo mode with the largest share of |q|^2 in a (complex) eigenvector."""
    return int(np.argmax(np.abs(q_part) ** 2)) + 1


def hopf_point_from(model: Model, scene: Scene, point) -> HopfPoint:
    x = np.asarray(point.x)
    omega = float(point.data["omega"]) * TIME_SCALE
    q = eigenvector_q(model, x, point.params, omega / TIME_SCALE)
    mstar = 10 ** point.params[LOG_M]
    return HopfPoint(mstar=mstar, ustar=float(x[-2:].sum() / scene.hstar),
                     pressure_drop=float(point.params[PI] * PI_SCALE * mstar), omega=omega,
                     freq_ratio=omega / model.omega_1,
                     l1=float(point.data.get("l1", np.nan)), dominant_mode=dominant_mode(model, q),
                     precision=float(point.precision), x=x, point=point)


def eigenvector_q(model: Model, x, params, omega) -> np.ndarray:
    """q-part of the eigenvector of ``J v = lambda M v`` (adapted field, time in units of
    T/TIME_SCALE) whose eigenvalue is nearest ``i omega`` at a Hopf point."""
    vf = flutter_field(model)
    p = np.array([params[k] for k in vf.par_names])
    lam, vec = generalized_eigen(dense(vf.jac_x(x, p)), dense(vf.mass(x, p)))
    k = int(np.argmin(np.abs(lam - 1j * omega)))
    n = model.n_modes
    return vec[n:2 * n, k]


def steady_branch(scene: Scene, model: Model, ustar_max: float, ustar_start: float | None = None, *,
                  stop_at: tuple = (), ustar_stop: float | None = None) -> C.Branch:
    """The steady branch continued in Π from ``ustar_start`` towards ``ustar_max`` (its
    special points located), ended at ``ustar_stop`` (< ustar_max, with the steps of
    ``ustar_max``) or past the first special point of a kind in ``stop_at``; the three
    are speeds |U*| in ``scene``'s direction (``ustar_start`` None: :func:`start_speed`).

    The Π bound is the steady state's at ``ustar_max``; where no steady state is found
    there (the branch may fold or be lost above the onset), it is extrapolated as
    ``Π ∝ U*^2`` from the start, with a margin, and points above ``ustar_max`` are not
    used by the callers. CriticalVelocityError when the start is already unstable."""
    ustar_start = start_speed(scene) if ustar_start is None else ustar_start
    if not 0 < ustar_start < ustar_max:
        raise ValueError(f"need 0 < ustar_start < ustar_max, got {ustar_start}, {ustar_max}")
    problem = flutter_problem(scene, model, ustar_start)
    pi_max = _pi_bound(scene, model, ustar_max, problem.X0[-1], ustar_start)
    pi_stop = None if ustar_stop is None or ustar_stop >= ustar_max else \
        _pi_bound(scene, model, ustar_stop, problem.X0[-1], ustar_start)
    branch = C.continuation(problem, settings=_settings(
        problem.X0[-1], pi_max, stop_at=stop_at, pi_stop=pi_stop,
        low_start=scene.direction == "reverse"))
    if branch.n_unstable is not None and len(branch.n_unstable) and branch.n_unstable[0] > 0:
        raise CriticalVelocityError(
            f"the steady state is already unstable at U* = {scene.flow_sign * ustar_start:g} "
            f"(M* = {scene.mstar:g}); lower ustar_start")
    return branch


#: The speed |U*| where the steady branch starts, below the first onset, by direction.
#: Reversed flow loses stability by divergence at a pressure drop independent of M*, so
#: at speeds ∝ M*^-1/2 (|U*| = 0.14 at M* = 10 in the paper's channel): it starts lower,
#: and above M* = 1 lower still (:func:`start_speed`).
USTAR_START = {"forward": 0.2, "reverse": 0.01}


def start_speed(scene: Scene) -> float:
    """The speed |U*| the steady branch starts from: :data:`USTAR_START`, for reversed
    flow divided by sqrt(M*) above M* = 1 (the same pressure drop M* U*^2 as at M* = 1:
    at M* = 1e4 the paper's channel diverges at |U*| = 0.0045, below 0.01)."""
    start = USTAR_START[scene.direction]
    return start / math.sqrt(max(1.0, scene.mstar)) if scene.direction == "reverse" else start


def _pi_bound(scene: Scene, model: Model, ustar: float, pi_start: float, ustar_start: float) -> float:
    """Π at the speed ``ustar``: the steady state's, or (none found there) the margin
    :data:`PI_MARGIN` times ``pi_start (ustar / ustar_start)^2``."""
    try:
        return pi_of(scene, model, scene.flow_sign * ustar)
    except SteadyStateError:
        return PI_MARGIN * pi_start * (ustar / ustar_start) ** 2


#: Margin of the extrapolated Π bound (:func:`_pi_bound`) over ``Π ∝ U*^2``.
PI_MARGIN = 1.5


def _lost(scene: Scene, branch: C.Branch, ustar_max: float) -> None:
    """CriticalVelocityError when the branch was lost (the corrector failed) below
    ``ustar_max``."""
    if branch.status == "failed" and speed(scene, branch.x[-1]) < ustar_max:
        raise CriticalVelocityError(f"steady branch lost at M* = {scene.mstar:g}, U* = "
                                    f"{branch.x[-1, -2:].sum() / scene.hstar:.6g}: {branch.message}")


def hopf_points(scene: Scene, model: Model | None = None, ustar_max: float = 40.0,
                ustar_start: float | None = None, *, first_only: bool = False,
                ustar_stop: float | None = None) -> list[HopfPoint]:
    """All Hopf points of the steady branch for U* in (ustar_start, ustar_max), in order;
    with ``first_only`` the branch ends at the step past the first one (and the list
    holds the Hopf points of that step only). ``ustar_stop`` (< ustar_max) ends the
    branch there, with the steps of ``ustar_max``: the Hopf points below it are those of
    the full search (same steps), the ones above it are not searched."""
    model = model or build_model(scene)
    branch = steady_branch(scene, model, ustar_max, ustar_start,
                           stop_at=("hopf",) if first_only else (), ustar_stop=ustar_stop)
    points = [hopf_point_from(model, scene, h) for h in branch.special("hopf")]
    points = [h for h in points if abs(h.ustar) <= ustar_max]
    if not (first_only and points):
        _lost(scene, branch, ustar_max)
    return points


def first_hopf(scene: Scene, model: Model | None = None, ustar_max: float = 40.0,
               ustar_start: float | None = None) -> HopfPoint | None:
    """The first Hopf point of the steady branch below ``ustar_max`` (None if none),
    whether or not the steady state lost its stability statically before it."""
    points = hopf_points(scene, model, ustar_max, ustar_start, first_only=True)
    return points[0] if points else None


#: The special points of the steady branch where it may lose its stability.
ONSET_KINDS = ("hopf", *DIVERGENCE_KINDS)


def critical_velocity(scene: Scene, model: Model | None = None, ustar_max: float = 40.0,
                      ustar_start: float | None = None) -> Onset | None:
    """The onset: the first loss of stability of the steady branch below ``ustar_max``,
    whatever its kind (``.kind``): a Hopf point (``"flutter"``, a :class:`HopfPoint`) or a
    real eigenvalue crossing zero (``"divergence"``, a :class:`DivergencePoint`); None
    if the branch stays stable. Its ``truncation``: the relative change of U*_c with
    twice the modes (:mod:`fsicas.linear.truncation`); a :class:`ModalTruncationWarning`
    when that exceeds its tolerance or no onset is found."""
    model = model or build_model(scene)
    onset = first_onset(scene, model, ustar_max, ustar_start)
    if onset is not None:
        onset = replace(onset, truncation=truncation_error(scene, model, onset))
    warn_if_truncated(scene, onset, ustar_max)
    return onset


def first_onset(scene: Scene, model: Model | None = None, ustar_max: float = 40.0,
                ustar_start: float | None = None) -> Onset | None:
    """:func:`critical_velocity` without the truncation warning.

    The branch stops past its first special point; where that one leaves the branch
    stable (a branch point rejected on re-evaluation can), the search goes on from there.
    Where stability is lost in a step with no special point located (the step, of
    ``ustar_max``'s size, jumped across a fold onto another branch: a reversed onset far
    below ``ustar_max`` in an asymmetric channel), the search is repeated with the bound
    (and so the steps) cut to :data:`REFINE` times the speed at that step's end."""
    model = model or build_model(scene)
    bound = ustar_max
    for attempt in range(REFINEMENTS + 1):
        try:
            return _first_onset(scene, model, bound, ustar_start)
        except CriticalVelocityError as err:
            if attempt == REFINEMENTS or err.speed is None or REFINE * err.speed >= bound:
                raise
            bound = REFINE * err.speed


#: A repeated onset search: its bound over the speed of the unlocated loss; repeats at most.
REFINE, REFINEMENTS = 1.5, 3


def _first_onset(scene: Scene, model: Model, ustar_max: float, ustar_start: float | None
                 ) -> Onset | None:
    """:func:`first_onset` on the steps of ``ustar_max``."""
    start = ustar_start
    for _ in range(MAX_RESTARTS):
        branch = steady_branch(scene, model, ustar_max, start, stop_at=ONSET_KINDS)
        onset = _first_loss(model, scene, branch)
        if onset is not None or branch.status != "stopped":
            break
        start = speed(scene, branch.x[-1])
    if onset is not None and abs(onset.ustar) > ustar_max:
        onset = None
    if onset is None:
        _lost(scene, branch, ustar_max)
    elif onset.kind == "divergence" and onset.point is None:
        onset = _relocated(scene, model, onset, ustar_max)
    return onset


def _relocated(scene: Scene, model: Model, onset: DivergencePoint, ustar_max: float
               ) -> DivergencePoint:
    """A divergence solved between two steps (:func:`_first_loss`) located again by the
    library from 1 % below it, so that it carries its point of the steady branch (the
    start of the deflected branches); the solved one if that fails."""
    branch = steady_branch(scene, model, ustar_max, RELOCATE * abs(onset.ustar),
                           stop_at=ONSET_KINDS)
    for point in branch.special_points:
        if point.kind in DIVERGENCE_KINDS and point.status == "converged" and \
                abs(point.x[-2:].sum() / scene.hstar / onset.ustar - 1) < 1e-8:
            return divergence_point_from(model, scene, point)
    return onset


#: Where a divergence solved between two steps is located again from (its U* times this).
RELOCATE = 0.99


def onset_points(scene: Scene, model: Model | None = None, ustar_max: float = 40.0,
                 ustar_start: float | None = None, *, ustar_stop: float | None = None) -> list[Onset]:
    """Every Hopf point and every located divergence of the steady branch for U* in
    (ustar_start, ustar_max), in order of U* (``ustar_stop`` as in :func:`hopf_points`):
    where the branch loses or regains stability, or an unstable one changes."""
    model = model or build_model(scene)
    branch = steady_branch(scene, model, ustar_max, ustar_start, ustar_stop=ustar_stop)
    points = [_onset_from(model, scene, p) for p in branch.special_points
              if p.kind == "hopf" or (p.kind in DIVERGENCE_KINDS and p.status == "converged")]
    _lost(scene, branch, ustar_max)
    return sorted((p for p in points if abs(p.ustar) <= ustar_max), key=lambda p: abs(p.ustar))


def _onset_from(model: Model, scene: Scene, point) -> Onset:
    """The HopfPoint or DivergencePoint of a special point of the steady branch."""
    if point.kind == "hopf":
        return hopf_point_from(model, scene, point)
    return divergence_point_from(model, scene, point)


#: Restarts of the onset search past special points that leave the branch stable.
MAX_RESTARTS = 20


def _first_loss(model: Model, scene: Scene, branch: C.Branch) -> Onset | None:
    """The special point (the lowest in U* of those in that step) of the first step
    after which the branch has an unstable eigenvalue; None if it stays stable. A
    divergence the library did not locate is solved between the step's ends in U*.
    CriticalVelocityError when no special point was located in that step."""
    unstable = np.flatnonzero(branch.n_unstable > 0)
    if not unstable.size:
        return None
    step = int(unstable[0])
    found = [p for p in branch.special_points if p.index == step and p.kind in ONSET_KINDS]
    if not found:
        raise CriticalVelocityError(
            f"the steady state loses its stability between U* = "
            f"{branch.x[step - 1, -2:].sum() / scene.hstar:.6g} and "
            f"{branch.x[step, -2:].sum() / scene.hstar:.6g} (M* = {scene.mstar:g}) but no "
            "Hopf, branch or fold point was located there",
            speed=max(speed(scene, branch.x[step - 1]), speed(scene, branch.x[step])))
    first = min(found, key=lambda p: speed(scene, p.x))
    if first.kind in DIVERGENCE_KINDS and first.status != "converged":
        # the library's location failed: the divergence lies between the two steps
        lo, hi = (float(branch.x[k, -2:].sum() / scene.hstar) for k in (step - 1, step))
        located = divergence_between(scene, model, lo, hi)
        if located is not None:
            return located
    return _onset_from(model, scene, first)
