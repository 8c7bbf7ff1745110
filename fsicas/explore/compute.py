"""What the explorer shows, from the library's analyses (no physics of its own): the
scene of the page's inputs, the instant view (steady state, eigenvalues, the least stable
mode shape), the onset and the boundary, each as plain data for the page."""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from ..cycles.collocation import CycleSettings, cycle_branch
from ..cycles.curves import CurveSettings, curve_seeds, cycle_curves
from ..cycles.impacting_collocation import CollocationImpactSettings
from ..cycles.impacting_routes import impacting_cycles, through_contact_law
from ..linear import critical_velocity, linear_stability, stability_boundary
from .. import strict_json
from ..physical import KEYS, Physical, load_physical, parse_flow
from ..scene import Scene, directed_ustar
from ..timedomain.run import run_case, sweep_model
from ..timedomain.sound import AUDIO_RATE, cycle_sound, line_spectrum

__all__ = ["INPUTS", "PHYSICAL_INPUTS", "scene_of", "preset_scene", "physical_texts",
           "physical_scene", "input_text", "instant_view", "onset_view",
           "boundary_view", "boundary_grid", "boundary_range", "curves_view",
           "cycles_view", "impacting_view", "CYCLE_USTAR_MAX",
           "BOUNDARY_PER_DECADE", "run_view",
           "SOUND_DISTANCE", "SOUND_DURATION", "export"]

#: The page's inputs: Scene field -> (label, type); their order on the page.
INPUTS = {"mstar": ("M*", float), "ustar": ("U*", float), "hstar": ("H*", float),
          "friction": ("f", float), "kl": ("KL", float), "zeta": ("ζ", float),
          "modes": ("N", int)}
#: The physical inputs offered with a preset or a physical file (those of its [physical]
#: table but the nondimensional friction and zeta, which have their own boxes): key -> label.
PHYSICAL_INPUTS = {"flow": "airflow (L/min or m/s)", "E": "Young's modulus E",
                   "nu": "Poisson ratio ν", "rho_s": "beam density ρ_s",
                   "e": "thickness e", "L": "length L", "b": "width b",
                   "gap": "gap of each channel", "H1": "gap H1 (above)", "H2": "gap H2 (below)",
                   "rho_f": "fluid density ρ_f", "viscosity": "fluid viscosity μ"}
#: Points of the boundary map per decade of M*; it spans the two decades around M*.
BOUNDARY_PER_DECADE = 6


def _number(name: str, text, kind) -> float | int:
    """``text`` read as ``kind``; ValueError naming the input otherwise."""
    try:
        value = kind(str(text).strip())
    except ValueError:
        what = "an integer" if kind is int else "a number"
        raise ValueError(f"{name} must be {what}, got {str(text)!r}") from None
    return value


def _value(name: str, text) -> float | int | tuple:
    """The page's input ``name`` read from ``text``; ζ also one value per mode, separated
    by commas (as a scene file may give it)."""
    kind = INPUTS[name][1]
    if name == "zeta" and "," in str(text):
        return tuple(_number(name, part, kind) for part in str(text).split(","))
    return _number(name, text, kind)


def input_text(value) -> str:
    """The text of a Scene field's value in the page's box (a tuple comma-separated)."""
    if isinstance(value, tuple):
        return ", ".join(f"{v:.6g}" for v in value)
    return "" if value is None else f"{value:.6g}"


def scene_of(base: Scene, texts: dict) -> Scene:
    """``base`` with the page's inputs (field -> text; ``beam`` and ``slenderness``, empty
    for none, together; ``ends``; ``direction`` with the speed |U*| in ``ustar``,
    ``directed_ustar``) applied; the library's ValueError for values it refuses."""
    values = {k: _value(k, texts[k]) for k in INPUTS if k in texts}
    if "direction" in texts and "ustar" in values:     # the box holds the speed |U*|
        values["ustar"] = directed_ustar(values["ustar"], texts["direction"])
    if "ends" in texts:
        values["ends"] = texts["ends"]
    if "beam" in texts:
        text = str(texts.get("slenderness", "")).strip()
        values["beam"] = texts["beam"]
        values["slenderness"] = _number("slenderness", text, float) if text else None
    return base.replace(**values)


def _default_walls(scene: Scene) -> Scene:
    """Straight symmetric channels as the default walls of the scene's H* (H* stays an
    input of the page)."""
    if scene.straight and scene.symmetric:
        return scene.replace(channel1=None, channel2=None)
    return scene


