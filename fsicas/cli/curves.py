"""CLI command ``fsicas grazing``: the boundaries of Fig. 4 as curves in (M*, U*): the
flutter (Hopf) boundary, the grazing curve (first wall contact of the cycles) and the
fold-of-cycles curve (hysteresis), docs/cycles.md.

Registered by :func:`add_curve_command` from :func:`fsicas.cli.build_parser`.
"""
from __future__ import annotations

from ..cycles.collocation import CycleSettings
from ..cycles.curves import CurveSettings, curve_seeds, cycle_curves
from ..linear.boundary import stability_boundary
from ..model.assembly import build_model
from ..physical_report import add_physical
from ..plots.cycles import plot_curves
from ..workers import OVERSUBSCRIBE_HELP, check_workers
from .meta import record, write_json
from .progress import reporter
from .ranges import parse_range
from .scene_options import add_scene_options, scene_from_args

__all__ = ["add_curve_command"]


def add_curve_command(sub) -> None:
    """Add the ``grazing`` subcommand."""
    p = sub.add_parser("grazing", help="Fig. 4's boundaries as curves in (M*, U*): flutter "
                       "(Hopf), grazing (first contact of the cycles), fold of cycles")
    add_scene_options(p, mstar=False)
    p.add_argument("--mstar", dest="mstar_values", default="0.05:20:40", metavar="LO:HI:COUNT",
                   help="the M* window and the flutter boundary's points (log-spaced; "
                   "default 0.05:20:40)")
    p.add_argument("--seeds", metavar="LIST", help="M* of the cycle branches the curves start "
                   "from (default: one per piece of the flutter boundary between its mode "
                   "switches)")
    p.add_argument("--ustar-max", type=float, default=20.0, help="cycle branches up to this U*")
    p.add_argument("--ntst", type=int, default=20, help="collocation mesh intervals")
    p.add_argument("--max-points", type=int, default=150,
                   help="points of each curve per direction at most")
    p.add_argument("--workers", type=int, default=1, help="seeds computed in parallel processes")
    p.add_argument("--oversubscribe", action="store_true", help=OVERSUBSCRIBE_HELP)
    p.add_argument("--out", metavar="FILE.json", help="save the curves whole, with their meta")
    p.add_argument("--plot", metavar="FILE", help="the (U*, M*) plane with the three curves")
    p.set_defaults(run=_cmd_grazing)


def _cmd_grazing(args) -> dict:
    scene = scene_from_args(args)
    if scene.contact:
        raise ValueError("the curves are of contact-free cycles: drop --contact")
    check_workers(args.workers, args.oversubscribe)
    if args.ntst < 2:
        raise ValueError(f"--ntst must be >= 2, got {args.ntst}")
    mstars = parse_range(args.mstar_values, "mstar", log=True)
    if mstars.size < 2:
        raise ValueError(f"--mstar must give a window of at least two values, got "
                         f"{args.mstar_values!r}")
    settings = CurveSettings(mstar_min=float(mstars.min()), mstar_max=float(mstars.max()),
                             max_points=args.max_points)
    cycles = CycleSettings(ntst=args.ntst, quadrature_tol=settings.quadrature_tol)
    seeds = None if args.seeds is None else parse_range(args.seeds, "seeds", log=True)
    _check_seeds(seeds, settings)
    record(args, scene, curve_settings=settings, cycle_settings=cycles)
    say = reporter(args)
    model = build_model(scene)
    say.stage(f"flutter boundary at {mstars.size} M* in [{mstars.min():g}, {mstars.max():g}]")
    boundary = stability_boundary(scene, mstars, model)
    seeds = curve_seeds([s.mstar for s in boundary.switches], settings.mstar_min,
                        settings.mstar_max) if seeds is None else list(seeds)
    say.stage(f"grazing and fold curves from {len(seeds)} cycle branches (N = {scene.modes})",
              always=True)
    curves = cycle_curves(scene, seeds, settings=settings, cycles=cycles,
                          ustar_max=args.ustar_max, workers=args.workers,
                          progress=lambda text: say.stage(text, always=True))
    say.stats(f"{len(curves.grazing)} grazing and {len(curves.fold)} fold curves "
              f"in {curves.wall_time:.1f} s")
    out = {**curves.to_json(), "hopf": _hopf_points(boundary),
           "switches": [vars(s) for s in boundary.switches]}
    if args.out:
        write_json(args.out, out, args)
    if args.plot:
        plot_curves(curves, boundary, args.plot)
    out.pop("curves")
    return add_physical(out, scene, "grazing")


def _check_seeds(seeds, settings: CurveSettings) -> None:
    if seeds is not None and any(not settings.mstar_min <= m <= settings.mstar_max
                                 for m in seeds):
        raise ValueError(f"--seeds must lie in the --mstar window [{settings.mstar_min:g}, "
                         f"{settings.mstar_max:g}], got {list(seeds)}")


def _hopf_points(boundary) -> list:
    """The flutter boundary's points as ``{mstar, ustar, omega, l1, criticality}``."""
    keys = ("omega", "l1", "criticality", "branch")
    return [{"mstar": p.mstar, "ustar": p.ustar_crit, **{k: p.to_json().get(k) for k in keys}}
            for p in boundary.points if p.ustar_crit is not None]
