"""CLI command ``fsicas sound``: the sound a fluttering palate radiates
(:mod:`fsicas.timedomain.sound`, docs/sound.md): a time integration in physical units,
the monopole pressure at ``--distance`` from the settled cycle looped to ``--duration``
(or, with ``--breath``, from a whole breath), written as a 44.1 kHz WAV with its
spectrogram; the JSON holds the fundamental, the level, the harmonics and the WAV's
scale factor.
"""
from __future__ import annotations

import math
import warnings

from ..plots.sound import plot_sound
from ..timedomain.integrators import Settings
from ..timedomain.run import run_case
from ..timedomain.sound import (AUDIO_RATE, breath_run, cycle_sound, trajectory_sound,
                                write_wav)
from .meta import cli_meta, record
from .progress import reporter
from .scene_options import add_scene_options, scene_from_args

__all__ = ["add_sound_command"]

#: The contact law of ``sound`` when none is given: the wall holds the palate's impacts.
SOUND_STIFFNESS, SOUND_EPS = 1e8, 0.1
#: The default integration time to settle a cycle, and the start-up kept before the
#: sound of an unsettled run (units of T; :func:`_t_end`).
SETTLE_T_END, LEAD_T = 20.0, 10.0

#: Units of the fields of the JSON (its meta.units).
SOUND_UNITS = {"fundamental_hz": "Hz", "dominant_hz": "Hz", "spl_db": "dB SPL re 20 uPa (RMS)",
                  "harmonics_pa": "Pa (amplitudes)", "distance_m": "m", "period_s": "s",
                  "duration_s": "s", "sample_rate_hz": "Hz", "peak_pa": "Pa", "rms_pa": "Pa",
                  "wav_pa_per_count": "Pa per int16 count", "onset_s": "s", "offset_s": "s",
                  "t_end": "nondimensional (units of T)"}


def add_sound_command(sub) -> None:
    """Add the ``sound`` subcommand."""
    p = sub.add_parser("sound", help="the radiated sound of the flutter (snore): WAV, "
                       "spectrogram, fundamental, dB SPL; needs --physical")
    add_scene_options(p)
    p.add_argument("--out", metavar="FILE.wav", help="write the sound as a 44.1 kHz 16-bit WAV")
    p.add_argument("--plot", metavar="FILE", help="figure: pressure signal and spectrogram")
    p.add_argument("--distance", type=float, default=0.3, help="listener distance r (m)")
    p.add_argument("--duration", type=float, default=2.0,
                   help="length of the sound (s); with --breath the breath's duration")
    p.add_argument("--breath", action="store_true", help="one breath from rest: the flow "
                   "rises from 0 to --flow and back (|sin|) over --duration; onset and offset "
                   "heard")
    p.add_argument("--t-end", type=float, default=None, help="integration time (units of T; "
                   f"not with --breath; default: {SETTLE_T_END:g}, or --duration plus "
                   f"{LEAD_T:g} T when the sound is longer)")
    p.add_argument("--dt-out", type=float, default=2e-4, help="output step (units of T)")
    p.add_argument("--rtol", type=float, default=1e-7, help="relative tolerance")
    p.add_argument("--quadrature-tol", default="auto", metavar="TOL",
                   help="repeat the run on more nodes while its quadrature error exceeds TOL "
                        "(default auto: 1e-4 with the contact law); 'none': the scene's nodes, "
                        "the error reported")
    p.set_defaults(run=_cmd_sound, human=_print_sound)


def _quadrature_tol(text: str) -> float | str | None:
    """``--quadrature-tol``: 'auto', 'none' (no control) or a number in (0, 1)."""
    word = text.strip().lower()
    if word in ("auto", "none"):
        return None if word == "none" else word
    try:
        value = float(word)
    except ValueError:
        value = math.nan
    if not 0 < value < 1:
        raise ValueError(f"--quadrature-tol must be a number in (0, 1), 'auto' or 'none', got {text!r}")
    return value


def _check(args) -> None:
    if args.physical is None:
        raise ValueError("--physical PRESET|FILE.toml is needed: the sound is in Pa at a "
                         "distance in m (e.g. --physical soft_palate)")
    for option in ("distance", "duration", "t_end", "dt_out"):
        value = getattr(args, option)
        if value is None:
            continue
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"--{option.replace('_', '-')} must be > 0, got {value}")
    _quadrature_tol(args.quadrature_tol)
    if not 0.01 <= args.duration <= 600:
        raise ValueError(f"--duration must lie in [0.01, 600] s, got {args.duration}")
    if args.out and not args.out.lower().endswith(".wav"):
        raise ValueError(f"--out {args.out}: the sound is written as WAV, name it FILE.wav")


