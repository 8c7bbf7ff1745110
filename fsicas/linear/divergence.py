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

from ..model.assembly import Model
from ..scene import Scene
from .adapter import LOG_M, PI, PI_SCALE
from .stability import generalized_eigen

__all__ = ["DivergencePoint", "divergence_point_from", "DIVERGENCE_KINDS"]

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

    kind: ClassVar[str] = "divergence"
    #: a static loss of stability: no frequency (kept for code written for both kinds)
    omega: ClassVar[float] = 0.0
    freq_ratio: ClassVar[float] = 0.0

    def to_json(self) -> dict:
        return {"kind": self.kind, "mstar": self.mstar, "ustar_crit": self.ustar,
                "pressure_drop": self.pressure_drop, "omega": 0.0, "freq_ratio": 0.0,
                "bifurcation": self.bifurcation, "symmetry_breaking": self.symmetry_breaking,
                "dominant_mode": self.dominant_mode}


def null_vector(model: Model, x, p) -> np.ndarray:
    """The real eigenvector of ``F_x v = λ M v`` whose eigenvalue is nearest 0."""
    lam, vec = generalized_eigen(model.jac_rhs(x, p), model.mass(x, p))
    k = int(np.argmin(np.abs(lam)))
    v = vec[:, k]
    v = (v * np.exp(-1j * np.angle(v[np.argmax(np.abs(v))]))).real
    return v / np.linalg.norm(v)


def divergence_point_from(model: Model, scene: Scene, point) -> DivergencePoint:
    """The :class:`DivergencePoint` of a located "bp" or "fold" special point of the
    steady branch in the adapter's parameters (:mod:`fsicas.linear.adapter`)."""
    x = np.asarray(point.x, dtype=float)
    mstar = 10 ** point.params[LOG_M]
    dp = float(point.params[PI] * PI_SCALE * mstar)
    v = null_vector(model, x, model.parameters(scene.replace(mstar=mstar), pressure_drop=dp))
    n = model.n_modes
    R = model.mirror
    antisymmetric = np.linalg.norm(R @ v + v) < np.linalg.norm(R @ v - v)
    return DivergencePoint(mstar=mstar, ustar=float(x[-2:].sum() / scene.hstar),
                           pressure_drop=dp, bifurcation=DIVERGENCE_KINDS[point.kind],
                           symmetry_breaking=bool(scene.symmetric and antisymmetric),
                           dominant_mode=int(np.argmax(v[n:2 * n] ** 2)) + 1,
                           precision=float(point.precision), x=x, point=point)
