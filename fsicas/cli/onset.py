"""CLI command ``fsicas onset``: the onset of instability (the snoring threshold of a
soft palate) on the linear analysis of :func:`fsicas.linear.hopf.critical_velocity`,
flutter or static divergence (``kind``), in physical units with ``--physical``
(docs/units.md): onset airflow (m/s, L/min), frequency (Hz), pressure drop (Pa), sub- or
supercritical, and the margin to the given (or the input's default) airflow.
"""
from __future__ import annotations

from ..linear.deflected import deflected_branch
from ..linear.onset import onset_at_own_flow
from ..linear.truncation import with_enough_modes
from ..model.assembly import build_model
from ..physical_report import onset_json, scales_json
from ..scene import MAX_ABS_USTAR
from .scene_options import add_scene_options, physical_from_args, scene_from_args

__all__ = ["add_onset_command"]

#: Default search bound in U*, raised to 1.5 times the reference flow's U* above it.
USTAR_MAX = 40.0
_HOPF_KEYS = ("kind", "mstar", "ustar_crit", "pressure_drop", "omega", "freq_ratio", "l1",
              "criticality", "dominant_mode", "bifurcation", "symmetry_breaking", "truncation")


def add_onset_command(sub) -> None:
    """Add the ``onset`` subcommand."""
    p = sub.add_parser("onset", help="onset of instability (snoring threshold), flutter or "
                       "divergence: airflow, frequency, pressure drop, criticality; in physical "
                       "units with --physical")
    add_scene_options(p)
    p.add_argument("--ustar-max", type=float, default=None,
                   help=f"search the onset below this U* (default {USTAR_MAX:g}, or 1.5 times "
                   "the U* of the airflow when higher)")
    p.set_defaults(run=_cmd_onset, human=_print_onset)


def _search_bound(args, reference: float | None) -> float:
    if args.ustar_max is not None:
        return args.ustar_max
    return min(max(USTAR_MAX, 1.5 * abs(reference or 0.0)), MAX_ABS_USTAR)


def _cmd_onset(args) -> dict:
    given = physical_from_args(args)
    auto = args.modes == "auto"
    args.modes = None if auto else args.modes
    scene = scene_from_args(args)
    has_flow = args.ustar is not None if given is None else given[1] is not None
    reference = scene.ustar if has_flow else None
    ustar_max = _search_bound(args, reference)
    by_viscosity = given is not None and "viscosity" in given[0].values and \
        args.friction is None and "friction" not in given[0].scene_fields
    find = lambda sc: onset_at_own_flow(sc, build_model(sc), ustar_max,
                                        given[0] if by_viscosity else None)
    if auto:
        scene, (_, hopf, reynolds) = with_enough_modes(scene, lambda sc: (
            (found := find(sc)), found[1].truncation if found[1] else 0.0))
    else:
        scene, hopf, reynolds = find(scene)
    found = {k: hopf.to_json().get(k) for k in _HOPF_KEYS} if hopf else \
        {k: (scene.mstar if k == "mstar" else None) for k in _HOPF_KEYS}
    out = {"found": hopf is not None, **found, "ustar_reference": reference,
           "ustar_max": ustar_max, "friction": scene.friction, "hstar": scene.hstar,
           "modes": scene.modes}
    if hopf is not None and hopf.kind == "divergence" and hopf.symmetry_breaking:
        out["deflected"] = deflected_branch(scene, build_model(scene), hopf,
                                            ustar_max).to_json()
    if given is not None:
        physical, _ = given
        out["physical"] = {"source": physical.source, "description": physical.description,
                           **onset_json(scene.scales, found if hopf else None, reference, ustar_max),
                           "friction": scene.friction, "reynolds": reynolds,
                           "inputs": physical.to_json(), "scales": scales_json(scene.scales)}
    return out


def _print_onset(result: dict) -> None:
    """The onset in sentences (``fsicas onset`` without ``--json``)."""
    ph = result.get("physical")
    if ph is not None:
        print(f"{ph['source']}: {ph['description']}" if ph["description"] else ph["source"])
    if not result["found"]:
        print(f"no onset of instability below U* = {result['ustar_max']:g} "
              f"(M* = {result['mstar']:.4g})")
    elif result["kind"] == "divergence":
        print(f"static divergence at U*_c = {result['ustar_crit']:.6g} (M* = "
              f"{result['mstar']:.4g}): a real eigenvalue crosses zero at a "
              f"{result['bifurcation']} of the steady branch"
              + (" (symmetry breaking: the beam is pushed towards one wall)"
                 if result["symmetry_breaking"] else "")
              + f", dominant mode {result['dominant_mode']}, pressure drop "
              f"{result['pressure_drop']:.6g}")
        _print_deflected(result.get("deflected"))
    elif ph is None:
        print(f"flutter onset at U*_c = {result['ustar_crit']:.6g} (M* = {result['mstar']:.4g}), "
              f"omega = {result['omega']:.6g} ({result['freq_ratio']:.4g} x omega_1), "
              f"pressure drop {result['pressure_drop']:.6g}, {result['criticality']}")
    else:
        _print_physical_onset(result, ph)
    for note in result.get("warnings", []):
        print(f"warning: {note}")


def _print_deflected(branch: dict | None) -> None:
    """The deflected steady states born at a pitchfork, in a sentence."""
    if not branch or not branch["ustar"]:
        return
    u, stable = branch["ustar"], branch["stable"]
    verdict = "stable" if all(stable) else f"unstable at {stable.count(False)} of {len(u)} points"
    print(f"  deflected steady states (a mirror pair) for U* in [{min(u):.6g}, {max(u):.6g}]: "
          f"{verdict}; largest tip deflection {max(map(abs, branch['tip_deflection'])):.4g} L"
          + (" (they end at a second branch point)" if branch["status"] == "event" else "")
          + (" (they end where the tip reaches the wall)" if branch["status"] == "wall" else ""))


def _print_physical_onset(result: dict, ph: dict) -> None:
    print(f"  flutter onset at {ph['onset_flow_l_min']:.4g} L/min "
          f"({ph['onset_velocity_m_s']:.4g} m/s mean inlet velocity; U*_c = "
          f"{result['ustar_crit']:.5g} at M* = {result['mstar']:.4g}, H* = {result['hstar']:.4g})")
    print(f"  frequency {ph['frequency_hz']:.4g} Hz ({result['freq_ratio']:.3g} x the first "
          f"in-vacuo mode, {ph['scales']['first_mode_hz']:.4g} Hz; dominant mode "
          f"{result['dominant_mode']})")
    print(f"  pressure drop at the onset {ph['pressure_drop_pa']:.4g} Pa; friction "
          f"f = {ph['friction']:.4g}" + ("" if ph["reynolds"] is None
                                         else f" (Re = {ph['reynolds']:.4g} at the onset)"))
    what = ("a jump to a large-amplitude oscillation at the onset, kept down to a lower "
            "flow (hysteresis)" if result["criticality"] == "subcritical"
            else "a small oscillation that grows with the flow past the onset")
    print(f"  {result['criticality']} (l1 = {result['l1']:.3g}): {what}")
    if ph["reference_flow_l_min"] is not None:
        verdict = "flutters" if ph["flutters_at_reference"] else "stable"
        print(f"  at {ph['reference_flow_l_min']:.4g} L/min ({ph['reference_velocity_m_s']:.4g} "
              f"m/s): {verdict}; margin {ph['margin_flow_l_min']:+.4g} L/min (onset / flow = "
              f"{ph['margin_ratio']:.3g})")
