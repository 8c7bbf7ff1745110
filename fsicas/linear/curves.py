"""Curves of onsets in the (M*, U*) plane: a located Hopf point continued in (Π, log10 M*)
on the Hopf system (:class:`HopfCurve`, the curves of :mod:`fsicas.linear.boundary`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

import continuation as C

from ..model.assembly import Model
from ..scene import Scene
from .adapter import LOG_M, PI, PI_SCALE, TIME_SCALE
from .hopf import HopfPoint, dominant_mode, flutter_problem

__all__ = ["HopfCurve", "trace_hopf_curve"]


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
