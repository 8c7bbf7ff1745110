"""CLI commands of the linear analysis: ``fsicas modes``, ``steady``, ``eig`` and
``boundary`` (docs/stability.md)."""
from __future__ import annotations

import numpy as np

from ..linear.boundary import stability_boundary
from ..linear.truncation import with_enough_modes
from ..linear.stability import linear_stability
from ..linear.steady import steady_state
from ..model.assembly import build_model, modal_basis
from ..model.beam import uniform_betas
from ..model.beam_timoshenko import TimoshenkoBeam, timoshenko_frequencies
from ..physical_report import add_physical
from ..scene import MAX_MODES, Scene
from ..plots.linear import plot_boundary, plot_eigenvalues, plot_mode_shapes
from .meta import record
from .progress import reporter
from .ranges import parse_range
from .scene_options import add_beam_options, add_scene_options, beam_fields, scene_from_args

__all__ = ["add_linear_commands"]


def add_linear_commands(sub) -> None:
    """Add the ``modes``, ``steady``, ``eig`` and ``boundary`` subcommands."""
    p = sub.add_parser("modes", help="in-vacuo clamped-free beam modes")
    p.add_argument("--modes", type=int, default=10, help="number of modes N, in [1, 200]")
    add_beam_options(p.add_argument_group("beam theory (docs/beam.md)"))
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(run=_cmd_modes)
    p = sub.add_parser("steady", help="steady state: pressure drop, flow split, static deflection")
    add_scene_options(p)
    p.set_defaults(run=_cmd_steady)
    p = sub.add_parser("eig", help="eigenvalues of the linearization at the steady state")
    add_scene_options(p)
    p.add_argument("--plot", metavar="FILE", help="write the eigenvalue map to FILE")
    p.set_defaults(run=_cmd_eig)
    _add_boundary_command(sub)


def _add_boundary_command(sub) -> None:
    p = sub.add_parser("boundary", help="stability boundary U*_c(M*) (flutter and divergence) from curve continuation")
    add_scene_options(p, mstar=False)
    p.add_argument("--mstar", dest="mstar_values", metavar="LIST_OR_RANGE",
                   help="0.1,1,10 or lo:hi:count (log-spaced); required unless --physical "
                   "(default there: the M* of the physical input)")
    p.add_argument("--ustar-max", type=float, default=40.0, help="search Hopf points below this U*")
    p.add_argument("--no-refine", action="store_true",
                   help="interpolate along the Hopf curves instead of locating each point")
    p.add_argument("--plot", metavar="FILE", help="write Fig. 2 to FILE and Fig. 3 to FILE_modes")
    p.set_defaults(run=_cmd_boundary)


def _cmd_modes(args) -> dict:
    if args.modes is None or not 1 <= args.modes <= MAX_MODES:
        raise ValueError(f"--modes must be an integer in [1, {MAX_MODES}], got {args.modes}")
    scene = Scene(modes=args.modes, **beam_fields(args))   # checks the beam options, naming them
    if scene.beam == "timoshenko":   # beta = sqrt(omega), the thin beam's beta_n (docs/beam.md)
        omega = timoshenko_frequencies(args.modes, TimoshenkoBeam(
            scene.slenderness, scene.poisson, scene.shear_coefficient)) \
            if scene.ends == "clamped-free" else modal_basis(scene, np.zeros(1)).omega
        return {"beta": np.sqrt(omega).tolist(), "omega": omega.tolist()}
    beta = uniform_betas(args.modes, scene.ends)
    return {"beta": beta.tolist(), "omega": (beta**2).tolist()}


def _cmd_steady(args) -> dict:
    scene = scene_from_args(args, need_flow=True)
    model = build_model(scene)
    return add_physical(steady_state(scene, model).to_json(model), scene, "steady")


def _cmd_eig(args) -> dict:
    scene = scene_from_args(args, need_flow=True)
    result = linear_stability(scene, build_model(scene))
    if args.plot:
        plot_eigenvalues(result, scene, args.plot)
    return add_physical(result.to_json(), scene, "eig")


def _cmd_boundary(args) -> dict:
    if args.mstar_values is None and args.physical is None:
        raise ValueError("--mstar is required (a list or lo:hi:count), unless --physical")
    auto = args.modes == "auto"
    args.modes = None if auto else args.modes
    scene = scene_from_args(args)
    mstars = ([scene.mstar] if args.mstar_values is None
              else parse_range(args.mstar_values, "mstar", log=True))
    record(args, scene, mstar_values=mstars)
    say = reporter(args)
    say.stage(f"stability boundary at {len(mstars)} M* in [{min(mstars):g}, {max(mstars):g}], "
              f"U* < {args.ustar_max:g}, N = {scene.modes}")
    trace = lambda sc: stability_boundary(sc, mstars, build_model(sc), ustar_max=args.ustar_max,
                                          refine=not args.no_refine)
    if auto:
        scene, boundary = with_enough_modes(scene, lambda sc: ((b := trace(sc)), b.truncation))
    else:
        boundary = trace(scene)
    model = build_model(scene)
    kinds = [c.kind for c in boundary.curves]
    say.stats(f"{len(boundary.points)} points, {len(boundary.switches)} mode switches, "
              f"{kinds.count('flutter')} Hopf and {kinds.count('divergence')} divergence "
              "curves traced")
    if args.plot:
        plot_boundary(boundary, args.plot)
        stem = args.plot.rsplit(".", 1)
        plot_mode_shapes(boundary, model, f"{stem[0]}_modes.{stem[1] if len(stem) > 1 else 'png'}")
    out = boundary.to_json()
    out.pop("curves")
    return add_physical(out, scene, "boundary")