def _scene(args):
    """The scene, with the contact law on (:data:`SOUND_STIFFNESS`, :data:`SOUND_EPS`
    where not given) unless ``--contact``/``--no-contact`` or the input says otherwise."""
    scene = scene_from_args(args, need_flow=True)
    if args.contact is None and not scene.contact:
        scene = scene.replace(contact=True,
                              contact_stiffness=args.contact_stiffness or SOUND_STIFFNESS,
                              contact_eps=args.contact_eps or SOUND_EPS)
    return scene


def _t_end(args, scene) -> float:
    """The integration time (units of T): the breath's length, ``--t-end``, or by
    default :data:`SETTLE_T_END` to settle, longer when ``--duration`` is: an unsettled
    run's sound is its last ``--duration``, after at least :data:`LEAD_T` of start-up."""
    heard = args.duration / scene.scales.time
    if args.breath:
        return heard
    return args.t_end if args.t_end is not None else max(SETTLE_T_END, heard + LEAD_T)


def _cmd_sound(args) -> dict:
    _check(args)
    scene = _scene(args)
    t_end = _t_end(args, scene)
    settings = Settings(rtol=args.rtol, atol=1e-10, dt_out=args.dt_out)
    record(args, scene, integrator=settings, t_end=t_end)
    say = reporter(args)
    say.stage(f"time integration to t = {t_end:g} T ({scene.scales.seconds(t_end):.3g} s), "
              f"N = {scene.modes}")
    if args.breath:
        run = breath_run(scene, t_end, settings, progress=say.bars,
                         quadrature_tol=_quadrature_tol(args.quadrature_tol))
        sound = trajectory_sound(run.trajectory, scene.scales, args.distance, AUDIO_RATE)
    else:
        run = run_case(scene, t_end, settings=settings, progress=say.bars,
                       quadrature_tol=_quadrature_tol(args.quadrature_tol))
        sound = _sound(run, scene, args)
    traj = run.trajectory      # the run's quadrature, controlled (docs/simulate.md)
    out = {**sound.to_json(), "outcome": run.outcome.outcome, "status": run.status,
           "message": traj.message, "t_end_reached": float(traj.t[-1]),
           "quadrature_error": run.quadrature_error, "quadrature_nodes": run.model.scene.n_quad,
           "quadrature_tol": run.quadrature_tol,
           "contact": scene.contact, "out": args.out, "plot": args.plot}
    if args.out:
        out["wav_pa_per_count"] = write_wav(sound, args.out)
    if args.plot:
        plot_sound(sound, args.plot)
    meta = cli_meta(args)
    return {**out, "meta": {**meta, "units": {**SOUND_UNITS, **meta["units"]}}}


def _sound(run, scene, args):
    """The cycle looped, or the last ``--duration`` of a run that did not settle (with a
    warning); ValueError if the run failed before that."""
    traj, sc = run.trajectory, scene.scales
    if run.outcome.periodic:
        return cycle_sound(traj, sc, args.distance, args.duration, AUDIO_RATE)
    if traj.failed or run.outcome.outcome == "decay" or (
            run.outcome.outcome == "contact" and not scene.contact):
        why = traj.message or "no oscillation"
        raise ValueError(f"no sound: the run ended as {run.outcome.outcome} ({why}); give a "
                         "higher --flow, --contact, or a stiffer contact law "
                         "(--contact-stiffness, --contact-eps)")
    span = sc.time * (traj.t[-1] - traj.t[0])
    if span < args.duration:
        raise ValueError(f"the run ({span:.3g} s) is shorter than --duration "
                         f"{args.duration:g} s and did not settle ({run.outcome.outcome}): "
                         f"raise --t-end to at least {args.duration / sc.time:.4g} (T = "
                         f"{sc.time:.4g} s) or shorten --duration")
    warnings.warn(f"the oscillation did not settle ({run.outcome.outcome} by t = "
                  f"{traj.t[-1]:.4g} T): the sound is the last {args.duration:g} s of the "
                  "trajectory, its fundamental that of the median period between the tip's returns")
    return trajectory_sound(traj, sc, args.distance, AUDIO_RATE,
                            traj.t[-1] - args.duration / sc.time)


def _print_sound(result: dict) -> None:
    f0, top = result["fundamental_hz"], result["dominant_hz"]
    print(f"sound at {result['distance_m']:g} m: {result['spl_db']:.1f} dB SPL, fundamental "
          + ("none" if f0 is None else f"{f0:.4g} Hz") + ", strongest line "
          + ("none" if top is None else f"{top:.4g} Hz") + f" ({result['source']}, outcome "
          f"{result['outcome']})")
    print("  harmonics (mPa): " + ", ".join(f"{a * 1e3:.3g}" for a in result["harmonics_pa"]))
    if result.get("onset_s") is not None:
        print(f"  snore heard from {result['onset_s']:.3g} s to {result['offset_s']:.3g} s")
    for key in ("out", "plot"):
        if result[key]:
            print(f"  wrote {result[key]}" + (f" ({result['wav_pa_per_count']:.4g} Pa per count)"
                                              if key == "out" else ""))
    for note in result.get("warnings", []):
        print(f"warning: {note}")