def preset_scene(name: str | None) -> Scene:
    """The Scene of a physical preset at its default airflow (scales kept for Hz and
    L/min), or the default Scene."""
    if name is None:
        return Scene()
    return physical_scene(load_physical(name))


def physical_texts(physical: Physical) -> dict:
    """The physical inputs of ``physical`` (a preset or a file) as its file writes them
    (a number, SI, with its unit added): key -> text, for the keys of
    :data:`PHYSICAL_INPUTS` it has."""
    raw = physical.raw
    return {k: raw[k] if isinstance(raw[k], str) else f"{raw[k]:g} {KEYS[k]}".rstrip()
            for k in PHYSICAL_INPUTS if k in raw}


def physical_scene(physical: Physical, texts: dict | None = None) -> Scene:
    """The Scene of ``physical`` with the page's physical inputs (key -> text with its
    unit, :data:`PHYSICAL_INPUTS`; none: its own, at its default airflow) in place of its
    own: read and converted by the library (``Physical.from_table``, ``parse_flow``,
    ``Physical.scene``), its ValueError for what it refuses."""
    if texts is None:
        return _default_walls(physical.scene(physical.flow))
    table = {**physical.raw, **{k: v for k, v in texts.items() if k != "flow"}}
    changed = Physical.from_table(table, physical.source, physical.description,
                                  physical.scene_fields)
    flow = parse_flow(texts["flow"], "airflow") if "flow" in texts else physical.flow
    return _default_walls(changed.scene(flow))


def _hz(scene: Scene, omega: float) -> float | None:
    return None if scene.scales is None else scene.scales.hz(omega)


def _l_per_min(scene: Scene) -> float | None:
    """The airflow of a physical scene in L/min, where its gap is still the scales'
    (H* unchanged from the physical input's)."""
    sc = scene.scales
    if sc is None or sc.gap is None or not math.isclose(scene.hstar * sc.length, sc.gap,
                                                         rel_tol=1e-5):
        return None
    return sc.l_per_min(scene.ustar)


def instant_view(scene: Scene) -> dict:
    """Steady state and eigen-analysis at ``scene`` (``linear_stability``); the least
    stable eigenvalue lambda_0 = sigma + i omega gives the growth rate sigma and the
    frequency |omega|; its complex mode shape y(x) with max |y| = 1."""
    model = sweep_model(scene, guarded=False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        stab = linear_stability(scene, model)
    lam = stab.eigenvalues
    shape = stab.mode_shape(model, 0)
    steady = stab.steady.to_json(model)
    return {"stable": stab.stable, "eigenvalues": lam, "growth_rate": float(lam[0].real),
            "omega": abs(float(lam[0].imag)), "freq_ratio": abs(float(stab.freq_ratio[0])),
            "hz": _hz(scene, abs(float(lam[0].imag))), "x": shape["x"], "y": shape["y"],
            "l_per_min": _l_per_min(scene),
            "pressure_drop": steady["pressure_drop"], "tip": steady["tip_deflection"],
            "x_ref": steady["x_ref"],
            "warnings": [str(w.message) for w in caught]}


def onset_view(scene: Scene) -> dict:
    """The onset of ``scene``'s steady branch (``critical_velocity``) as JSON, with Hz,
    L/min and Pa where the scene is physical; ``{"kind": "none"}`` if it stays stable."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        onset = critical_velocity(scene, sweep_model(scene, guarded=False))
    out = {"kind": "none"} if onset is None else onset.to_json()
    out["warnings"] = [str(w.message) for w in caught]
    scales = scene.scales
    if onset is not None and scales is not None:
        out["hz"] = scales.hz(out.get("omega", 0.0))
        out["pa"] = scales.pa(out["pressure_drop"])
        if scales.gap is not None:
            out["l_per_min"] = scales.l_per_min(out["ustar_crit"])
    return out


def boundary_grid(mstar: float) -> np.ndarray:
    """The M* of the boundary map: the decade of ``mstar`` and the one on each side."""
    low = math.floor(math.log10(mstar)) - 1
    return np.logspace(low, low + 3, 3 * BOUNDARY_PER_DECADE + 1)


def boundary_range(mstar: float) -> str:
    """:func:`boundary_grid` as the command line writes it, ``LO:HI:COUNT``."""
    grid = boundary_grid(mstar)
    return f"{grid[0]:g}:{grid[-1]:g}:{grid.size}"


def boundary_view(scene: Scene) -> dict:
    """The stability boundary U*_c(M*) of ``scene`` (``stability_boundary``) on
    :func:`boundary_grid` as JSON."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = stability_boundary(scene, boundary_grid(scene.mstar),
                                    sweep_model(scene, guarded=False))
    out = result.to_json()
    out["warnings"] += [str(w.message) for w in caught]
    return out


