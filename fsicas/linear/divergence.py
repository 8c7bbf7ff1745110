"""Static divergence: a real eigenvalue of the steady branch crosses zero.

Along the steady branch continued in Π, ``det F_x`` changes sign where a real eigenvalue
of ``F_x v = λ M v`` crosses zero: at a fold of the branch (``dΠ/ds`` changes sign) or at
a branch point (``det [G_X; τ^T] = det F_x / τ_Π`` changes sign). The library locates
both (its "fold" and "bp" special points). A symmetric channel's straight state loses
stability this way at a pitchfork: the null vector is antisymmetric (``R v = -v``, the
channel's mirror ``R``), the beam is pushed towards one wall and two deflected steady
states branch off.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Literal

import numpy as np
from scipy.optimize import brentq

from ..model.assembly import Model
from ..scene import Scene
from .adapter import LOG_M, PI, PI_SCALE
from .stability import generalized_eigen
from .steady import SteadyStateError, steady_state

__all__ = ["DivergencePoint", "divergence_point_from", "divergence_at", "divergence_between",
           "DIVERGENCE_KINDS", "BRACKETS"]

#: The library's special points where a real eigenvalue crosses zero, and their names.
DIVERGENCE_KINDS = {"bp": "branch point", "fold": "fold"}


@dataclass(frozen=True)
class DivergencePoint:
    """A located static divergence of the steady branch (a real eigenvalue crosses 0).

    ``bifurcation``: "branch point" or "fold" of the steady branch; ``symmetry_breaking``:
    the channel is symmetric and the null vector antisymmetric (a pitchfork);
    ``dominant_mode``: the in-vacuo mode with the largest share of the null vector's q."""

    mstar: float
    ustar: float
    pressure_drop: float
    bifurcation: Literal["branch point", "fold"]
    symmetry_breaking: bool
    dominant_mode: int
    precision: float
    x: np.ndarray = field(repr=False)
    point: object = field(repr=False, default=None)
    #: relative change of U* with twice the modes (:mod:`fsicas.linear.truncation`)
    truncation: float = float("nan")

    kind: ClassVar[str] = "divergence"
    #: a static loss of stability: no frequency (kept for code written for both kinds)
    omega: ClassVar[float] = 0.0
    freq_ratio: ClassVar[float] = 0.0

    def to_json(self) -> dict:
        return {"kind": self.kind, "mstar": self.mstar, "ustar_crit": self.ustar,
                "pressure_drop": self.pressure_drop, "omega": 0.0, "freq_ratio": 0.0,
                "bifurcation": self.bifurcation, "symmetry_breaking": self.symmetry_breaking,
                "dominant_mode": self.dominant_mode,
                "truncation": None if np.isnan(self.truncation) else self.truncation}


def null_vector(model: Model, x, p) -> np.ndarray:
    """The real eigenvector of ``F_x v = λ M v`` whose eigenvalue is nearest 0."""
    lam, vec = generalized_eigen(model.jac_rhs(x, p), model.mass(x, p))
    k = int(np.argmin(np.abs(lam)))
    v = vec[:, k]
    v = (v * np.exp(-1j * np.angle(v[np.argmax(np.abs(v))]))).real
    return v / np.linalg.norm(v)


def _point(model: Model, scene: Scene, x, p, dp: float, bifurcation, precision: float,
           point=None) -> DivergencePoint:
    """The DivergencePoint at state ``x``, model parameters ``p``, of ``scene``'s M*."""
    v = null_vector(model, x, p)
    n = model.n_modes
    R = model.mirror
    antisymmetric = np.linalg.norm(R @ v + v) < np.linalg.norm(R @ v - v)
    breaking = bool(scene.symmetric and antisymmetric)
    return DivergencePoint(mstar=scene.mstar, ustar=float(x[-2:].sum() / scene.hstar),
                           pressure_drop=float(dp),
                           bifurcation=bifurcation or ("branch point" if breaking else "fold"),
                           symmetry_breaking=breaking,
                           dominant_mode=int(np.argmax(v[n:2 * n] ** 2)) + 1,
                           precision=float(precision), x=np.asarray(x, float), point=point)


def divergence_point_from(model: Model, scene: Scene, point) -> DivergencePoint:
    """The :class:`DivergencePoint` of a located "bp" or "fold" special point of the
    steady branch in the adapter's parameters (:mod:`fsicas.linear.adapter`)."""
    x = np.asarray(point.x, dtype=float)
    scene = scene.replace(mstar=10 ** point.params[LOG_M])
    dp = float(point.params[PI] * PI_SCALE * scene.mstar)
    return _point(model, scene, x, model.parameters(scene, pressure_drop=dp), dp,
                  DIVERGENCE_KINDS[point.kind], point.precision, point)


#: Relative tolerance of the divergence in U* (Brent's ``xtol`` and ``rtol``).
XTOL = 1e-13
#: Relative half-widths in U* tried, in turn, to bracket a divergence near a guess.
BRACKETS = (0.01, 0.03, 0.1)


def real_rate(scene: Scene, model: Model, ustar: float) -> tuple[float, object]:
    """The real eigenvalue nearest 0 at the steady state of ``scene`` at ``ustar`` (it
    changes sign at a divergence), and that steady state."""
    st = steady_state(scene.replace(ustar=ustar), model)
    lam, _ = generalized_eigen(model.jac_rhs(st.x, st.p), model.mass(st.x, st.p))
    real = lam[np.abs(lam.imag) <= 1e-12 * (1.0 + np.abs(lam))].real
    return (float(real[np.argmin(np.abs(real))]) if real.size else np.inf), st


def divergence_at(scene: Scene, model: Model, ustar_guess: float) -> DivergencePoint | None:
    """The divergence of ``scene`` (at its M*) near ``ustar_guess`` (signed: < 0 for
    reversed flow): the sign change of the real eigenvalue nearest 0 along the steady
    states in U*, bracketed within :data:`BRACKETS` of the guess and solved by Brent's
    method to round-off; None when no sign change is bracketed (or no steady state is
    found there)."""
    for half in BRACKETS:
        point = divergence_between(scene, model, ustar_guess * (1 - half),
                                   ustar_guess * (1 + half), scale=abs(ustar_guess))
        if point is not None:
            return point
    return None


def divergence_between(scene: Scene, model: Model, lo: float, hi: float,
                       scale: float | None = None) -> DivergencePoint | None:
    """The divergence of ``scene`` with U* between ``lo`` and ``hi`` (either order, either
    sign): the sign change there of the real eigenvalue nearest 0 along the steady states,
    solved by Brent's method to :data:`XTOL` relative to ``scale`` (default the larger
    speed); None when its signs at the two ends agree (or a steady state is not found)."""
    lo, hi = sorted((lo, hi))
    scale = max(abs(lo), abs(hi)) if scale is None else scale
    rate = lambda u: real_rate(scene, model, u)[0]
    try:
        if np.sign(rate(lo)) == np.sign(rate(hi)):
            return None
        u = brentq(rate, lo, hi, xtol=XTOL * scale, rtol=XTOL)
        st = real_rate(scene, model, u)[1]
    except SteadyStateError:
        return None
    return _point(model, scene, st.x, st.p, st.pressure_drop, None, XTOL * (scale + abs(u)))
