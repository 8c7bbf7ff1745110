"""The background tier's limit-cycle branch: started on request in its own process
(``cycles_view``: from the first Hopf point to the first wall contact, as ``fsicas
lco``), with its elapsed time and a cancel button; the tip amplitude against U*, stable
and unstable cycles apart, and the command that reproduces it. Cached by scene (the
branch does not depend on U*)."""
from __future__ import annotations

import panel as pn
from bokeh.models import ColumnDataSource, Span

from .compute import cycles_view
from .figures import STABLE_COLOR, UNSTABLE_COLOR, figure
from .background import BackgroundPanel
from .jobs import Jobs
from .widgets import NumberBox, held, readout

__all__ = ["CyclePanel"]


def _fmt(value) -> str:
    return "—" if value is None else f"{value:.5g}"


class CyclePanel(BackgroundPanel):
    """The limit-cycle branch's controls and results for one page."""

    kind, testid, label, busy = "lco", "lco-status", "limit cycles", "computing"

    def __init__(self, jobs: Jobs):
        super().__init__(jobs, "not computed (seconds to a minute at N = 10, in the "
                         "background)")
        self.command, self.key = "", None
        self.start = pn.widgets.Button(name="limit cycles", button_type="primary", width=120)
        self.stop = pn.widgets.Button(name="cancel cycles", width=120)
        self.stop.on_click(lambda _: self.jobs.cancel("lco") and self.show("cancelled", None))
        self.through = pn.widgets.Checkbox(name="on through contact (minutes)", value=False)
        self.impact_points = NumberBox(value="20", label="impacting cycles, at most",
                                       testid="impact-points")
        self.source = ColumnDataSource({"ustar": [], "amplitude": [], "color": []})
        self.impacting = ColumnDataSource({"ustar": [], "amplitude": [], "color": []})
        f = figure("limit_cycles", title="limit cycles: tip amplitude (blue stable, red "
                   "unstable; squares: through contact)", x_axis_label="U*",
                   y_axis_label="tip amplitude / L", height=260, sizing_mode="stretch_width")
        f.line("ustar", "amplitude", source=self.source, color="gray")
        f.scatter("ustar", "amplitude", source=self.source, color="color", size=5)
        f.line("ustar", "amplitude", source=self.impacting, color="gray", line_dash="dotted")
        f.scatter("ustar", "amplitude", source=self.impacting, color="color", size=6,
                  marker="square")
        self.here = Span(location=0.0, dimension="height", line_color="gray", line_dash="dashed")
        f.add_layout(self.here)
        self.figure = f

    @held
    def ask(self, scene, key: str, command) -> None:
        """Start (or show the cached) branch of ``scene`` (on through contact where asked);
        ``command`` gives the scene's command lines (:func:`command_line` of the scene)."""
        points = None
        if self.through.value:
            points = self._count(self.impact_points, "impacting cycles")
            if points is None:
                return
        extra = {} if points is None else {"through_contact": True, "impact_points": points}
        self.command, self.key = command("lco", **extra), ("lco", f"{key}|{points}")
        cached = self.jobs.start(self.key, cycles_view, scene, points)
        self.show("done", cached) if cached is not None else self.show("running", 0.0)

    def _done(self, branch: dict) -> None:
        points = branch["points"]
        contact = branch["contact"]
        lines = [readout("lco-status", branch["status"], "limit cycles")
                 + f" ({branch['message']})",
                 readout("lco-points", str(len(points)), "cycles"),
                 readout("lco-contact", _fmt(None if contact is None else contact["ustar"]),
                         "first wall contact at U*")]
        impacting = branch["impacting"] or {"points": []}
        if branch["impacting"] is not None:
            special = ", ".join(f"{s['kind']} at U* = {s['ustar']:.5g}"
                                for s in impacting["special"]) or "none"
            lines += [readout("impact-status", impacting["status"], "through contact")
                      + f" ({impacting['message']})",
                      readout("impact-count", str(len(impacting["points"])), "impacting cycles")
                      + ", " + readout("impact-special", special, "special cycles")]
        lines += [readout("warning", w) for w in branch["warnings"]]
        lines.append(readout("lco-command", self.command))
        self.source.data = _columns(points)
        self.impacting.data = _columns(impacting["points"])
        self.status.text = "<br>".join(lines)

    def page(self) -> pn.viewable.Viewable:
        return pn.Column("### Limit cycles", pn.Row(self.start, self.stop), self.through,
                         self.impact_points, self.status, pn.pane.Bokeh(self.figure))


def _columns(points: list) -> dict:
    """The figure's columns of ``points``: U*, tip amplitude, colour by stability."""
    return {"ustar": [p["ustar"] for p in points],
            "amplitude": [p["tip_amplitude"] for p in points],
            "color": [STABLE_COLOR if p["stable"] else UNSTABLE_COLOR for p in points]}