def _check_count(what: str, value, most: int) -> None:
    """ValueError naming ``what`` unless ``value`` is an integer in [1, ``most``]."""
    if not (isinstance(value, int) and 1 <= value <= most):
        raise ValueError(f"the {what} must be an integer in [1, {most}], got {value!r}")


def curves_view(scene: Scene, max_points: int) -> dict:
    """The grazing and fold-of-cycles curves of ``scene`` over the map's M* window (as
    ``fsicas grazing --mstar`` :func:`boundary_range` ``--max-points``): the flutter
    boundary on :func:`boundary_grid` (``stability_boundary``), one seed per piece of it
    between its mode switches (``curve_seeds``), the curves through the cycle branches
    there (``cycle_curves``, up to U* = :data:`CYCLE_USTAR_MAX`, at most ``max_points``
    points per direction); each curve as its (M*, U*) points."""
    _check_count("curve points", max_points, MAX_CURVE_POINTS)
    if scene.contact:
        raise ValueError("the curves are of contact-free cycles: the scene has the contact "
                         "law on (contact = true)")
    grid = boundary_grid(scene.mstar)
    settings = CurveSettings(mstar_min=float(grid[0]), mstar_max=float(grid[-1]),
                             max_points=max_points)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        boundary = stability_boundary(scene, grid, sweep_model(scene, guarded=False))
        seeds = curve_seeds([s.mstar for s in boundary.switches], settings.mstar_min,
                            settings.mstar_max)
        curves = cycle_curves(scene, seeds, settings=settings, ustar_max=CYCLE_USTAR_MAX,
                              cycles=CycleSettings(quadrature_tol=settings.quadrature_tol))
    line = lambda c: {"mstar": c.column("mstar").tolist(), "ustar": c.column("ustar").tolist()}
    return {"grazing": [line(c) for c in curves.grazing], "fold": [line(c) for c in curves.fold],
            "seeds": curves.seeds, "failures": curves.failures,
            "warnings": [str(w.message) for w in caught]}


#: The U* up to which the limit-cycle branch is followed (``fsicas lco``'s default); the
#: most impacting cycles and curve points asked for.
CYCLE_USTAR_MAX, MAX_IMPACT_POINTS, MAX_CURVE_POINTS = 20.0, 1000, 1000


def _cycle(p) -> dict:
    """One cycle of a branch as plain data: U*, tip amplitude, period, stability."""
    return {"ustar": float(p.ustar), "tip_amplitude": float(p.tip_amplitude),
            "period": float(p.period), "stable": bool(p.stable)}


def cycles_view(scene: Scene, impact_points: int | None = None) -> dict:
    """The limit-cycle branch of ``scene`` from its first Hopf point up to the first wall
    contact (``cycle_branch`` with its default settings, as ``fsicas lco``) as plain data:
    per cycle U*, tip amplitude, period and stability; the contact, status and message.
    With ``impact_points``, also the branch on through contact (``impacting``, as
    ``fsicas lco --through-contact --impact-points``: :func:`impacting_view`; both
    branches then on the contact law of ``through_contact_law``, whose eps also sets
    where the contact-free one meets the wall)."""
    if impact_points is not None:        # both branches on its law, as fsicas lco does
        _check_count("impacting cycles", impact_points, MAX_IMPACT_POINTS)
        scene = through_contact_law(scene)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        branch = cycle_branch(scene, ustar_max=CYCLE_USTAR_MAX)
        impacting = None if impact_points is None else impacting_view(scene, branch,
                                                                      impact_points)
    return {"status": branch.status, "message": branch.message, "hopf": branch.hopf,
            "points": [_cycle(p) for p in branch.points],
            "contact": None if branch.contact is None else _cycle(branch.contact),
            "impacting": impacting, "warnings": [str(w.message) for w in caught]}


