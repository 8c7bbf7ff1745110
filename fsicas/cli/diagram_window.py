"""``fsicas diagram --mstar LO:HI:COUNT``: the codimension-two points over a window of M*
and the curves switched onto from them (:mod:`fsicas.cycles.window`)."""
from __future__ import annotations

from ..cycles.window import window_diagram
from ..model.assembly import build_model
from ..plots.diagram import plot_window_diagram
from .meta import record, write_json
from .progress import reporter

__all__ = ["window_command"]


def window_command(args, scene, mstars, settings) -> dict:
    """Run the window's analysis; its summary (``--out``: the curves' points too)."""
    if mstars.size < 2:
        raise ValueError(f"--mstar must give a window of at least two values, got "
                         f"{args.mstar_values!r}")
    record(args, scene, diagram_settings=settings)
    say = reporter(args)
    say.stage(f"codimension-two points over M* in [{mstars.min():g}, {mstars.max():g}] "
              f"({mstars.size} onsets, N = {scene.modes})", always=True)
    result = window_diagram(scene, build_model(scene), mstars, ustar_max=args.ustar_max,
                            cycles=settings.cycles, curve_points=args.max_points,
                            progress=lambda text: say.stage(text))
    say.stats(f"{len(result.points)} codimension-two points, {len(result.curves)} curves "
              f"in {result.wall_time:.1f} s")
    if args.out:
        write_json(args.out, result.to_json(points=True), args)
    if args.plot:
        plot_window_diagram(result, args.plot)
    return result.to_json(points=False)
