"""CLI commands of the time integration: ``fsicas simulate`` and ``fsicas map``.

Registered by :func:`add_time_commands` from :func:`fsicas.cli.build_parser`; the JSON
contract (keys) is in ``docs/simulate.md``.
"""
from __future__ import annotations

import numpy as np

from ..physical_report import add_physical
from ..plots.timedomain import plot_cycle, plot_map, plot_run
from ..timedomain.breathing import PressureSchedule
from ..timedomain.impact_map import MAP_SCENE, directed, impact_map
from ..timedomain.integrators import Settings
from ..timedomain.run import run_case
from ..scene import MAX_ABS_USTAR, directed_ustar
from ..workers import OVERSUBSCRIBE_HELP, check_workers, dask_executor
from .meta import record
from .progress import reporter
from .ranges import parse_range
from .scene_options import (add_beam_options, add_direction_option, add_scene_options, beam_fields,
                            scene_from_args)

__all__ = ["add_time_commands"]


def add_time_commands(sub) -> None:
    """Add the ``simulate`` and ``map`` subcommands."""
    p = sub.add_parser("simulate", help="nonlinear time integration and outcome classification")
    add_scene_options(p)
    p.add_argument("--t-end", type=float, required=True, help="final time (units of T)")
    p.add_argument("--method", default="idas", choices=["cvodes", "idas", "radau", "bdf"],
                   help="integrator: CasADi IDAS or CVODES, SciPy Radau or BDF")
    p.add_argument("--rtol", type=float, default=1e-8, help="relative tolerance")
    p.add_argument("--atol", type=float, default=1e-10, help="absolute tolerance")
    p.add_argument("--dt-out", type=float, default=1e-3, help="output sampling step")
    p.add_argument("--perturbation", type=float, default=1e-2,
                   help="initial modal displacement, as a fraction of H*/2 (docs/simulate.md)")
    p.add_argument("--schedule", default="constant",
                   choices=["constant", "ramp", "breath", "tidal"],
                   help="inlet flow in time: constant, a ramp from --ustar-start, "
                   "inspirations (breath), or whole breaths through zero flow (tidal: up to "
                   "U*, then down to -(--expiration-peak))")
    p.add_argument("--ustar-start", type=float, default=0.0, help="ramp: initial U*")
    p.add_argument("--ramp-time", type=float, default=1.0, help="ramp: duration")
    p.add_argument("--breath-period", type=float, default=1.0, help="breath, tidal: period")
    p.add_argument("--expiration-peak", type=float, default=None,
                   help="tidal: the expiration's peak speed |U*| >= 0 (default: U*)")
    p.add_argument("--full", action="store_true", help="run to --t-end (no early stop)")
    p.add_argument("--plot", metavar="FILE", help="figure of the run (and FILE_cycle if settled)")
    p.set_defaults(run=_cmd_simulate)
    _add_map_command(sub)


def _add_map_command(sub) -> None:
    p = sub.add_parser("map", help="impact-boundary map in (U*, M*) (paper Fig. 4)")
    p.add_argument("--ustar", default="4:14:11", metavar="LO:HI:COUNT",
                   help="U* grid (linear), all of one sign (negative: reversed flow; with "
                   "--direction, the speeds |U*|)")
    add_direction_option(p, "the --ustar grid")
    p.add_argument("--mstar", default="0.1:10:7", metavar="LO:HI:COUNT", help="M* grid (log)")
    p.add_argument("--modes", type=int, default=10, help="number of beam modes N")
    p.add_argument("--t-end", type=float, default=30.0, help="final time of each run (units of T)")
    p.add_argument("--workers", type=int, default=None, help="local processes (default: the cores)")
    p.add_argument("--oversubscribe", action="store_true", help=OVERSUBSCRIBE_HELP)
    p.add_argument("--dask", metavar="ADDRESS", help="run the points on a Dask scheduler "
                   "(e.g. tcp://host:8786) instead of local processes; needs the parallel extra")
    p.add_argument("--out", default="impact_map.jsonl", help="results file (resumable)")
    p.add_argument("--plot", metavar="FILE", help="write Fig. 4 to FILE")
    add_beam_options(p.add_argument_group("beam theory (docs/beam.md)"))
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(run=_cmd_map)


