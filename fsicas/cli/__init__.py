"""Command line: ``fsicas <command> [scene options] [--scene FILE.toml] [--json]``.

With ``--json`` stdout holds one JSON object and nothing else (a stable contract).
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from ..model.beam import clamped_free_betas
from ..model.assembly import build_model
from ..scene import Scene, load_scene
from ..linear.hopf import CriticalVelocityError
from ..linear.steady import SteadyStateError, steady_state

__all__ = ["main"]

# CLI option -> Scene field
_SCENE_OPTIONS = {
    "mstar": float, "ustar": float, "hstar": float, "friction": float, "k0": float,
    "kl": float, "zeta": float, "modes": int, "quad_nodes": int,
    "contact_stiffness": float, "contact_eps": float,
}


def _add_scene_options(parser: argparse.ArgumentParser, mstar: bool = True) -> None:
    group = parser.add_argument_group("scene (nondimensional; see docs/model.md)")
    group.add_argument("--scene", metavar="FILE.toml", help="read the scene from a TOML file")
    for name, kind in _SCENE_OPTIONS.items():
        if name != "mstar" or mstar:
            group.add_argument("--" + name.replace("_", "-"), dest=name, type=kind, default=None)
    group.add_argument("--contact", dest="contact", action=argparse.BooleanOptionalAction, default=None)
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def scene_from_args(args: argparse.Namespace) -> Scene:
    """Scene from --scene FILE and/or the options (options override the file)."""
    values = {k: getattr(args, k, None) for k in (*_SCENE_OPTIONS, "contact")}
    values = {k: v for k, v in values.items() if v is not None}
    if args.scene:
        return load_scene(args.scene, **values)
    return Scene(**values)


def _cmd_modes(args) -> dict:
    if args.modes is None or args.modes < 1:
        raise ValueError(f"--modes must be an integer >= 1, got {args.modes}")
    beta = clamped_free_betas(args.modes)
    return {"beta": beta.tolist(), "omega": (beta**2).tolist()}


def _cmd_steady(args) -> dict:
    scene = scene_from_args(args)
    model = build_model(scene)
    return steady_state(scene, model).to_json(model)


def _cmd_eig(args) -> dict:
    from ..linear.stability import linear_stability
    scene = scene_from_args(args)
    model = build_model(scene)
    result = linear_stability(scene, model)
    if args.plot:
        from ..plots.linear import _pyplot
        plt = _pyplot()
        fig, ax = plt.subplots(figsize=(5, 4))
        ax.plot(result.growth_rate, result.omega, "o", ms=4)
        ax.axvline(0, color="k", lw=0.8)
        ax.set(xlabel="growth rate (1/T)", ylabel="omega (1/T)",
               title=f"M*={scene.mstar:g}, U*={scene.ustar:g}, N={scene.modes}")
        fig.savefig(args.plot, dpi=120)
    return result.to_json()


def _cmd_boundary(args) -> dict:
    from ..linear.boundary import parse_mstar, stability_boundary
    mstars = parse_mstar(args.mstar_values)
    scene = scene_from_args(args)
    model = build_model(scene)
    boundary = stability_boundary(scene, mstars, model, ustar_max=args.ustar_max,
                                  refine=not args.no_refine)
    if args.plot:
        from ..plots.linear import plot_boundary, plot_mode_shapes
        plot_boundary(boundary, args.plot)
        stem = args.plot.rsplit(".", 1)
        plot_mode_shapes(boundary, model, f"{stem[0]}_modes.{stem[1] if len(stem) > 1 else 'png'}")
    out = boundary.to_json()
    out.pop("curves")
    return out


def _cmd_paper(args) -> dict:
    """The main job: the paper's core numbers on its embedded default configuration."""
    from ..paper import run_paper, summary
    report = run_paper(out=args.out, quick=args.quick)
    return report if args.json else {**summary(report), "written to": args.out}


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="fsicas", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("modes", help="in-vacuo clamped-free beam modes")
    p.add_argument("--modes", type=int, default=10)
    p.add_argument("--json", action="store_true")
    p.set_defaults(run=_cmd_modes)
    p = sub.add_parser("steady", help="steady state: pressure drop, flow split, static deflection")
    _add_scene_options(p)
    p.set_defaults(run=_cmd_steady)
    p = sub.add_parser("eig", help="eigenvalues of the linearization at the steady state")
    _add_scene_options(p)
    p.add_argument("--plot", metavar="FILE", help="write the eigenvalue map to FILE")
    p.set_defaults(run=_cmd_eig)
    p = sub.add_parser("boundary", help="flutter boundary U*_c(M*) from Hopf-curve continuation")
    _add_scene_options(p, mstar=False)
    p.add_argument("--mstar", dest="mstar_values", required=True, metavar="LIST_OR_RANGE",
                   help="0.1,1,10 or lo:hi:count (log-spaced)")
    p.add_argument("--ustar-max", type=float, default=40.0, help="search Hopf points below this U*")
    p.add_argument("--no-refine", action="store_true",
                   help="interpolate along the Hopf curves instead of locating each point")
    p.add_argument("--plot", metavar="FILE", help="write Fig. 2 to FILE and Fig. 3 to FILE_modes")
    p.set_defaults(run=_cmd_boundary)
    p = sub.add_parser("paper", help="reproduce the paper's core results on the embedded default")
    p.add_argument("--out", default="results", help="folder for the report and figures")
    p.add_argument("--quick", action="store_true", help="coarser grids (for a smoke test)")
    p.add_argument("--json", action="store_true")
    p.set_defaults(run=_cmd_paper)
    from .timedomain import add_time_commands   # simulate, map (docs/simulate.md)
    add_time_commands(sub, _add_scene_options)
    from .cycles import add_cycle_commands   # cycles (docs/cycles.md)
    add_cycle_commands(sub, _add_scene_options)
    return parser


def _print_human(result: dict) -> None:
    for key, value in result.items():
        if isinstance(value, list) and value and isinstance(value[0], float):
            value = np.array2string(np.array(value), precision=6, max_line_width=100)
        print(f"{key:>16}: {value}")


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    start = time.perf_counter()
    try:
        result = args.run(args)
    except (ValueError, SteadyStateError, CriticalVelocityError) as err:
        if getattr(args, "json", False):
            print(json.dumps({"error": str(err)}))
        else:
            print(f"fsicas {args.command}: error: {err}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(result))
    else:
        _print_human(result)
        print(f"{'wall time':>16}: {time.perf_counter() - start:.3f} s")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
