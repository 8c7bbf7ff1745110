"""The main job: the paper's core results on its embedded default configuration.

Default (paper, Fig. 2): H* = 1/10, f = 0.14, K0 = 0, KL = 1, zeta = 0, N = 10 modes.
Writes to the output folder: ``report.json`` (in-vacuo frequencies, steady state against
its closed form, the flutter boundary with frequencies, branches, mode switches and
criticality, the impact map's counts and the impacting cycles), ``fig2_boundary.png``,
``fig3_modes.png``, ``fig4_impact_map.png`` (with its resumable ``fig4_map.jsonl``; unless
``quick``, over the grazing and fold-of-cycles curves, ``fig4_curves.json``, and the
report counts the map points the curves explain),
``fig6_9_U7.png``, ``fig6_9_U8.5.png``, ``fig6_9_U10.png`` (impacting cycles at
N = :data:`CYCLE_MODES`, each with its truncation estimate against N/2 modes,
zeta = 0.01, with the contact law that holds, k* = 1e8, eps/H = 1e-2; the paper's
k* = 1e6, eps/H = 1e-3 is run too and reported: its gap closes, docs/simulate.md),
``fig6_9_cycles.png`` (the three cycles side by side, as the paper shows them) and,
unless ``quick``, ``boundary_variants.png`` (zeta = 0.01 and H* in {1/20, 1/5}).
``quick`` shrinks every grid and run to a smoke test.
"""
from __future__ import annotations

import textwrap
import time
from dataclasses import asdict
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from . import __version__, strict_json
from .cycles.bautin import switched_curves
from .cycles.collocation import CycleSettings
from .cycles.curves import CurveMap, CurveSettings, curve_seeds, cycle_curves, expected_outcomes
from .cycles.window import onset_points
from .linear.boundary import stability_boundary
from .linear.steady import steady_state, straight_pressure_drop
from .model.assembly import build_model
from .model.beam import clamped_free_betas
from .provenance import with_meta
from .linear.stretches import boundary_function
from .plots.linear import plot_boundary, plot_boundary_variants, plot_mode_shapes
from .plots.timedomain import cycle_view, plot_cycle, plot_cycles, plot_map, return_period
from .scene import Scene
from .timedomain.impact_map import MAP_SCENE, impact_map
from .timedomain.outcome import outcome_words
from .timedomain.impacting_run import (HOLDING_CONTACT, PAPER_CONTACT, impacting_run,
                                       with_truncation)

__all__ = ["PAPER_SCENE", "VARIANTS", "CYCLE_USTARS", "CYCLE_MODES", "REPORT_FIELDS",
           "impacting_cycle",
           "run_paper", "summary", "consistency"]

PAPER_SCENE = Scene(mstar=1.0, ustar=5.0, hstar=0.1, friction=0.14, k0=0.0, kl=1.0,
                    zeta=0.0, modes=10)
PAPER_LABEL = "paper (zeta = 0, H* = 1/10)"
VARIANTS = {"zeta = 0.01": dict(zeta=0.01), "H* = 1/20": dict(hstar=0.05),
            "H* = 1/5": dict(hstar=0.2)}
CYCLE_USTARS = (7.0, 8.5, 10.0)
#: The modes of Figs. 6-9; each cycle's truncation is estimated against half as many
#: (docs/simulate.md: at U* = 7 the period moves 3.4e-3 from N = 10 to 20, 3.4e-4 from
#: 20 to 40).
CYCLE_MODES = 20
#: The boundary is searched for onsets up to this U*.
BOUNDARY_USTAR_MAX = 40.0