def _schedule(args, scene):
    if args.expiration_peak is not None and args.schedule != "tidal":
        raise ValueError("--expiration-peak is the peak of a tidal breath: give it with "
                         "--schedule tidal")
    for option, value in (("ramp-time", args.ramp_time), ("breath-period", args.breath_period)):
        if args.schedule in option and not value > 0:
            raise ValueError(f"--{option} must be > 0, got {value}")
    if args.schedule == "ramp":
        if not abs(args.ustar_start) <= MAX_ABS_USTAR:
            raise ValueError(f"--ustar-start must lie in [-{MAX_ABS_USTAR:g}, "
                             f"{MAX_ABS_USTAR:g}] (as --ustar), got {args.ustar_start}")
        return PressureSchedule.ramp(args.ustar_start, scene.ustar, args.ramp_time)
    if args.schedule == "breath":
        return PressureSchedule.breath(scene.ustar, args.breath_period)
    if args.schedule == "tidal":
        if scene.direction == "reverse":
            raise ValueError("--schedule tidal breathes in, then out: give the inspiration's "
                             "peak as U* >= 0 (no --direction reverse) and the expiration's "
                             "as --expiration-peak")
        peak = scene.ustar if args.expiration_peak is None else args.expiration_peak
        return PressureSchedule.tidal(scene.ustar, peak, args.breath_period)
    return None


def _cmd_simulate(args) -> dict:
    if not args.t_end > 0:
        raise ValueError(f"--t-end must be > 0, got {args.t_end}")
    settings = Settings(method=args.method, rtol=args.rtol, atol=args.atol, dt_out=args.dt_out)
    scene = scene_from_args(args, need_flow=True)
    record(args, scene, integrator=settings)
    say = reporter(args)
    say.stage(f"time integration to t = {args.t_end:g} ({settings.method}, N = {scene.modes})")
    run = run_case(scene, args.t_end, settings=settings, schedule=_schedule(args, scene),
                   perturbation=args.perturbation, stop_early=not args.full, progress=say.bars)
    say.stats(f"{run.trajectory.steps} steps, outcome {run.outcome.outcome}, status "
              f"{run.status}, {run.wall_time:.2f} s")
    if args.plot:
        plot_run(run, args.plot)
        if run.outcome.periodic:
            stem, dot, ext = args.plot.rpartition(".")
            plot_cycle(run, f"{stem}_cycle.{ext}" if dot else args.plot + "_cycle")
    return add_physical(run.to_json(), scene, "simulate")


def _cmd_map(args) -> dict:
    check_workers(args.workers, args.oversubscribe)
    ustars = parse_range(args.ustar, "ustar", log=False)
    if args.direction is not None:
        ustars = np.array([directed_ustar(u, args.direction) for u in ustars])
    mstars = parse_range(args.mstar, "mstar", log=True)
    scene = directed(MAP_SCENE, ustars).replace(modes=args.modes, **beam_fields(args))
    record(args, scene, ustar_values=ustars, mstar_values=mstars)
    reporter(args).stage(f"impact map: {ustars.size * mstars.size} points, t_end = "
                         f"{args.t_end:g}, into {args.out}")
    if args.dask:
        with dask_executor(args.dask) as executor:
            result = impact_map(ustars, mstars, args.out, scene=scene, t_end=args.t_end,
                                executor=executor)
    else:
        result = impact_map(ustars, mstars, args.out, scene=scene, t_end=args.t_end,
                            workers=args.workers)
    if args.plot:
        plot_map(result, args.plot)
    return {**result.to_json(), "out": args.out}
