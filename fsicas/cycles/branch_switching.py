"""Branch switching at the special cycles of an impacting collocation branch: at a period
doubling onto the cycles of twice the period, at a branch point (the symmetric channel's
symmetric cycle giving way) onto the pair of asymmetric cycles."""
from __future__ import annotations

import time

import numpy as np

import continuation as C

from ..checks import require_forward
from ..model.assembly import Model, build_model
from ..scene import Scene
from .impacting_collocation import (CollocatedImpactBranch, CollocatedImpactPoint,
                                    CollocationImpactSettings, check_smooth,
                                    continued_branch, failed_branch,
                                    impacting_collocation_problem)

__all__ = ["period_doubled_branch", "symmetry_broken_branch"]


def period_doubled_branch(scene: Scene, point: "CollocatedImpactPoint", *,
                          model: Model | None = None, amplitude: float = 1e-2,
                          ustar_min: float = 0.0, ustar_max: float = 12.0,
                          settings: CollocationImpactSettings = CollocationImpactSettings()
                          ) -> CollocatedImpactBranch:
    """The branch of cycles of twice the period born at the period doubling ``point`` (a
    special point of kind "pd" of :func:`fsicas.cycles.impacting_cycles` (collocation) on ``scene``).

    The PD cycle is rebuilt from the point's state (one integrated period, the start mesh
    equidistributed on it) and refined by Newton on its minimally extended system; the
    doubled cycle starts from it plus ``amplitude`` times its Floquet solution of
    multiplier -1 (``continuation.cycle_from_pd``: 2 NTST intervals, the PD cycle's mesh
    run through twice) and is continued towards larger amplitude, in either direction
    of U* as the branch bends (the PD is super- or subcritical)."""
    require_forward(scene, "the period-doubled branch")
    return _switched(scene, point, "pd", model, amplitude, (ustar_min, ustar_max), settings)


def symmetry_broken_branch(scene: Scene, point: "CollocatedImpactPoint", *,
                           model: Model | None = None, amplitude: float = 1e-3,
                           ustar_min: float = 0.0, ustar_max: float = 12.0,
                           settings: CollocationImpactSettings = CollocationImpactSettings()
                           ) -> CollocatedImpactBranch:
    """The branch of cycles that break the channel's symmetry, born at the branch point
    ``point`` (kind "bp" of :func:`fsicas.cycles.impacting_cycles` (collocation) on ``scene``).

    The cycle is rebuilt from the point's state (as for :func:`period_doubled_branch`)
    and kept as the guess (Newton at fixed U* is singular at a branch point: two null
    vectors); the new branch starts from it plus ``amplitude``
    times the null direction of its Jacobian that keeps U* (``continuation.cycle_from_bp``,
    scaled to a largest nodal change of ``amplitude``; at 1e-2 the stiff contact law
    already throws the guess out of Newton's reach) and is continued towards larger
    amplitude."""
    require_forward(scene, "the symmetry-broken branch")
    return _switched(scene, point, "bp", model, amplitude, (ustar_min, ustar_max), settings)


def _switched(scene, point, kind, model, amplitude, ustar_range, settings
              ) -> CollocatedImpactBranch:
    """The branch born at the special cycle ``point`` of ``kind`` ("pd", "bp"), on
    ``model`` or else on the quadrature nodes the point was computed on."""
    start = time.perf_counter()
    check_smooth(scene)
    if getattr(point, "kind", None) != kind:
        raise ValueError(f"point must be a special point of kind {kind!r} of an impacting "
                         f"collocation branch, got kind {getattr(point, 'kind', None)!r}")
    if not (np.isfinite(amplitude) and amplitude > 0):
        raise ValueError(f"amplitude must be a positive finite number, got {amplitude!r}")
    scene = scene.replace(quad_nodes=model.scene.n_quad if model else
                          point.quadrature_nodes or scene.quad_nodes)
    model = model or build_model(scene)     # the nodes the point was computed on
    try:
        problem = impacting_collocation_problem(scene, point.state, point.period,
                                                point.pressure_drop, model=model,
                                                settings=settings)
        square, X, residual = _rebuilt_special(problem, kind, settings)
    except (RuntimeError, ValueError, np.linalg.LinAlgError) as err:
        return failed_branch(scene, model, f"the special cycle could not be rebuilt: {err}",
                             start)
    special = C.SpecialPoint(kind, 0, square.state(X), square.par_dict(X), "converged",
                             residual, {"X": list(X), "mesh": list(square.mesh)})
    switch = C.cycle_from_pd if kind == "pd" else C.cycle_from_bp
    return continued_branch(scene, model, switch(problem, special, amplitude=amplitude),
                            ustar_range, 1, settings, start)


def _rebuilt_special(problem, kind, settings) -> tuple:
    """``(problem, X, residual)``: a period doubling by Newton on its minimally extended
    system (RuntimeError if that fails). A branch point is not located again here (the
    point was, on the symmetric cycles): the rebuilt cycle stays the guess, and the new
    branch's start corrector, off the branch point by the switch's amplitude, corrects
    it."""
    if kind == "bp":
        return problem, problem.X0, float("nan")
    square, result = C.locate_cycle(problem, problem.X0, C.PeriodDoubling(),
                                    C.NewtonSettings(tol=settings.tol))
    if not result.converged:
        raise RuntimeError(f"Newton on its extended system failed: {result.message}")
    return square, result.X, result.residual
