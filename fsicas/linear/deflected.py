"""The deflected steady states born at a symmetric channel's pitchfork.

Past a symmetry-breaking divergence (:class:`fsicas.linear.divergence.DivergencePoint`)
the straight state is unstable, and two deflected steady states branch off, mirror images
of each other (``R x``). One of them is continued in Π from the branch point
(:func:`continuation.equilibrium_from_bp`), with its stability at every point (the
eigenvalues of ``F_x v = λ M v``); the other is its mirror, with the same U*, stability
and the opposite deflection. The continuation ends where the deflection changes sign (an
event: the branch has come back to the straight state, at the other end of a window of
divergence, and would go on along its mirror), where the beam reaches the wall's contact
layer at its reference point (the cantilever's tip; status "wall": the gap there is eps,
beyond which the flow model closes the channel; the reversed cantilever's deflected states
run there) or at the U* bound.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

import continuation as C

from ..model.assembly import Model
from ..scene import Scene
from .adapter import PI, PI_SCALE, pi_interval
from .divergence import DivergencePoint
from .hopf import PI_MARGIN, flutter_problem

__all__ = ["DeflectedBranch", "deflected_branch"]


@dataclass(frozen=True)
class DeflectedBranch:
    """One deflected branch: ``ustar``, ``tip_deflection`` (y(x_ref) in units of L at the
    reference point ``x_ref``, :func:`fsicas.model.assembly.reference_point`; the sign
    of one side; the mirror branch has the opposite), ``stable``, ``pressure_drop`` and
    the ``states`` along it, in the order continued from the branch point;
    ``status``/``message`` of the continuation ("wall": ended where the tip reaches the
    wall's contact layer)."""

    ustar: np.ndarray
    tip_deflection: np.ndarray
    stable: np.ndarray
    status: str
    message: str = ""
    pressure_drop: np.ndarray = field(default=None, repr=False)
    states: np.ndarray = field(default=None, repr=False)
    x_ref: float = 1.0

    def to_json(self) -> dict:
        return {"ustar": self.ustar.tolist(), "tip_deflection": self.tip_deflection.tolist(),
                "x_ref": self.x_ref,
                "stable": self.stable.tolist(), "status": self.status, "message": self.message}


def deflected_branch(scene: Scene, model: Model, onset: DivergencePoint, ustar_max: float,
                     amplitude: float = 1e-3) -> DeflectedBranch:
    """The deflected branch born at ``onset`` (a symmetry-breaking divergence located on
    the steady branch, as :func:`fsicas.linear.hopf.critical_velocity` returns it),
    continued in Π up to about the speed |U*| = ``ustar_max`` (Π ∝ U*|U*| with a margin;
    points above are dropped; Π < 0 for reversed flow)."""
    if onset.kind != "divergence" or not onset.symmetry_breaking or onset.point is None:
        raise ValueError("deflected_branch needs a symmetry-breaking divergence located on "
                         "the steady branch (critical_velocity's onset of kind 'divergence')")
    problem = flutter_problem(scene, model, min(0.2, abs(onset.ustar) / 2))
    start = C.equilibrium_from_bp(problem, onset.point, amplitude=amplitude)
    pi_bp = onset.pressure_drop / (onset.mstar * PI_SCALE)
    pi_max = PI_MARGIN * pi_bp * (ustar_max / onset.ustar) ** 2
    size = abs(pi_max)
    settings = C.ContinuationSettings(ds=size / 600, ds_max=size / 150, ds_min=1e-10 * size,
                                      max_steps=600, bounds={PI: pi_interval(0.0, pi_max)})
    n = model.n_modes
    side = np.asarray(start.X0[n:2 * n]) - np.asarray(onset.x[n:2 * n])     # the q it leaves along
    mirror = C.Event("mirror", lambda problem, X: float(side @ X[n:2 * n]), terminal=True)
    branch = C.continuation(start, settings=settings, events=(mirror, _wall(scene, model)))
    ustar = branch.x[:, -2:].sum(axis=1) / scene.hstar
    keep = np.abs(ustar) <= ustar_max
    status = branch.status
    if status == "event" and branch.special_points[-1].kind == "wall":
        status = "wall"
    elif status == "event":      # its end is the straight state at the other branch point
        keep[-1] = False
    tip = np.array([float(model.deflection(x, [model.x_ref])[0]) for x in branch.x[keep]])
    dp = branch.par(PI)[keep] * PI_SCALE * scene.mstar
    return DeflectedBranch(ustar[keep], tip, branch.n_unstable[keep] == 0, status,
                           branch.message, dp, branch.x[keep], model.x_ref)


def _wall(scene: Scene, model: Model) -> C.Event:
    """The terminal event where the narrower gap at the reference point, ``min_c
    (H_c(x_ref) + s_c y(x_ref))``, reaches the contact layer eps (the tip of a
    cantilever)."""
    n, phi = model.n_modes, model.probe.phi[:, 1]
    heights = [float(w(model.x_ref)) for w in scene.walls]
    gap = lambda y: min(heights[0] - y, heights[1] + y) - scene.contact_gap
    return C.Event("wall", lambda problem, X: float(gap(phi @ X[n:2 * n])), terminal=True)
