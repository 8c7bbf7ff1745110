"""CLI command ``fsicas lco`` (alias ``cycles``): the flutter limit-cycle branch versus U*
(docs/cycles.md), with ``--through-contact`` on past the first contact into the impacting
regime; ``lco`` is the name the command-line contract fixes.

Registered by :func:`add_cycle_commands` from :func:`fsicas.cli.build_parser`, like the
time integration commands of :mod:`fsicas.cli.timedomain`.
"""
from __future__ import annotations

import math

import continuation as C

from ..cycles.collocation import CycleSettings, cycle_branch
from ..cycles.impacting import ImpactSettings
from ..cycles.impacting_collocation import CollocationImpactSettings
from ..cycles.impacting_routes import (THROUGH_EPS, THROUGH_STIFFNESS, impacting_cycles,
                                       impacting_start, through_contact_law)
from ..model import build_model
from ..model.accuracy import QUADRATURE_TOL
from ..model.contact import reference_force
from ..physical_report import add_physical
from ..plots.cycles import plot_branch
from .meta import record, write_json
from .progress import reporter
from .scene_options import add_scene_options, scene_from_args

__all__ = ["add_cycle_commands"]

_POINT_KEYS = ("kind", "ustar", "period", "omega", "tip_amplitude", "gap_ratio", "stable",
               "quadrature_error", "quadrature_nodes")
_IMPACT_KEYS = ("ustar", "period", "tip_amplitude", "min_gap", "gap_ratio", "impacts",
                "peak_force", "flow_reduction", "stable", "quadrature_error", "quadrature_nodes")
#: the collocation error indicator above which the impacting mesh is reported too coarse
#: (at N = 20 NTST = 200 reached 1-2 and its branch was not trusted; NTST = 400 kept
#: 1e-2-4e-2 and agreed with time integration to 1e-7, docs/cycles.md)
COARSE_MESH = 0.1

#: The impacting branch's points without ``--impact-points``: no limit that a branch
#: bounded by ``--ustar-max`` reaches.
UNLIMITED_POINTS = 10 ** 6


def add_cycle_commands(sub) -> None:
    """Add the ``lco`` subcommand (alias ``cycles``)."""
    p = sub.add_parser("lco", aliases=["cycles"],
                       help="limit cycles vs U* by collocation continuation from the first Hopf "
                            "point, up to the first contact")
    add_scene_options(p)
    p.add_argument("--ustar-max", type=float, default=20.0, help="stop beyond this U*")
    p.add_argument("--ntst", type=int, default=20, help="collocation mesh intervals")
    p.add_argument("--ncol", type=int, default=4, help="collocation points per interval")
    p.add_argument("--max-points", type=int, default=300, help="branch points at most")
    p.add_argument("--quadrature-tol", type=_tolerance, default=QUADRATURE_TOL, metavar="TOL",
                   help="from a point whose quadrature error exceeds TOL, go on with the nodes "
                        "doubled as often as needed; 'none': the scene's nodes throughout")
    p.add_argument("--out", metavar="FILE.json", help="save the full branch (multipliers, "
                   "states) with its meta")
    p.add_argument("--plot", metavar="FILE", help="tip amplitude and period against U*")
    p.add_argument("--through-contact", action="store_true",
                   help="go on past the first contact on the model with the wall-contact law "
                   f"(k* = --contact-stiffness, default {THROUGH_STIFFNESS:g}; eps/H = "
                   f"--contact-eps, default {THROUGH_EPS:g}; smoothed): per point impacts, "
                   "peak force, flow reduction, Floquet stability; with the collocation "
                   "route also its folds, period doublings and Neimark-Sacker points")
    p.add_argument("--impact-points", type=int, default=None,
                   help="stop the impacting branch after this many points (with "
                        "--through-contact; default: no limit, on to --ustar-max)")
    p.add_argument("--impact-route", choices=("collocation", "shooting"), default="collocation",
                   help="the impacting branch by adaptive collocation (NTST = --impact-ntst; "
                        "special cycles located) or by multiple shooting (12 segments)")
    p.add_argument("--impact-ntst", type=int, default=200,
                   help="collocation intervals of the impacting branch (adapted to the impacts)")
    p.add_argument("--special-ntst", type=int, default=0,
                   help="locate each special cycle once more on this many intervals of 6 "
                        "points, re-meshed three times on its own error (its critical "
                        "multiplier nearer the unit circle; 0: on the branch's mesh)")
    p.set_defaults(run=_cmd_cycles)


