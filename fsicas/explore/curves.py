"""The background tier's grazing and fold-of-cycles curves: started on request in its own
process (``curves_view``: over the map's M* window, as ``fsicas grazing``), with its
elapsed time and a cancel button; drawn on the boundary map, with the command that
reproduces them. Cached by scene (they depend on neither U* nor M* within the window)."""
from __future__ import annotations

import panel as pn

from .background import BackgroundPanel
from .compute import boundary_range, curves_view
from .figures import BoundaryMap
from .jobs import Jobs
from .widgets import NumberBox, held, readout

__all__ = ["CurvePanel"]


class CurvePanel(BackgroundPanel):
    """The grazing and fold curves' controls and results for one page."""

    kind, testid, label, busy = "curves", "curves-status", "grazing and fold curves", "computing"

    def __init__(self, jobs: Jobs, boundary: BoundaryMap):
        super().__init__(jobs, "not computed (minutes, in the background)")
        self.map, self.command, self.key = boundary, "", None
        self.start = pn.widgets.Button(name="grazing and fold curves", button_type="primary",
                                       width=190)
        self.stop = pn.widgets.Button(name="cancel curves", width=120)
        self.stop.on_click(lambda _: self.jobs.cancel("curves") and self.show("cancelled", None))
        self.max_points = NumberBox(value="40", label="curve points, at most",
                                    testid="curve-points")

    @held
    def ask(self, scene, key: str, command) -> None:
        """Start (or show the cached) curves of ``scene``; ``command`` gives the scene's
        command lines (:func:`command_line` of the scene)."""
        points = self._count(self.max_points, "curve points")
        if points is None:
            return
        self.command = command("grazing", mstar=boundary_range(scene.mstar), max_points=points)
        self.key = ("curves", f"{key}|{points}")
        cached = self.jobs.start(self.key, curves_view, scene, points)
        self.show("done", cached) if cached is not None else self.show("running", 0.0)

    def _done(self, curves: dict) -> None:
        self.map.curves(curves["grazing"], curves["fold"])
        lines = [readout("curves-status", "done", self.label),
                 readout("curves-grazing", str(len(curves["grazing"])), "grazing curves")
                 + ", " + readout("curves-fold", str(len(curves["fold"])), "fold curves")
                 + f" (seeds M* = {', '.join(f'{m:.3g}' for m in curves['seeds'])})"]
        lines += [readout("warning", w) for w in curves["warnings"]]
        lines += [readout("warning", f"no curve from a seed: {f}") for f in curves["failures"]]
        lines.append(readout("curves-command", self.command))
        self.status.text = "<br>".join(lines)

    def page(self) -> pn.viewable.Viewable:
        return pn.Column(pn.Row(self.start, self.stop), self.max_points, self.status)