#: What the report's quantities are, and their units (nondimensional, docs/model.md).
REPORT_FIELDS = {
    "units": "nondimensional: lengths by the beam length L, time by T = L^2 sqrt(rho_s e / D), "
             "pressure by D / L^3 (D the bending stiffness per unit width)",
    "scene": "each section's own scene (as scene files, docs/model.md; meta.scene is null): "
             "whole where one scene made it, else the fields held fixed while M* and U* vary "
             "over its grid",
    "omega_invacuo": "in-vacuo clamped-free frequencies w_n = beta_n^2 (rad per unit T)",
    "steady": "steady state at U*: pressure drop P0 - PL and its closed form, flow rates Q1, Q2",
    "boundary": "flutter boundary U*_c(M*) at mstar_values (onsets searched up to ustar_max): "
                "per M* the onset U*, frequency omega (rad per unit "
                "T), omega / w_1, branch, first Lyapunov coefficient l1 and criticality; the mode "
                "switches (crossings and folds of Hopf curves, located)",
    "variants": "the boundary for zeta = 0.01 and H* = 1/20, 1/5, each with its scene",
    "impact_map": "Fig. 4: outcome counts of the (U*, M*) map (decay, lco, contact, unsettled) "
                  "over its grid, each point a run to t_end (units of T) with the integrator "
                  "settings and settling criteria given; its linear boundary (first Hopf point "
                  "per M*)",
    "fig4_curves": "Fig. 4's map against its curves (fig4_curves.json: grazing and fold-of-"
                   "cycles curves, mstar and ustar per point): points whose outcome agrees "
                   "with the region the curves put them in, and the exceptions; the curves' "
                   "settings (CurveSettings); from_generalized_hopf: the boundary's "
                   "generalized Hopf points (l1 = 0, with l2) and the fold-of-cycles curve "
                   "switched onto from each",
    "impacting_cycles": "Figs. 6-9: per U* the outcome (impacting_lco: a cycle that repeats "
                        "to its convergence; impacting_nonperiodic: one that does not, measured "
                        "over its last cycles), period (units of T; the mean return time when "
                        "not periodic), tip amplitude (units of L), impacts per cycle, peak "
                        "impact force, mean flow-rate reduction; truncation_error: per measure "
                        "|X_N - X_N'| / |X_N| against the same run with truncation_modes "
                        "N' = N/2 modes (a bound where X converges in N; the peak force and "
                        "impacts per cycle do not), warned above truncation_tol; its scene, "
                        "t_end (units of T) and settle_tol (relative change per cycle)",
    "warnings": "every section's warnings, each prefixed with the section",
    "wall_time": "seconds",
}


def run_paper(out="results", quick: bool = False, progress=None, meta: dict | None = None) -> dict:
    """Compute the report and the figures and write them to ``out``. ``progress(text)``
    (optional) is told when each stage starts. ``meta``: how the report was made
    (versions, time, command line, settings; ``fsicas paper`` passes
    :func:`fsicas.cli.meta.cli_meta`'s), written as the report's ``"meta"`` with
    ``"fields"`` added (:data:`REPORT_FIELDS`)."""
    start = time.perf_counter()
    say = progress or (lambda text: None)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    scene = PAPER_SCENE
    model = build_model(scene)
    steady = steady_state(scene, model)
    mstars = np.logspace(-1, 1, 7) if quick else np.logspace(-2, 2, 33)
    say(f"Fig. 2 and 3: the flutter boundary at {len(mstars)} M* (N = {scene.modes})")
    boundary = stability_boundary(scene, mstars, model, ustar_max=BOUNDARY_USTAR_MAX)
    plot_boundary(boundary, out / "fig2_boundary.png")
    plot_mode_shapes(boundary, model, out / "fig3_modes.png")
    report = {
        "version": __version__,
        "meta": {**(meta or {}), "scene": None, "fields": REPORT_FIELDS},
        "omega_invacuo": (clamped_free_betas(scene.modes) ** 2).tolist(),
        "steady": {"scene": scene.to_dict(), "ustar": scene.ustar,
                   "pressure_drop": steady.pressure_drop,
                   "closed_form": straight_pressure_drop(scene), "Q": steady.Q.tolist()},
        "boundary": {"scene": held(scene), "mstar_values": mstars.tolist(),
                     "ustar_max": BOUNDARY_USTAR_MAX,
                     **{k: v for k, v in boundary.to_json().items() if k != "curves"}},
    }
    damped = None        # the zeta = 0.01 boundary: Fig. 4's linear boundary, drawn dense
    if not quick:
        say("the boundary variants (zeta = 0.01, H* = 1/20, 1/5)")
        report["variants"], damped = _variants(scene, mstars[::2], boundary,
                                               out / "boundary_variants.png")
    report.update(_time_domain(out, quick, say, damped))
    report["warnings"] = collected_warnings(report)
    report["wall_time"] = time.perf_counter() - start
    report = with_meta(report, report["meta"])
    (out / "report.json").write_text(strict_json.dumps(report, indent=2))
    return report