def impacting_view(scene: Scene, branch, points: int) -> dict:
    """The impacting cycles of ``scene`` (with its contact law) on through contact from
    its contact-free ``branch`` (``impacting_cycles`` by adaptive collocation, as
    ``fsicas lco --through-contact``), at most ``points`` of
    them, up to :data:`CYCLE_USTAR_MAX`: per cycle also its contact intervals per period
    and peak impact force; its located special cycles (kind and U*)."""
    if branch.contact is None:
        return {"status": "not_reached", "message": "the contact-free branch did not reach "
                f"the wall below U* = {CYCLE_USTAR_MAX:g}", "points": [], "special": []}
    imp = impacting_cycles(scene.replace(contact=True), branch,
                           settings=CollocationImpactSettings(max_points=points),
                           ustar_max=CYCLE_USTAR_MAX)
    cycle = lambda p: {**_cycle(p), "impacts": int(p.impacts), "peak_force": float(p.peak_force)}
    return {"status": imp.status, "message": imp.message,
            "points": [cycle(p) for p in imp.points],
            "special": [{"kind": p.kind, "ustar": float(p.ustar)} for p in imp.special]}


#: The listener's distance (m) and the length (s) of the sound of a settled cycle.
SOUND_DISTANCE, SOUND_DURATION = 0.3, 2.0
#: Most samples of the tip's history sent to the page; the sound's spectrum up to (Hz).
HISTORY_POINTS, SPECTRUM_MAX_HZ = 2000, 5000.0


def run_view(scene: Scene, t_end: float) -> dict:
    """A time run of ``scene`` to ``t_end`` (``run_case``: the perturbed steady state
    integrated and classified) as ``fsicas simulate --json``, the tip deflection
    y(x_ref, t) (at most :data:`HISTORY_POINTS` samples) and, for a physical scene whose run
    settled on a cycle, its sound (``cycle_sound``: Pa at :data:`SOUND_DISTANCE`) and the
    sound's spectrum (``line_spectrum``: Hz and dB SPL up to :data:`SPECTRUM_MAX_HZ`)."""
    if not (math.isfinite(t_end) and 0 < t_end <= 1000):
        raise ValueError(f"t_end must be in (0, 1000], got {t_end}")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = run_case(scene, t_end)
    traj, n = run.trajectory, scene.modes
    step = max(1, traj.t.size // HISTORY_POINTS)
    tip = traj.x[::step, n:2 * n] @ np.asarray(run.model.probe.phi)[:, 1]
    out = {**run.to_json(), "t": traj.t[::step], "tip": tip, "sound": None}
    out["warnings"] = list(dict.fromkeys(out["warnings"] + [str(w.message) for w in caught]))
    if scene.scales is not None and run.outcome.periodic:
        sound = cycle_sound(traj, scene.scales, SOUND_DISTANCE, SOUND_DURATION, AUDIO_RATE)
        hz, db = line_spectrum(sound.pressure, sound.rate, SPECTRUM_MAX_HZ)
        out["sound"] = {**sound.to_json(), "pressure": sound.pressure.astype(np.float32),
                        "spectrum": {"hz": hz, "spl_db": db}}
    return out


def export(scene: Scene, view: dict, onset: dict | None, command: str, *,
           boundary: dict | None = None, cycles: dict | None = None,
           run: dict | None = None, curves: dict | None = None) -> str:
    """The current view as JSON: the scene, the instant view (eigenvalues as [Re, Im]
    pairs, the mode shape dropped), the onset if known, the reproducing command; the map,
    the limit-cycle branch, the time run and the grazing and fold curves of the scene
    where computed (the run's tip
    history and its sound's spectrum as lists, its sound without the samples)."""
    instant = {k: v for k, v in view.items() if k not in ("eigenvalues", "x", "y")}
    instant["eigenvalues"] = [[float(l.real), float(l.imag)] for l in view["eigenvalues"]]
    if run is not None:
        sound = run["sound"]
        run = {**run, "t": np.asarray(run["t"]).tolist(), "tip": np.asarray(run["tip"]).tolist(),
               "sound": None if sound is None else {
                   **{k: v for k, v in sound.items() if k not in ("pressure", "spectrum")},
                   "spectrum": {k: np.asarray(v).tolist() for k, v in sound["spectrum"].items()}}}
    return strict_json.dumps({"scene": scene.to_dict(), "instant": instant, "onset": onset,
                              "command": command, "boundary": boundary, "cycles": cycles,
                              "run": run, "curves": curves}, indent=1)
