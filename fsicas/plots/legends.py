"""Legends that hide no data.

Matplotlib's ``loc="best"`` only minimizes the overlap: where the curves fill a panel it
still sets the legend on them. :func:`settle_legends` (run by
:func:`fsicas.plots.backend.finish` on every figure before it is written) moves each
axes' legend to the first corner of :data:`CORNERS` whose box crosses none of the
panel's drawn data (lines, markers, filled areas, in display coordinates after the
layout), and beside the panel (right of it, top aligned) where every corner is covered.
"""
from __future__ import annotations

import numpy as np

__all__ = ["CORNERS", "settle_legends", "covered"]

#: The places tried inside a panel, in order of preference.
CORNERS = ("upper right", "upper left", "lower left", "lower right", "center right",
           "center left", "upper center", "lower center")
#: Clearance kept between a legend's box and the data (points).
CLEARANCE = 2.0


def settle_legends(fig, passes: int = 3) -> None:
    """Every axes legend of ``fig`` off its panel's data (module docstring). A legend
    moved beside its panel changes the layout, so the placement is checked again on the
    new layout (at most ``passes`` times)."""
    if not any(ax.get_legend() is not None for ax in fig.axes):
        return
    for _ in range(passes):
        fig.draw_without_rendering()            # the layout as it will be written
        moved = [_place(ax.get_legend(), ax) for ax in fig.axes
                 if ax.get_legend() is not None and covered(ax.get_legend(), ax)]
        if not moved:
            return


def _place(legend, ax) -> bool:
    """Move ``legend`` to the first free corner of ``ax``, else beside it."""
    for corner in CORNERS:
        legend.set_bbox_to_anchor(None)
        legend.set_loc(corner)
        if not covered(legend, ax):
            return True
    legend.set_loc("upper left")
    legend.set_bbox_to_anchor((1.02, 1.0), transform=ax.transAxes)
    return True


def covered(legend, ax) -> bool:
    """Whether the box of ``legend`` (grown by :data:`CLEARANCE`) crosses the data drawn on
    ``ax`` inside the panel (its lines and markers, scatter markers and filled areas), in
    display coordinates."""
    from matplotlib.transforms import Bbox
    box = Bbox.intersection(legend.get_window_extent().padded(_points(ax, CLEARANCE)),
                            ax.get_window_extent())
    if box is None:
        return False
    return any(_crosses(artist, box, ax) for artist in [*ax.lines, *ax.collections]
               if artist.get_visible())


def _points(ax, size: float) -> float:
    """``size`` points in pixels of ``ax``'s figure."""
    return size * ax.figure.dpi / 72.0


def _crosses(artist, box, ax) -> bool:
    """Whether the line or collection ``artist`` draws inside ``box`` (display)."""
    from matplotlib.collections import PathCollection, PolyCollection
    if isinstance(artist, PathCollection):             # scatter: its markers
        centres = artist.get_offset_transform().transform(artist.get_offsets())
        size = _points(ax, float(np.sqrt(np.max(artist.get_sizes(), initial=0.0))) / 2)
        return _inside(centres, box.padded(size))
    if isinstance(artist, PolyCollection):              # filled areas
        return any(artist.get_transform().transform_path(p).intersects_bbox(box, filled=True)
                   for p in artist.get_paths())
    if not hasattr(artist, "get_xydata"):
        return False
    xy = artist.get_transform().transform(np.asarray(artist.get_xydata(), dtype=float))
    if artist.get_linestyle() not in ("None", "", " ", "none") and _segments_cross(xy, box):
        return True
    if artist.get_marker() in (None, "None", "", " ", "none"):
        return False
    return _inside(xy, box.padded(_points(ax, artist.get_markersize()) / 2))


def _inside(points: np.ndarray, box) -> bool:
    finite = points[np.all(np.isfinite(points), axis=1)]
    return bool(len(finite)) and bool(box.count_contains(finite))


def _segments_cross(xy: np.ndarray, box) -> bool:
    """Whether the polyline ``xy`` (display; non-finite points break it) enters ``box``."""
    from matplotlib.path import Path
    finite = np.all(np.isfinite(xy), axis=1)
    breaks = np.flatnonzero(np.diff(finite.astype(int)) != 0) + 1
    for run in np.split(np.arange(len(xy)), breaks):
        if finite[run[0]] and (_inside(xy[run], box) or (
                len(run) > 1 and Path(xy[run]).intersects_bbox(box, filled=False))):
            return True
    return False