def held(scene: Scene) -> dict:
    """The fields of ``scene`` a result over a grid in (U*, M*) holds fixed."""
    return {k: v for k, v in scene.to_dict().items() if k not in ("mstar", "ustar")}


def collected_warnings(report: dict) -> list[str]:
    """Every warning of the report's sections, each prefixed with where it is."""
    found = [f"boundary: {w}" for w in report["boundary"].get("warnings", [])]
    for c in report.get("impacting_cycles", []):
        law = f"k* = {c['contact_stiffness']:g}, eps/H = {c['contact_eps']:g}"
        found += [f"impacting cycle U* = {c['ustar']:g} ({law}): {w}"
                  for w in c.get("warnings", [])]
    return found


def _variants(scene, mstars, reference, path):
    """Boundaries with structural damping and other confinements, drawn together; returns
    their report and the zeta = 0.01 boundary."""
    scenes = {PAPER_LABEL: scene,
              **{label: scene.replace(**change) for label, change in VARIANTS.items()}}
    curves = {label: reference if label == PAPER_LABEL else
              stability_boundary(variant, mstars, build_model(variant), refine=False)
              for label, variant in scenes.items()}
    plot_boundary_variants(curves, path)
    return ({label: {"scene": held(scenes[label]),
                     "points": [{"mstar": p.mstar, "ustar_crit": p.ustar_crit,
                                 "freq_ratio": p.freq_ratio}
                                for p in b.points if p.ustar_crit is not None]}
             for label, b in curves.items()}, curves["zeta = 0.01"])


