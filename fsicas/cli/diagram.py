"""CLI command ``fsicas diagram``: the bifurcation diagram of a scene over U* (the steady
branch, the branches switched onto from it, recursively), or with ``--mstar LO:HI:COUNT``
the codimension-two points of the onset curves over a window of M* and the curves
switched onto from them (docs/cli.md, docs/continuation.md).

Registered by :func:`add_diagram_command` from :func:`fsicas.cli.build_parser`.
"""
from __future__ import annotations

import continuation as C

from ..cycles.collocation import CycleSettings
from ..cycles.diagram import DiagramSettings, scene_diagram
from ..model.assembly import build_model
from ..plots.diagram import MEASURES, plot_scene_diagram
from .diagram_window import window_command
from .meta import record, write_json
from .progress import reporter
from .ranges import parse_range
from .scene_options import add_scene_options, scene_from_args

__all__ = ["add_diagram_command"]


def add_diagram_command(sub) -> None:
    """Add the ``diagram`` subcommand."""
    p = sub.add_parser("diagram", help="the bifurcation diagram over U*: the steady branch "
                       "and every branch switched onto from it (cycles at Hopf points, deflected "
                       "states at branch points, ...), recursively; with --mstar LO:HI:COUNT the "
                       "codimension-two points of the onset curves in (M*, U*)")
    add_scene_options(p, mstar=False)
    p.add_argument("--mstar", dest="mstar_values", default=None, metavar="M|LO:HI:COUNT",
                   help="the mass ratio (default 1); a window LO:HI:COUNT (log-spaced) gives "
                   "the codimension-two points on the onset curves through its COUNT onsets "
                   "and the curves switched onto from them")
    p.add_argument("--ustar-max", type=float, default=20.0, help="branches up to this U*")
    p.add_argument("--depth", type=int, default=2,
                   help="levels of switching below the steady branch (0..5, default 2)")
    p.add_argument("--ntst", type=int, default=20, help="collocation mesh intervals of cycles")
    p.add_argument("--ncol", type=int, default=4, help="collocation points per interval")
    p.add_argument("--max-points", type=int, default=150, help="points of a cycle branch at most")
    p.add_argument("--measure", choices=sorted(MEASURES), default="tip",
                   help="the figure's vertical axis: tip (deflection of steady states, "
                   "half-amplitude of cycles) or period (cycles)")
    p.add_argument("--out", metavar="FILE.json", help="the whole tree (every branch's points, "
                   "special points, skipped switches) with its meta")
    p.add_argument("--plot", metavar="FILE", help="the diagram: the measure against U*, stable "
                   "solid, unstable dashed, special points labelled")
    p.set_defaults(run=_cmd_diagram)


def _cmd_diagram(args) -> dict:
    mstars = None if args.mstar_values is None else parse_range(args.mstar_values, "mstar",
                                                                log=True)
    if mstars is not None and mstars.size == 1:
        args.mstar, mstars = float(mstars[0]), None
    scene = scene_from_args(args)
    if scene.contact:
        raise ValueError("the diagram is of the contact-free equations: drop --contact")
    settings = _settings(args)
    if mstars is not None:
        return window_command(args, scene, mstars, settings)
    record(args, scene, diagram_settings=settings)
    say = reporter(args)
    say.stage(f"the diagram up to U* = {args.ustar_max:g}, depth {settings.depth} "
              f"(M* = {scene.mstar:g}, N = {scene.modes})", always=True)
    result = scene_diagram(scene, build_model(scene), ustar_max=args.ustar_max,
                           settings=settings)
    say.stats(f"{len(result.branches)} branches, {len(result.skipped)} switches skipped, "
              f"in {result.wall_time:.1f} s")
    if args.out:
        write_json(args.out, result.to_json(points=True), args)
    if args.plot:
        plot_scene_diagram(result, args.plot, args.measure)
    return result.to_json(points=False)


def _settings(args) -> DiagramSettings:
    """The diagram's settings from the options (ValueError naming a bad one)."""
    for name in ("ntst", "ncol", "max_points"):
        if getattr(args, name) < 2:
            raise ValueError(f"--{name.replace('_', '-')} must be >= 2, got {getattr(args, name)}")
    if args.ntst > C.MAX_NTST:
        raise ValueError(f"--ntst must be at most {C.MAX_NTST}, got {args.ntst}")
    if not 0 <= args.depth <= 5:
        raise ValueError(f"--depth must be an integer in 0..5, got {args.depth}")
    cycles = CycleSettings(ntst=args.ntst, ncol=args.ncol, max_points=args.max_points,
                           quadrature_tol=None)        # the scene's nodes throughout
    return DiagramSettings(depth=args.depth, cycles=cycles)
