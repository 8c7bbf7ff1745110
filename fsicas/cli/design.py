"""CLI command ``fsicas design``: what change of the palate would stop the snore
(:mod:`fsicas.linear.elasticity`, :mod:`fsicas.linear.design`, docs/design.md). The onset
airflow and frequency of a physical configuration and their elasticities to every
physical parameter; with ``--target-flow`` and ``--vary``, the smallest change of that
parameter (or weighted combination) that lifts the onset to the target, verified by the
eigenvalues at 99.5 % and 100.5 % of it.
"""
from __future__ import annotations

from ..linear.design import ALIASES, DESIGN_MAX_FACTOR, design_for_flow, parse_vary
from ..linear.elasticity import palate_sensitivity
from ..physical import Flow, parse_flow
from .meta import cli_meta, record
from .scene_options import add_scene_options, physical_from_args, scene_values

__all__ = ["add_design_command"]

#: Units of the fields of the JSON (its meta.units).
DESIGN_UNITS = {
    "onset_flow_l_min": "L/min", "onset_velocity_m_s": "m/s", "frequency_hz": "Hz",
    "ustar_crit": "nondimensional (units of L/T)",
    "sensitivities": "flow_elasticity = d ln Q_c / d ln theta, frequency_elasticity = "
                     "d ln f_c / d ln theta (dimensionless); *_per_unit: the same per SI "
                     "unit of theta ('unit')",
    "design": "before/after in the parameter's SI unit; flows in L/min; frequencies in Hz"}


def add_design_command(sub) -> None:
    """Add the ``design`` subcommand."""
    p = sub.add_parser("design", help="what change of the palate stops the snore: elasticities "
                       "of the onset airflow and frequency to every physical parameter, and "
                       "the smallest change of one that lifts the onset to a target airflow; "
                       "needs --physical")
    add_scene_options(p)
    p.add_argument("--target-flow", metavar="FLOW", help="lift the onset to this airflow "
                   "(e.g. 30L/min, the patient's peak inspiratory flow; negative, or its "
                   "magnitude with --direction reverse: an expiratory flow, whose magnitude "
                   "the onset's is lifted to); with --vary")
    p.add_argument("--vary", metavar="NAME[=W],...", help="the parameter to change: a "
                   "[physical] key (E, e, L, rho_s, zeta, gap, H1, H2, b, ...) or "
                   f"{', '.join(ALIASES)}; or a weighted combination moved together, "
                   "ln theta_j changing as w_j (e.g. stiffness=1,length=-1)")
    p.add_argument("--ustar-max", type=float, default=40.0,
                   help="search the onset below this U* (default 40)")
    p.set_defaults(run=_cmd_design, human=_print_design)


def _check(args):
    given = physical_from_args(args)
    if given is None:
        raise ValueError("--physical PRESET|FILE.toml is needed: the design is in physical "
                         "parameters (e.g. --physical soft_palate)")
    if (args.target_flow is None) != (args.vary is None):
        raise ValueError("--target-flow and --vary go together (e.g. --target-flow 30L/min "
                         "--vary stiffness)")
    if args.target_flow is None:
        return given[0], None
    target = parse_flow(args.target_flow, "--target-flow")
    if target.value < 0 and args.direction is not None:
        raise ValueError(f"--target-flow {args.target_flow} is negative and a direction is "
                         "given: give the flow's magnitude with --direction, or a signed "
                         "flow alone (negative: expiration)")
    if target.value < 0:
        args.direction = "reverse"                 # the signed target says the direction
    elif args.direction == "reverse":
        target = Flow(f"-{target.text}", target.kind, -target.value)
    parse_vary(args.vary, given[0])                    # names the allowed parameters
    try:
        given[0].scene(target)
    except ValueError as err:
        raise ValueError(f"--target-flow {args.target_flow}: {err}") from None
    return given[0], target


def _cmd_design(args) -> dict:
    physical, target = _check(args)
    overrides = scene_values(args)
    sens = palate_sensitivity(physical, ustar_max=args.ustar_max, **overrides)
    record(args, sens.scene, ustar_max=args.ustar_max, design_step=0.1,
           design_max_factor=DESIGN_MAX_FACTOR)
    out = {"source": physical.source, "description": physical.description, **sens.to_json(),
           "design": None}
    if target is not None:
        out["design"] = design_for_flow(physical, target, args.vary, ustar_max=args.ustar_max,
                                        base=sens, **overrides).to_json()
    meta = cli_meta(args)
    return {**out, "meta": {**meta, "units": {**DESIGN_UNITS, **meta["units"]}}}


def _print_design(result: dict) -> None:
    """The onset, the elasticities (largest first) and the design, in sentences."""
    print(f"{result['source']}: {result['description']}" if result["description"]
          else result["source"])
    print(f"  {result['kind']} onset at {result['onset_flow_l_min']:.4g} L/min, "
          f"{result['frequency_hz']:.4g} Hz (mode {result['dominant_mode']})")
    print("  a 1 % change of      moves the onset airflow by   and its frequency by")
    rows = sorted(result["sensitivities"].items(), key=lambda kv: -abs(kv[1]["flow_elasticity"]))
    for name, s in rows:
        per = "" if s["value"] else f"   (per unit: {s['flow_per_unit']:+.4g} / unit of {name})"
        w = s["frequency_elasticity"]
        print(f"    {name:<8} {s['meaning']:<28} {s['flow_elasticity']:+8.3f} %"
              + (f"{w:+14.3f} %" if w is not None else f"{'-':>14}  ") + per)
    _print_plan(result["design"])
    for note in dict.fromkeys(result.get("warnings", [])):
        print(f"warning: {note}")


def _print_plan(d: dict | None) -> None:
    """The design, its onset afterwards and its check by eigenvalues."""
    if d is None:
        return
    if d["note"]:
        print(f"  {d['note']}")
        return
    print(f"  to lift the onset to {d['target_flow_l_min']:.4g} L/min:")
    for c in d["changes"]:
        change = "" if c["relative_change"] is None else f" ({100 * c['relative_change']:+.3g} %)"
        print(f"    {c['parameter']} from {c['before']:.4g} to {c['after']:.4g} {c['unit']}{change}")
    print(f"  then the onset is at {d['onset_flow_after_l_min']:.4g} L/min and "
          f"{d['frequency_after_hz']:.4g} Hz; checked: "
          f"{'stable' if d['verified']['stable_below'] else 'NOT stable'} at 99.5 % and "
          f"{'unstable' if d['verified']['unstable_above'] else 'NOT unstable'} at 100.5 % of it")