def impacting_cycle(ustar: float, modes: int = CYCLE_MODES, contact: dict = HOLDING_CONTACT,
                    t_end: float = 4.0, plot=None, tol: float = 2e-2,
                    truncation: bool = True) -> dict:
    """One of the paper's impacting points (1a-c), run by
    :func:`fsicas.timedomain.impacting_run.impacting_run`; returns the run's JSON (plus U*,
    N, the contact law). ``plot``: the Figs. 6-9 panels of the last settled cycle, or of
    the last tip return of a run that hit the wall without settling. ``truncation``: with
    its modal truncation estimate against the same run with ``modes // 2`` modes
    (:func:`fsicas.timedomain.impacting_run.with_truncation`)."""
    cycle = _impacting_cycle(ustar, modes, contact, t_end, plot, tol)[0]
    if not truncation:
        return cycle
    return with_truncation(cycle, _impacting_cycle(ustar, modes // 2, contact, t_end, None, tol)[0])


def _impacting_cycle(ustar, modes, contact, t_end, plot=None, tol=2e-2):
    """:func:`impacting_cycle`'s JSON and the figures' view of its cycle (None if the run
    shows none)."""
    run = impacting_run(ustar, modes, contact, t_end, tol)
    shown = run.outcome.period is not None or return_period(run) is not None
    view = cycle_view(run) if shown and not run.trajectory.failed else None
    if plot is not None and view is not None:
        plot_cycle(view, plot)     # a perturbed periodic run: its last tip return
    return {**run.to_json(), "ustar": ustar, "modes": modes, **contact,
            "scene": run.scene.to_dict(), "t_end": t_end, "settle_tol": tol}, view


def _cycle_job(args):
    return _impacting_cycle(*args)


def _cycle_jobs(out: Path, quick: bool) -> tuple[list, list]:
    """The runs of Figs. 6-9, ``(ustar, modes, contact, t_end, plot)``: those reported
    and, for each with the law that holds, the same with half the modes (its truncation
    estimate; the paper's law, whose gap closes, has none)."""
    if quick:
        shown = [(8.5, 6, HOLDING_CONTACT, 0.6, out / "fig6_9_U8.5.png")]
    else:
        shown = [(u, CYCLE_MODES, HOLDING_CONTACT, 4.0, out / f"fig6_9_U{u:g}.png")
                 for u in CYCLE_USTARS]
    coarser = [(u, n // 2, law, t, None) for u, n, law, t, _ in shown]
    if not quick:
        shown.append((8.5, CYCLE_MODES, PAPER_CONTACT, 1.0, None))
    return shown, coarser


def _time_domain(out: Path, quick: bool, say, linear=None) -> dict:
    """Fig. 4 (the impact map, N = 10, over ``linear``, a dense boundary of its scene if
    given) and Figs. 6-9 (impacting cycles, N = :data:`CYCLE_MODES` with their
    truncation against N/2, each and side by side)."""
    if quick:
        ustars, mstars, t_map = np.array([4.0, 9.0]), np.array([1.0]), 5.0
    else:
        ustars, mstars, t_map = np.linspace(2, 16, 15), np.geomspace(0.1, 10, 7), 30.0
    say(f"Fig. 4: the impact map, {ustars.size * mstars.size} time integrations")
    result = impact_map(ustars, mstars, out / "fig4_map.jsonl", t_end=t_map, workers=2)
    curves = None if quick or linear is None else _fig4_curves(linear, mstars, ustars, say)
    switched = [] if curves is None else _fig4_bautin(linear, mstars, ustars, say)
    plot_map(result, out / "fig4_impact_map.png", linear=linear, curves=curves,
             cases=[] if quick else [(f"1{c}", u, 1.0) for c, u in zip("abc", CYCLE_USTARS)],
             switched=switched)
    jobs, coarser = _cycle_jobs(out, quick)
    say(f"Figs. 6-9: {len(jobs)} impacting cycles (N = {jobs[0][1]}) and {len(coarser)} "
        f"with N = {coarser[0][1]} (their truncation)")
    done = _run_cycles(jobs + coarser, say)
    views = [view for (_, view), job in zip(done, jobs) if job[4] is not None and view is not None]
    if views:
        plot_cycles(views, out / "fig6_9_cycles.png")
    cycles = [c for c, _ in done[:len(jobs)]]
    for i, (rough, _) in enumerate(done[len(jobs):]):
        cycles[i] = with_truncation(cycles[i], rough)
    report = {"impact_map": result.to_json(), "impacting_cycles": cycles}
    if curves is not None:
        curve_settings = fig4_curve_settings(mstars)
        (out / "fig4_curves.json").write_text(strict_json.dumps(curves.to_json(), indent=1))
        report["fig4_curves"] = {"scene": held(MAP_SCENE), "settings": asdict(curve_settings),
                                 **consistency(result, curves, boundary_function(linear)),
                                 "from_generalized_hopf": [c.to_json() for c in switched]}
    return report


def _run_cycles(jobs: list, say) -> list:
    """:func:`_cycle_job` of each job on two processes, in the jobs' order; each finished
    run told (a log sees the long stage advance)."""
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=2) as pool:
        futures = [pool.submit(_cycle_job, job) for job in jobs]
        for k, future in enumerate(as_completed(futures), 1):
            c = future.result()[0]
            say(f"impacting cycle {k}/{len(jobs)}: U* = {c['ustar']:g}, N = {c['modes']}, "
                f"{c['outcome']} ({time.perf_counter() - start:.0f} s)")
    return [future.result() for future in futures]


def fig4_curve_settings(mstars) -> CurveSettings:
    """The curves' settings over the map's M* window."""
    return CurveSettings(mstar_min=float(mstars.min()), mstar_max=float(mstars.max()))


def _fig4_curves(linear, mstars, ustars, say) -> CurveMap:
    """The grazing and fold-of-cycles curves over the map's window, seeded one per piece
    of its flutter boundary (two processes)."""
    settings = fig4_curve_settings(mstars)
    seeds = curve_seeds([s.mstar for s in linear.switches], settings.mstar_min,
                        settings.mstar_max)
    say(f"Fig. 4: grazing and fold-of-cycles curves from {len(seeds)} cycle branches")
    return cycle_curves(MAP_SCENE, seeds, settings=settings,
                        cycles=CycleSettings(quadrature_tol=settings.quadrature_tol),
                        ustar_max=float(ustars.max()), workers=2, progress=say)


def _fig4_bautin(linear, mstars, ustars, say) -> list:
    """The fold-of-cycles curves born at the generalized Hopf points of the map's
    boundary: the Hopf curve of each of its pieces (through the onset at the piece's
    middle M*) searched for l1 = 0 (``onset_points``), each point on the boundary switched
    from (``continuation.lpc_from_gh``) and its curve traced over the window."""
    settings = fig4_curve_settings(mstars)
    window = (np.log10(settings.mstar_min), np.log10(settings.mstar_max))
    edges = np.log10([settings.mstar_min, *sorted(s.mstar for s in linear.switches
                                                  if settings.mstar_min < s.mstar
                                                  < settings.mstar_max), settings.mstar_max])
    middles = 10 ** ((edges[:-1] + edges[1:]) / 2)
    model = build_model(MAP_SCENE)
    ustar_max = float(ustars.max())
    say(f"Fig. 4: the generalized Hopf points on the Hopf curves of {middles.size} pieces "
        "of the boundary")
    _, points = onset_points(MAP_SCENE, model, middles, window, ustar_max, ("gh",))
    points = [p for p in points if p.on_boundary]
    say(f"Fig. 4: the fold-of-cycles curves from {len(points)} generalized Hopf points")
    return switched_curves(MAP_SCENE, model, points, epsilon=0.02, settings=settings,
                           cycles=CycleSettings(quadrature_tol=settings.quadrature_tol),
                           ustar_max=ustar_max)


def consistency(result, curves: CurveMap, hopf) -> dict:
    """The map's outcomes against what the curves say (``expected_outcomes``): the count
    of agreeing points and each exception (an unsettled run or an outcome across a
    curve), with what was expected."""
    points = [p for p in result.points if p["outcome"] != "error"]
    expected = expected_outcomes(curves, hopf, [p["ustar"] for p in points],
                                 [p["mstar"] for p in points])
    impacting = {"contact", "impacting_lco", "impacting_nonperiodic"}
    accepted = {"decay": {"decay"}, "lco": {"lco"}, "contact": impacting,
                "bistable": {"decay", "lco"} | impacting, "unknown": {"lco"} | impacting}
    exceptions = [{"ustar": p["ustar"], "mstar": p["mstar"], "outcome": p["outcome"],
                   "expected": e} for p, e in zip(points, expected)
                  if p["outcome"] not in accepted[e]]
    return {"consistent": len(points) - len(exceptions), "exceptions": exceptions,
            "expected_counts": {k: expected.count(k) for k in accepted}}


def summary(report: dict) -> dict:
    """The headline numbers of a report, for the terminal."""
    b = report["boundary"]
    out = {"boundary points": len(b["points"]), "mode switches at M*":
           [round(w["mstar"], 3) for w in b["switches"]],
           "U*_c at M* = 1": next((p["ustar_crit"] for p in b["points"] if abs(p["mstar"] - 1) < 1e-9), None)}
    if "impact_map" in report:
        out["impact map (Fig. 4)"] = ", ".join(f"{n} {outcome}" for outcome, n in
                                               report["impact_map"]["counts"].items())
    if "fig4_curves" in report:
        c = report["fig4_curves"]
        out["map against the curves"] = (f"{c['consistent']} consistent, "
                                         f"{len(c['exceptions'])} exceptions")
    for c in report.get("impacting_cycles", []):
        key = (f"U* = {c['ustar']:g}, N = {c['modes']}, k* = {c['contact_stiffness']:g}, "
               f"eps/H = {c['contact_eps']:g}")
        out[key] = _cycle_summary(c)
    return out


def _cycle_summary(c: dict) -> str:
    """One impacting run in words: its outcome, convergence and measures."""
    if c["period"] is None:
        why = c["message"] or (f"first contact at t = {c['first_contact_time']:.4g}"
                               if c.get("first_contact_time") is not None else "no cycle")
        return f"{outcome_words(c['outcome'])} ({c['status']}): " + textwrap.shorten(why, 200, placeholder=" ...")
    period = "mean return time" if c["outcome"] == "impacting_nonperiodic" else "period"
    text = (f"{outcome_words(c['outcome'])} ({c['status']}, convergence {c['convergence']:.3g}): {period} "
            f"{c['period']:.5f}, {c['impacts_per_cycle']:g} impacts/cycle, peak force "
            f"{c['max_impact_force']:.4g} F0, flow -{100 * c['mean_flow_reduction']:.1f} %")
    if "truncation_error" in c:
        errors = ", ".join(f"{k} {'-' if e is None else f'{e:.1g}'}"
                           for k, e in c["truncation_error"].items())
        text += f"; against N = {c['truncation_modes']}: {errors}"
    return text
