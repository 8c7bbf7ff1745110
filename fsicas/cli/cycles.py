"""CLI command ``fsicas lco`` (alias ``cycles``): the flutter limit-cycle branch versus U*
(docs/cycles.md); ``lco`` is the name the command-line contract (shared DESIGN.md) fixes.

Registered by :func:`add_cycle_commands` from ``fsicas.cli._parser``, like the time
integration commands of ``fsicas.cli_time``.
"""
from __future__ import annotations

__all__ = ["add_cycle_commands"]

_POINT_KEYS = ("kind", "ustar", "period", "frequency", "tip_amplitude", "gap_ratio", "stable")


def add_cycle_commands(sub, add_scene_options) -> None:
    """Add the ``lco`` subcommand (alias ``cycles``)."""
    p = sub.add_parser("lco", aliases=["cycles"], help="limit cycles vs U* by collocation continuation from the "
                                      "first Hopf point, up to the first contact")
    add_scene_options(p)
    p.add_argument("--ustar-max", type=float, default=20.0, help="stop beyond this U*")
    p.add_argument("--ntst", type=int, default=20, help="collocation mesh intervals")
    p.add_argument("--ncol", type=int, default=4, help="collocation points per interval")
    p.add_argument("--max-points", type=int, default=300, help="branch points at most")
    p.add_argument("--out", metavar="FILE.json", help="save the full branch (multipliers, states)")
    p.add_argument("--plot", metavar="FILE", help="tip amplitude and period against U*")
    p.set_defaults(run=_cmd_cycles)


def _cmd_cycles(args) -> dict:
    from ..cli import scene_from_args
    from ..cycles.collocation import CycleSettings, cycle_branch
    scene = scene_from_args(args)
    if scene.contact:
        raise ValueError("cycles are continued on the contact-free model: drop --contact")
    settings = CycleSettings(ntst=args.ntst, ncol=args.ncol, max_points=args.max_points)
    branch = cycle_branch(scene, ustar_max=args.ustar_max, settings=settings)
    if args.out:
        branch.save(args.out)
    if args.plot:
        plot_branch(branch, args.plot)
    summary = lambda p: {k: getattr(p, k) for k in _POINT_KEYS}
    return {"hopf": branch.hopf, "status": branch.status, "message": branch.message,
            "eps": branch.eps, "folds": [summary(p) for p in branch.folds],
            "contact": None if branch.contact is None else summary(branch.contact),
            "points": [summary(p) for p in branch.points], "wall_time": branch.wall_time}


def plot_branch(branch, path) -> None:
    """Tip half-amplitude and period against U*: stable solid, unstable dashed; folds
    (triangles) and the first contact (star)."""
    import numpy as np
    from ..plots.linear import _pyplot
    plt = _pyplot()
    u, stable = branch.column("ustar"), branch.column("stable")
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for ax, name, label in zip(axes, ("tip_amplitude", "period"), ("tip half-amplitude / L", "period / T")):
        y = branch.column(name)
        for flag, style in ((True, "-"), (False, "--")):
            ax.plot(u, np.where(stable == flag, y, np.nan), "k" + style, lw=1.2)
        for p in branch.folds:
            ax.plot(p.ustar, getattr(p, name), "v", color="tab:blue")
        if branch.contact is not None:
            ax.plot(branch.contact.ustar, getattr(branch.contact, name), "*", ms=10, color="tab:red")
        ax.axvline(branch.hopf["ustar_crit"], color="0.6", lw=0.8)
        ax.set(xlabel="U*", ylabel=label)
    s = branch.scene
    fig.suptitle(f"M* = {s.mstar:g}, N = {s.modes}, zeta = {s.zeta}: {branch.status}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
