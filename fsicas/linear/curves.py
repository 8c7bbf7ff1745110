"""Curves of onsets in the (M*, U*) plane (:class:`OnsetCurve`, the curves of
:mod:`fsicas.linear.boundary`):

- a Hopf curve: a located Hopf point continued in (Π, log10 M*) on the Hopf system;
- a divergence curve: a located divergence followed in log10 M* in steps of
  :data:`DIVERGENCE_STEP` decades, each point solved at its M* on the sign change of the
  real eigenvalue nearest 0 (:func:`fsicas.linear.divergence.divergence_at`), from the
  log-log extrapolation of the last two. It ends where none is bracketed near the
  extrapolation (two divergences merge: the window of divergence closes).

The curves carry the signed U* (< 0 for reversed flow); lowest means the smallest speed
|U*|, and ``ustar_max`` is a speed.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

import continuation as C

from ..model.assembly import Model
from ..scene import Scene
from .adapter import LOG_M, PI, PI_SCALE, TIME_SCALE, flutter_field, pi_interval
from .divergence import DivergencePoint, divergence_at
from .hopf import HopfPoint, Onset, dominant_mode, flutter_problem, hopf_point_from

__all__ = ["OnsetCurve", "Envelope", "trace_hopf_curve", "trace_divergence_curve",
           "onset_on_curve", "DIVERGENCE_STEP"]

#: Step of a divergence curve in log10 M*.
DIVERGENCE_STEP = 0.05


@dataclass(frozen=True)
class OnsetCurve:
    """A traced curve of onsets of one ``kind``: "flutter" (Hopf points) or "divergence"
    (``omega`` = 0; no ``states``, ``params``); arrays along the curve (ordered by
    arclength). ``status``: "bound" when both halves ran to the window's bounds (or were
    ended by the tracing's ``stop`` predicate), else the status of the half that stopped
    first (``message`` says why)."""

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
    kind: str = "flutter"

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
        if not step.size:        # a curve of one point has no segment (and no piece)
            return np.zeros(0, dtype=int)
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
                     first_piece: int = 0, make_stop=None) -> OnsetCurve:
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
            bounds={LOG_M: window, PI: pi_interval(0.0, pi_max)}, detect=False,
            compute_eigenvalues=False,
            newton=C.NewtonSettings(tol=1e-8))   # curve points only guide; points are refined
        branch = C.continuation(C.HopfCurveProblem.from_point(problem, h.point, LOG_M),
                                settings=settings, record=_mode_recorder(model),
                                stop=make_stop() if make_stop else None)
        if branch.status not in ("bound", "stopped") and status == "bound":
            status = branch.status
            message = f"from M* = {h.mstar:.4g}, U* = {h.ustar:.5g}: {branch.message}"
        halves.append(branch)
    lower, upper = halves
    join = lambda a, b: np.concatenate([a[::-1], b[1:] if len(a) else b])
    x, params = join(lower.x, upper.x), join(lower.params, upper.params)
    kappa = join(*(np.asarray(b.columns.get("kappa", ())) for b in halves))
    keep = kappa > 0           # neutral-saddle stretches are not Hopf points
    x, params, omega = x[keep], params[keep], np.sqrt(kappa[keep])
    names = lower.par_names
    modes = join(*(np.asarray(b.columns.get("mode", ())) for b in halves))[keep].astype(int)
    lm = params[:, names.index(LOG_M)]
    return OnsetCurve(index, 10 ** lm, x[:, -2:].sum(axis=1) / scene.hstar, omega * TIME_SCALE,
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


def trace_divergence_curve(scene: Scene, model: Model, d: DivergencePoint, index: int, window,
                           ustar_max: float, first_piece: int = 0, make_check=None) -> OnsetCurve:
    """Follow the divergence ``d`` both ways in log10 M* inside ``window``, up to U* =
    ``ustar_max`` (module docstring). ``make_check()`` (optional) returns for each half a
    ``check(ustar, log10_mstar)`` that ends it where it returns a true value (a message)."""
    halves, status, message = [], "bound", ""
    for direction in (-1, 1):
        points, why, text = _divergence_half(scene, model, d, direction, window, ustar_max,
                                             make_check() if make_check else None)
        if why not in ("bound", "stopped") and status == "bound":
            status, message = why, text
        halves.append(points)
    points = halves[0][::-1] + halves[1][1:]
    column = lambda name: np.array([getattr(p, name) for p in points], dtype=float)
    return OnsetCurve(index, column("mstar"), column("ustar"), np.zeros(len(points)),
                      column("dominant_mode").astype(int), status, int(first_piece),
                      message=message, kind="divergence")


def _divergence_half(scene, model, d, direction, window, ustar_max, check):
    """The points of one half of a divergence curve, why it ended and the message."""
    points = [d]
    while True:
        lm = np.log10([p.mstar for p in points[-2:]])
        edge = window[0] if direction < 0 else window[1]
        if lm[-1] == edge:
            return points, "bound", ""
        step = direction * DIVERGENCE_STEP
        nxt = min(lm[-1] + step, edge) if direction > 0 else max(lm[-1] + step, edge)
        u = np.log([abs(p.ustar) for p in points[-2:]])
        slope = (u[-1] - u[0]) / (lm[-1] - lm[0]) if len(points) > 1 else 0.0
        guess = scene.flow_sign * float(np.exp(u[-1] + slope * (nxt - lm[-1])))
        p = divergence_at(scene.replace(mstar=float(10 ** nxt)), model, guess)
        if p is None:
            return points, "failed", (f"no divergence bracketed near U* = {guess:.6g} at "
                                      f"M* = {10 ** nxt:.6g}")
        points.append(p)
        why = check(p.ustar, nxt) if check else False
        if abs(p.ustar) > ustar_max or why:
            return points, "stopped", why or ""


def onset_on_curve(scene: Scene, model: Model, curve: OnsetCurve, piece: int,
                   log_m: float) -> Onset | None:
    """The exact onset of ``piece`` of ``curve`` at log10 M* = ``log_m``, from the curve's
    interpolation there: Newton on the Hopf system in Π (flutter), or the divergence
    solved in U* (:func:`fsicas.linear.divergence.divergence_at`); None if that fails.
    ValueError when the piece does not reach log_m."""
    at = scene.replace(mstar=float(10 ** log_m))
    if curve.kind == "divergence":
        guess = [u for u, _, k in curve.crossings(log_m) if k == piece]
        if not guess:
            raise ValueError(f"piece {piece} does not reach log10 M* = {log_m}")
        return divergence_at(at, model, guess[0])
    x, params, omega = curve.guess(log_m, piece)
    vf = flutter_field(model)
    values = dict(zip(vf.par_names, params))
    values[LOG_M] = float(log_m)
    located = C.hopf_point(C.EquilibriumProblem(vf, x, values, PI), x, omega / TIME_SCALE)
    if located.status != "converged" or located.data.get("omega", 0.0) <= 0:
        return None
    return hopf_point_from(model, at, located)


class Envelope:
    """The segments of all traced curves stacked (in curve order), for their crossings
    at one log10 M*; restacked when curves are added."""

    def __init__(self, curves: list):
        self.curves, self._count, self._ends = curves, -1, None

    def _at(self, log_m: float):
        """Indices of the segments that cross log_m, and the interpolation weights."""
        if self._count != len(self.curves):
            parts = [c.segments for c in self.curves]
            self._ends = [np.concatenate([p[k][j] for p in parts]) for k in range(3) for j in (0, 1)]
            self._pieces = np.concatenate([c.pieces for c in self.curves])
            self._count = len(self.curves)
        a, b = self._ends[:2]
        i = np.flatnonzero(((a - log_m) * (b - log_m) <= 0) & (a != b))
        return i, (log_m - a[i]) / (b[i] - a[i])

    def crossings(self, log_m: float) -> tuple[np.ndarray, np.ndarray]:
        """U* and omega of every traced curve at log10 M* = log_m (linear interpolation)."""
        if not self.curves:
            return np.zeros(0), np.zeros(0)
        i, t = self._at(log_m)
        _, _, ua, ub, wa, wb = self._ends
        return ua[i] + t * (ub[i] - ua[i]), wa[i] + t * (wb[i] - wa[i])

    def lowest(self, log_m: float):
        """(U*, omega, piece) of the lowest crossing at log_m (smallest |U*|, the first of
        equal ones), or None."""
        u, w = self.crossings(log_m)
        if not u.size:
            return None
        k = int(np.argmin(np.abs(u)))
        return float(u[k]), float(w[k]), int(self._pieces[self._at(log_m)[0][k]])
