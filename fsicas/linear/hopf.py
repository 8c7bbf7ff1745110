"""Flutter onset: Hopf points of the steady branch in U*, through ``continuation``.

The model is handed to the library through the adapter of :mod:`fsicas.linear.adapter`
(parameters Π = Δp/(M* PI_SCALE) and log10 M*, time in units of T/TIME_SCALE). The
steady branch is continued in Π from a small U*; each Hopf point found is located by the
library (Newton on the Hopf system), with its first Lyapunov coefficient l1 (< 0:
supercritical, a small stable cycle is born; > 0: subcritical, a jump to large amplitude
with hysteresis). A located Hopf point is continued in (Π, log10 M*) as a Hopf curve
(:func:`trace_hopf_curve`, the curves of :mod:`fsicas.linear.boundary`).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal

import numpy as np

import continuation as C

from ..model.assembly import Model, build_model
from ..scene import Scene
from .adapter import LOG_M, PI, PI_SCALE, TIME_SCALE, dense, flutter_field, pi_of
from .stability import generalized_eigen
from .steady import steady_state

__all__ = ["Criticality", "HopfPoint", "CriticalVelocityError", "ModalTruncationWarning", "flutter_problem", "hopf_points",
           "critical_velocity", "dominant_mode", "hopf_point_from", "eigenvector_q", "HopfCurve",
           "trace_hopf_curve"]

#: Sign of the first Lyapunov coefficient at a Hopf point: l1 < 0 "supercritical" (a small
#: stable cycle is born), l1 > 0 "subcritical" (a jump to large amplitude, hysteresis).
Criticality = Literal["supercritical", "subcritical"]


class CriticalVelocityError(RuntimeError):
    """The steady branch could not be followed or was unstable where it starts."""


class ModalTruncationWarning(UserWarning):
    """The onset is not resolved by the modes kept: none was found below the search
    bound, or the flutter mode is the last mode kept (more modes may move it)."""


def warn_if_truncated(scene: Scene, hopf: "HopfPoint | None", ustar_max: float) -> None:
    """A :class:`ModalTruncationWarning` when ``hopf`` (the onset found with
    ``scene.modes`` modes below ``ustar_max``) may be an artefact of the truncation."""
    if hopf is None:
        warnings.warn(f"no flutter onset below U* = {ustar_max:g} (the search bound) at M* = "
                      f"{scene.mstar:g} with N = {scene.modes} modes: either it lies higher or "
                      "the modes kept do not resolve it (the flutter mode rises with M*); "
                      "check with a higher bound and more modes",
                      ModalTruncationWarning, stacklevel=3)
    elif hopf.dominant_mode >= scene.modes:
        warnings.warn(f"the flutter mode at M* = {scene.mstar:g} is mode {hopf.dominant_mode}, "
                      f"the last of the N = {scene.modes} kept: the onset U*_c = "
                      f"{hopf.ustar:.4g} is not resolved by this truncation; raise modes",
                      ModalTruncationWarning, stacklevel=3)


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

    @property
    def supercritical(self) -> bool:
        return self.l1 < 0

    @property
    def criticality(self) -> Criticality:
        """"supercritical" (l1 < 0) or "subcritical" (otherwise, also for l1 = NaN)."""
        return "supercritical" if self.supercritical else "subcritical"

    def to_json(self) -> dict:
        return {"mstar": self.mstar, "ustar_crit": self.ustar, "pressure_drop": self.pressure_drop,
                "omega": self.omega, "freq_ratio": self.freq_ratio, "l1": self.l1,
                "criticality": self.criticality,
                "dominant_mode": self.dominant_mode}


def flutter_problem(scene: Scene, model: Model, ustar_start: float) -> C.EquilibriumProblem:
    """Equilibrium problem in Π from the steady state at ``ustar_start``."""
    st = steady_state(scene.replace(ustar=ustar_start), model)
    vf = flutter_field(model)
    names = vf.par_names
    values = dict(zip(model.parameter_names, st.p))
    params = {PI: st.pressure_drop / (scene.mstar * PI_SCALE), LOG_M: math.log10(scene.mstar)}
    params.update({k: values[k] for k in names[2:]})
    return C.EquilibriumProblem(vf, st.x, params, PI)


def _settings(pi_start: float, pi_max: float, max_steps: int = 1000,
              stop_at: tuple = (), pi_stop: float | None = None) -> C.ContinuationSettings:
    """Steps of at most pi_max/150 in Π (≈ U*^2): a pocket of stability between two Hopf
    points closer than one step would leave the unstable count unchanged and be missed,
    and two Hopf points in one step (near a crossing of Hopf curves) would be confused.
    The branch ends at ``pi_stop`` (default ``pi_max``)."""
    ds_max = pi_max / 150
    stop = pi_max if pi_stop is None else min(pi_stop, pi_max)
    return C.ContinuationSettings(ds=ds_max / 4, ds_min=1e-10 * pi_max, ds_max=ds_max,
                                  max_steps=max_steps, bounds={PI: (0.0, stop)},
                                  locate_tol=1e-12, stop_at=stop_at)


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


def hopf_points(scene: Scene, model: Model | None = None, ustar_max: float = 40.0,
                ustar_start: float = 0.2, *, first_only: bool = False,
                ustar_stop: float | None = None) -> list[HopfPoint]:
    """All Hopf points of the steady branch for U* in (ustar_start, ustar_max), in order;
    with ``first_only`` the branch ends at the step past the first one (and the list
    holds the Hopf points of that step only). ``ustar_stop`` (< ustar_max) ends the
    branch there, with the steps of ``ustar_max``: the Hopf points below it are those of
    the full search (same steps), the ones above it are not searched."""
    if not 0 < ustar_start < ustar_max:
        raise ValueError(f"need 0 < ustar_start < ustar_max, got {ustar_start}, {ustar_max}")
    model = model or build_model(scene)
    problem = flutter_problem(scene, model, ustar_start)
    pi_max = pi_of(scene, model, ustar_max)
    pi_stop = None if ustar_stop is None or ustar_stop >= ustar_max else \
        pi_of(scene, model, ustar_stop)
    stop_at = ("hopf",) if first_only else ()
    branch = C.continuation(problem, settings=_settings(problem.X0[-1], pi_max, stop_at=stop_at,
                                                        pi_stop=pi_stop))
    if branch.status == "failed":
        raise CriticalVelocityError(f"steady branch lost at M* = {scene.mstar:g}: {branch.message}")
    if branch.n_unstable is not None and len(branch.n_unstable) and branch.n_unstable[0] > 0:
        raise CriticalVelocityError(
            f"the steady state is already unstable at U* = {ustar_start:g} (M* = {scene.mstar:g}); "
            "lower ustar_start")
    return [hopf_point_from(model, scene, h) for h in branch.special("hopf")]


def critical_velocity(scene: Scene, model: Model | None = None, ustar_max: float = 40.0,
                      ustar_start: float = 0.2) -> HopfPoint | None:
    """The first Hopf point (flutter onset) of the steady branch, or None below ustar_max;
    a :class:`ModalTruncationWarning` when the modes kept may not resolve it."""
    points = hopf_points(scene, model, ustar_max, ustar_start, first_only=True)
    hopf = points[0] if points else None
    warn_if_truncated(scene, hopf, ustar_max)
    return hopf


@dataclass(frozen=True)
class HopfCurve:
    """A traced Hopf curve: arrays along the curve (ordered by arclength). ``status``:
    "bound" when both halves ran to the window's bounds (or were ended by the tracing's
    ``stop`` predicate), else the library's status of the half that stopped first
    (``message`` says why)."""

    index: int
    mstar: np.ndarray
    ustar: np.ndarray
    omega: np.ndarray
    dominant_mode: np.ndarray
    status: C.Status
    first_piece: int = 0
    states: np.ndarray = field(default=None, repr=False)   # steady states along the curve
    params: np.ndarray = field(default=None, repr=False)   # adapter parameters along it
    message: str = ""

    def guess(self, log_m: float, piece: int) -> tuple[np.ndarray, np.ndarray, float]:
        """Interpolated (state, params, omega) on ``piece`` at log10 M* = log_m."""
        lm = np.log10(self.mstar)
        for i in np.flatnonzero(self.pieces == piece):   # pieces are per segment
            a, b = lm[i], lm[i + 1]
            if (a - log_m) * (b - log_m) <= 0 and a != b:
                t = (log_m - a) / (b - a)
                mix = lambda arr: arr[i] + t * (arr[i + 1] - arr[i])
                return mix(self.states), mix(self.params), float(mix(self.omega))
        raise ValueError(f"piece {piece} does not reach log10 M* = {log_m}")

    @property
    def pieces(self) -> np.ndarray:
        """Branch id of each segment (length = points - 1): a new id after every fold in M*
        (the lower envelope jumps between pieces, even of one curve)."""
        return self._pieces.copy()

    @cached_property
    def _pieces(self) -> np.ndarray:
        step = np.sign(np.diff(np.log10(self.mstar)))
        turns = np.concatenate([[0], np.cumsum(step[1:] * step[:-1] < 0)])
        return self.first_piece + turns

    @cached_property
    def segments(self) -> tuple:
        """Ends of the segments in log10 M*, U* and omega (arrays of length points - 1)."""
        lm = np.log10(self.mstar)
        ends = lambda arr: (arr[:-1], arr[1:])
        return ends(lm), ends(self.ustar), ends(self.omega)

    def crossings(self, log_m: float) -> list[tuple[float, float, int]]:
        """(U*, omega, piece) where the curve passes log10 M* = log_m (linear interpolation)."""
        (a, b), (ua, ub), (wa, wb) = self.segments
        i = np.flatnonzero(((a - log_m) * (b - log_m) <= 0) & (a != b))
        t = (log_m - a[i]) / (b[i] - a[i])
        u, w = ua[i] + t * (ub[i] - ua[i]), wa[i] + t * (wb[i] - wa[i])
        return [(float(uk), float(wk), int(pk)) for uk, wk, pk in zip(u, w, self._pieces[i])]


def trace_hopf_curve(scene: Scene, model: Model, h: HopfPoint, index: int, window, ustar_max: float,
                     first_piece: int = 0, make_stop=None) -> HopfCurve:
    """Continue the Hopf curve through h both ways inside the (log10 M*, U*) window
    (log10 M* in ``window``, U* up to ``ustar_max``), in (Π, log10 M*). ``make_stop()``
    (optional) returns for each half a ``continuation`` stop predicate that may end it
    earlier."""
    problem = flutter_problem(scene.replace(mstar=h.mstar), model, ustar_start=0.2)
    pi_max = _pi_max(h, ustar_max)
    halves, status, message = [], "bound", ""
    for direction in (-1, 1):
        settings = C.ContinuationSettings(
            ds=0.05, ds_min=1e-8, ds_max=0.3, max_steps=300, direction=direction,
            bounds={LOG_M: window, PI: (0.0, pi_max)}, detect=False, compute_eigenvalues=False,
            newton=C.NewtonSettings(tol=1e-8))   # curve points only guide; points are refined
        branch = C.continuation(C.HopfCurveProblem.from_point(problem, h.point, LOG_M),
                                settings=settings, record=_mode_recorder(model),
                                stop=make_stop() if make_stop else None)
        if branch.status not in ("bound", "stopped") and status == "bound":
            status, message = branch.status, branch.message
        halves.append(branch)
    lower, upper = halves
    join = lambda a, b: np.concatenate([a[::-1], b[1:]])
    x, params = join(lower.x, upper.x), join(lower.params, upper.params)
    kappa = join(lower.columns["kappa"], upper.columns["kappa"])
    keep = kappa > 0           # neutral-saddle stretches are not Hopf points
    x, params, omega = x[keep], params[keep], np.sqrt(kappa[keep])
    names = lower.par_names
    modes = join(lower.columns["mode"], upper.columns["mode"])[keep].astype(int)
    lm = params[:, names.index(LOG_M)]
    return HopfCurve(index, 10 ** lm, x[:, -2:].sum(axis=1) / scene.hstar, omega * TIME_SCALE,
                     modes, status, int(first_piece), x, params, message)


def _mode_recorder(model):
    """``record`` hook of a Hopf curve: the dominant mode of the eigenvector
    ``q = v - i w / omega`` of ``i omega`` carried by the unknowns ``X = (x, v, w, kappa,
    ...)`` (0 where ``kappa <= 0``), instead of an eigen-decomposition per point."""
    n = model.n_modes

    def record(problem, X):
        m, kappa = problem.vf.n, X[3 * problem.vf.n]
        if kappa <= 0:
            return {"mode": 0.0}
        q = X[m: 2 * m] - 1j * X[2 * m: 3 * m] / np.sqrt(kappa)
        return {"mode": float(dominant_mode(model, q[n: 2 * n]))}

    return record


def _pi_max(h: HopfPoint, ustar_max: float) -> float:
    """Π bound equivalent to U* <= ustar_max, scaled from the Hopf point (Π ∝ U*^2)."""
    pi_h = h.pressure_drop / (h.mstar * PI_SCALE)
    return pi_h * (ustar_max / h.ustar) ** 2
