"""The modal truncation error of an onset: the same onset with more modes.

An onset found with N modes (a Hopf point or a divergence) is located again with
``N' = finer_modes(N)`` modes (twice as many, at most :data:`MAX_MODES`), started from the
N-mode point with the added modes at rest: Newton on the Hopf system in Π, or the
divergence solved in U*. Its estimate is ``|U*_c(N) - U*_c(N')| / U*_c(N')``; above
:data:`TRUNCATION_RTOL` the onset says so in its ``warnings``. A spurious branch of a
short truncation (M* = 30, N = 10: the onset 6 % low) moves by that much; a converged one
by less than the tolerance.
"""
from __future__ import annotations

import math
import warnings

import numpy as np

import continuation as C

from ..model.assembly import Model, build_model, per_model
from ..scene import Scene
from .adapter import LOG_M, PI, PI_SCALE, TIME_SCALE, flutter_field
from .divergence import divergence_at

__all__ = ["TRUNCATION_RTOL", "MAX_MODES", "finer_modes", "finer_model", "truncation_error",
           "truncation_warning", "AUTO_START", "with_enough_modes"]

#: Relative change of U*_c with twice the modes above which an onset is flagged.
TRUNCATION_RTOL = 1e-2
#: The most modes a finer model gets (the Scene's limit).
MAX_MODES = 200


def finer_modes(modes: int) -> int:
    """The modes of the finer model: 2N, at most :data:`MAX_MODES`."""
    return min(2 * modes, MAX_MODES)


@per_model
def finer_model(model: Model) -> Model:
    """The model of the same structure with :func:`finer_modes` modes, built once per model."""
    scene = model.scene
    return build_model(scene.replace(modes=finer_modes(scene.modes), quad_nodes=None))


def truncation_error(scene: Scene, model: Model, onset) -> float:
    """``|U*_c(N) - U*_c(N')| / U*_c(N')`` of ``onset`` (found on ``model``, N modes),
    relocated with N' modes (module docstring); NaN where the relocation fails (then
    no estimate: the onset's branch is not resolved by N modes either), 0 when N is
    already the most."""
    if finer_modes(scene.modes) == scene.modes:
        return 0.0
    fine = finer_model(model)
    at = scene.replace(modes=fine.scene.modes, quad_nodes=None)
    ustar = _relocated(at, fine, onset, scene.modes)
    return abs(onset.ustar - ustar) / abs(ustar) if ustar else math.nan


def _relocated(scene: Scene, fine: Model, onset, modes: int) -> float | None:
    """U* of ``onset`` located on the finer model, or None."""
    if onset.kind == "divergence":
        point = divergence_at(scene, fine, onset.ustar)
        return None if point is None else point.ustar
    x = _padded(onset.x, modes, fine.n_modes)
    vf = flutter_field(fine)
    values = dict(zip(fine.parameter_names, fine.parameters(scene,
                                                            pressure_drop=onset.pressure_drop)))
    params = {PI: onset.pressure_drop / (scene.mstar * PI_SCALE), LOG_M: math.log10(scene.mstar)}
    params.update({k: values[k] for k in vf.par_names[2:]})
    problem = C.EquilibriumProblem(vf, x, params, PI)
    point = C.hopf_point(problem, x, onset.omega / TIME_SCALE)
    if point.status != "converged" or point.data.get("omega", 0.0) <= 0:
        return None
    return float(np.asarray(point.x)[-2:].sum() / scene.hstar)


def _padded(x, modes: int, fine_modes: int) -> np.ndarray:
    """The state ``(r, q, Q)`` of ``modes`` modes with the added modes at rest."""
    x = np.asarray(x, dtype=float)
    extra = np.zeros(fine_modes - modes)
    r, q, Q = x[:modes], x[modes:2 * modes], x[2 * modes:]
    return np.concatenate([r, extra, q, extra, Q])


def truncation_warning(scene: Scene, onset, error: float) -> str | None:
    """The warning of an onset whose truncation error exceeds :data:`TRUNCATION_RTOL`
    (or could not be estimated), else None."""
    n, fine = scene.modes, finer_modes(scene.modes)
    if math.isnan(error):
        return (f"the {onset.kind} onset U*_c = {onset.ustar:.6g} at M* = {scene.mstar:g} "
                f"with N = {n} modes is not found again with N = {fine}: not resolved by "
                "the truncation; raise modes (--modes auto)")
    if error > TRUNCATION_RTOL:
        return (f"the {onset.kind} onset U*_c = {onset.ustar:.6g} at M* = {scene.mstar:g} "
                f"moves by {error:.2g} (relative) from N = {n} to N = {fine} modes, above "
                f"the tolerance {TRUNCATION_RTOL:g}: raise modes (--modes auto)")
    return None


#: The first N of ``--modes auto``.
AUTO_START = 10


def with_enough_modes(scene: Scene, analyse, start: int = AUTO_START):
    """``(scene, result)`` of ``analyse(scene)`` (returning ``(result, worst truncation
    error)``) with N = start, 2 start, ... modes, the first N whose error is at most
    :data:`TRUNCATION_RTOL` (NaN: not estimated, goes on), or the last below
    :data:`MAX_MODES`. Only the warnings of the N returned are issued."""
    modes = start
    while True:
        at = scene.replace(modes=modes, quad_nodes=None)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result, error = analyse(at)
        if error <= TRUNCATION_RTOL or finer_modes(modes) == modes:
            for w in caught:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
            return at, result
        modes = finer_modes(modes)