def _cmd_cycles(args) -> dict:
    scene = scene_from_args(args)
    if scene.contact:
        raise ValueError("cycles are continued on the contact-free model: drop --contact "
                         "(--through-contact turns the contact law on past the first contact)")
    for name in ("impact_points", "impact_ntst"):
        if getattr(args, name) is not None and getattr(args, name) < 1:
            raise ValueError(f"--{name.replace('_', '-')} must be >= 1, got {getattr(args, name)}")
    if args.special_ntst < 0:
        raise ValueError(f"--special-ntst must be >= 0 (0: off), got {args.special_ntst}")
    for name in ("ntst", "impact_ntst", "special_ntst"):
        if getattr(args, name) > C.MAX_NTST:
            raise ValueError(f"--{name.replace('_', '-')} must be at most {C.MAX_NTST}, got "
                             f"{getattr(args, name)}")
    if args.through_contact:
        scene = through_contact_law(scene, args.contact_stiffness, args.contact_eps)
    settings = CycleSettings(ntst=args.ntst, ncol=args.ncol, max_points=args.max_points,
                             quadrature_tol=args.quadrature_tol)
    record(args, scene, cycle_settings=settings)
    say = reporter(args)
    say.stage(f"limit cycles from the first Hopf point up to U* = {args.ustar_max:g} "
              f"(N = {scene.modes}, NTST = {settings.ntst}, NCOL = {settings.ncol})")
    branch = cycle_branch(scene, ustar_max=args.ustar_max, settings=settings)
    say.stats(f"{len(branch.points)} cycles, {len(branch.folds)} folds, status {branch.status}")
    if args.out:
        write_json(args.out, branch.to_json(), args)    # CycleBranch.load reads it
    if args.plot:
        plot_branch(branch, args.plot)
    out = {"hopf": branch.hopf, "status": branch.status,
           **_stop(branch.status, branch.message, "--max-points", args.max_points, args),
           "eps": branch.eps, "folds": [_point_summary(p) for p in branch.folds],
           "contact": None if branch.contact is None else _point_summary(branch.contact),
           "points": [_point_summary(p) for p in branch.points], "wall_time": branch.wall_time}
    if args.through_contact:
        out["impacting"] = _through_contact(scene, branch, args, say)
    return add_physical(out, scene, "lco")


def _through_contact(scene, branch, args, say) -> dict:
    """The impacting branch on the model with contact from the contact-free ``branch``
    (:func:`fsicas.cycles.impacting_cycles`: from its last cycle well before the wall)."""
    if branch.contact is None:
        return {"status": "not_reached", "message": "the contact-free branch did not reach "
                "the wall below --ustar-max", "points": []}
    scene, start = impacting_start(scene.replace(contact=True), branch)
    model = build_model(scene)
    imp = _impacting_branch(scene, model, start, args, say)
    say.stats(f"{len(imp.points)} impacting cycles, {len(imp.special)} special, "
              f"status {imp.status}")
    worst = imp.max_error_estimate
    if worst > COARSE_MESH:
        say.stage(f"warning: the collocation error indicator reached {worst:.2g} (> "
                  f"{COARSE_MESH:g}): the mesh is too coarse for these cycles; raise "
                  "--impact-ntst", always=True)
    stop = _stop(imp.status, imp.message, "--impact-points", args.impact_points, args)
    if imp.status == "max_points":
        say.stage(f"warning: {stop['message']}", always=True)
    return {"status": imp.status, **stop, "eps": imp.eps,
            "max_error_estimate": worst,
            "reference_force": reference_force(model), "route": args.impact_route,
            "start_ustar": start.ustar, "wall_time": imp.wall_time,
            "points": [{k: getattr(p, k) for k in _IMPACT_KEYS} for p in imp.points],
            "special": [_special_summary(p) for p in imp.special]}


def _impacting_branch(scene, model, start, args, say):
    """The impacting branch from ``start`` by ``--impact-route``, on to ``--ustar-max``
    or ``--impact-points`` points."""
    law = f"k* = {scene.contact_stiffness:g}, eps/H = {scene.contact_eps:g}"
    points = args.impact_points or UNLIMITED_POINTS
    if args.impact_route == "shooting":
        settings = ImpactSettings(max_points=points)
        how = f"multiple shooting ({settings.segments} segments, {law})"
    else:
        settings = CollocationImpactSettings(ntst=args.impact_ntst, max_points=points,
                                             refine_ntst=args.special_ntst)
        how = f"adaptive collocation (NTST = {settings.ntst}, {law})"
    say.stage(f"through contact from U* = {start.ustar:.5g} by {how}")
    return impacting_cycles(scene, start, method=args.impact_route, settings=settings,
                            model=model, ustar_max=args.ustar_max)


def _stop(status: str, message: str, option: str, value, args) -> dict:
    """``stopped_by`` (the option that ended a branch: ``option`` = ``value`` on its
    points, ``--ustar-max`` at the U* bound; None for the wall or a failure) and the
    ``message`` saying so."""
    if status == "max_points":
        by = f"{option} {value}"
        message = (f"stopped after {value} points by {by}, below --ustar-max "
                   f"{args.ustar_max:g}: raise {option} to go on ({message})")
    elif status == "bound":
        by = f"--ustar-max {args.ustar_max:g}"
        message = f"reached {by}"        # the library's words name its internal parameter
    else:
        by = None
    return {"stopped_by": by, "message": message}


def _special_summary(point) -> dict:
    """A special impacting cycle: its kind, whether Newton refined it (and on which
    NTST and NCOL), the measures, its critical multiplier [re, im] and its flow defect
    (None where not located)."""
    m = point.critical_multiplier
    return {"kind": point.kind, "located": point.located, "ntst": point.ntst,
            "ncol": point.ncol,
            "flow_defect": point.flow_defect if math.isfinite(point.flow_defect) else None,
            **{k: getattr(point, k) for k in _IMPACT_KEYS},
            "multiplier": [float(m.real), float(m.imag)]}


def _tolerance(text: str) -> float | None:
    """``--quadrature-tol``: a number, or 'none' (no control)."""
    return None if text.strip().lower() == "none" else float(text)


def _point_summary(point) -> dict:
    """The JSON keys of one branch point (docs/cycles.md)."""
    return {k: getattr(point, k) for k in _POINT_KEYS}
