"""The explorer's Bokeh figures and the data sources they draw from: the root locus
(eigenvalues, unstable ones marked), the mode shape in the channel and the boundary map
with a crosshair at the current point."""
from __future__ import annotations

import numpy as np
from bokeh.models import (ColumnDataSource, CustomAction, CustomJS, DataRange1d, Range1d,
                          SaveTool, Span)
from bokeh.plotting import figure as bokeh_figure

__all__ = ["figure", "RootLocus", "ModeShape", "BoundaryMap", "STABLE_COLOR", "UNSTABLE_COLOR",
           "SVG_TOOL"]

STABLE_COLOR, UNSTABLE_COLOR, FOLD_COLOR = "#1f77b4", "#d62728", "#ff7f0e"
_SIZE = dict(height=300, sizing_mode="stretch_width", toolbar_location="right")
#: The description (tooltip) of the toolbar's SVG button.
SVG_TOOL = "save as SVG"
#: The figure drawn again by Bokeh's own SVG backend (``export("svg")`` of the figure's
#: view, as its PNG save tool does on the canvas) and downloaded as ``name``.svg.
_SAVE_SVG = """Promise.resolve(Bokeh.index.find_one(plot).export("svg").to_blob()).then((blob) => {
  const link = document.createElement("a");
  link.href = URL.createObjectURL(blob);
  link.download = name;
  link.dispatchEvent(new MouseEvent("click")); });"""
_SVG_ICON = ("data:image/svg+xml;utf8,<svg xmlns='http://www.w3.org/2000/svg' width='20' "
             "height='20'><text x='0' y='14' font-size='9' font-family='sans-serif' "
             "font-weight='bold'>SVG</text></svg>")


def figure(name: str, **kwargs):
    """A Bokeh figure whose toolbar saves it as PNG (Bokeh's save tool) and as SVG
    (:data:`SVG_TOOL`), both as ``name`` (Bokeh's default tools but its help, and no
    logo, so that every button fits beside a figure 260 px high)."""
    f = bokeh_figure(tools="pan,box_zoom,wheel_zoom,save,reset", **kwargs)
    f.add_tools(CustomAction(description=SVG_TOOL, icon=_SVG_ICON,
                             callback=CustomJS(args={"plot": f, "name": f"{name}.svg"},
                                               code=_SAVE_SVG)))
    f.select_one({"type": SaveTool}).filename = name
    f.toolbar.logo = None
    return f


def _fit(axis: Range1d, values: np.ndarray) -> None:
    """Fit ``axis`` to ``values`` (5 % margins) where they leave it or fill less than
    half of it: a small move of the eigenvalues moves no axis (nothing more to send)."""
    low, high = float(values.min()), float(values.max())
    pad = 0.05 * (high - low) or 1.0
    if not axis.start <= low <= high <= axis.end or high - low < 0.5 * (axis.end - axis.start):
        axis.update(start=low - pad, end=high + pad)


class RootLocus:
    """Eigenvalues lambda = sigma + i omega in the complex plane; Re > 0 in red. Its
    ranges are set here, not by the browser (whose own fitting would send them back to
    the server after each change)."""

    def __init__(self):
        self.source = ColumnDataSource({"re": [], "im": [], "color": []})
        self.figure = figure("eigenvalues", title="eigenvalues λ = σ + iω", x_axis_label="growth rate σ",
                             y_axis_label="ω", x_range=Range1d(-1.0, 1.0),
                             y_range=Range1d(-1.0, 1.0), **_SIZE)
        self.figure.scatter("re", "im", color="color", size=7, source=self.source)
        self.figure.add_layout(Span(location=0.0, dimension="height", line_dash="dashed",
                                    line_color="gray"))

    def update(self, eigenvalues: np.ndarray) -> None:
        lam = np.asarray(eigenvalues)
        colors = np.where(lam.real > 0, UNSTABLE_COLOR, STABLE_COLOR)
        self.source.data = {"re": lam.real, "im": lam.imag, "color": colors}
        _fit(self.figure.x_range, np.append(lam.real, 0.0))
        _fit(self.figure.y_range, lam.imag)


class ModeShape:
    """The least stable complex mode y(x) (max |y| = 1) in the channel: the beam at
    phase phi, Re(y e^{i phi}), its envelope ±|y|, the walls at ±H*/2; the amplitude
    drawn is 0.8 H*/2 (a shape, not a size)."""

    def __init__(self):
        self.source = ColumnDataSource({"x": [], "beam": [], "upper": [], "lower": []})
        self.walls = ColumnDataSource({"x": [0.0, 1.0], "top": [0.05, 0.05],
                                       "bottom": [-0.05, -0.05]})
        f = figure("mode_shape", title="least stable mode in the channel", x_axis_label="x / L",
                   y_axis_label="y / L", x_range=Range1d(-0.02, 1.02),
                   y_range=Range1d(-0.06, 0.06), **_SIZE)
        f.line("x", "top", source=self.walls, color="black", line_width=2)
        f.line("x", "bottom", source=self.walls, color="black", line_width=2)
        f.varea("x", "lower", "upper", source=self.source, fill_alpha=0.15)
        f.line("x", "beam", source=self.source, line_width=3, color="#2ca02c")
        self.figure, self.shape, self.half = f, None, 0.05

    def update(self, x, y, hstar: float) -> None:
        """The mode ``y(x)``; the walls and the ranges only where H* changed."""
        if hstar / 2 != self.half:
            self.half = hstar / 2
            self.walls.data = {"x": [0.0, 1.0], "top": [self.half] * 2,
                               "bottom": [-self.half] * 2}
            self.figure.y_range.update(start=-1.2 * self.half, end=1.2 * self.half)
        self.shape = (np.asarray(x), 0.8 * self.half * np.asarray(y))
        env = np.abs(self.shape[1])
        self.source.data = {"x": self.shape[0], "beam": self.shape[1].real, "upper": env,
                            "lower": -env}

    def animate(self, phase: float) -> None:
        """The beam at ``phase`` (radians) of the oscillation."""
        if self.shape is not None:
            beam = (self.shape[1] * np.exp(1j * phase)).real
            self.source.patch({"beam": [(slice(0, beam.size), beam)]})


class BoundaryMap:
    """U*_c(M*) (log M*), flutter and divergence points, a crosshair at (M*, U*); the
    grazing (black) and fold-of-cycles (dashed) curves where computed. Its U* axis is
    fitted by the browser to what it draws (a ``DataRange1d`` of the boundary, the curves
    and the current point): it grows and shrinks with each new boundary."""

    def __init__(self):
        self.source = ColumnDataSource({"mstar": [], "ustar": [], "color": []})
        self.point = ColumnDataSource({"mstar": [1.0], "ustar": [5.0]})
        f = figure("boundary", title="stability boundary U*_c(M*) (click to move the point)",
                   x_axis_type="log", x_axis_label="M*", y_axis_label="U*",
                   x_range=Range1d(0.1, 10.0), y_range=DataRange1d(range_padding=0.15),
                   **_SIZE)
        drawn = [f.line("mstar", "ustar", source=self.source, color="gray"),
                 f.scatter("mstar", "ustar", source=self.source, color="color", size=6),
                 f.scatter("mstar", "ustar", source=self.point, color=UNSTABLE_COLOR, size=8,
                           marker="circle_cross", fill_alpha=0.0)]
        self.vertical = Span(location=1.0, dimension="height", line_color=UNSTABLE_COLOR)
        self.horizontal = Span(location=5.0, dimension="width", line_color=UNSTABLE_COLOR)
        f.add_layout(self.vertical)
        f.add_layout(self.horizontal)
        self.grazing = ColumnDataSource({"xs": [], "ys": []})
        self.fold = ColumnDataSource({"xs": [], "ys": []})
        drawn.append(f.multi_line("xs", "ys", source=self.grazing, color="black", line_width=2,
                                  legend_label="grazing"))
        drawn.append(f.multi_line("xs", "ys", source=self.fold, color=FOLD_COLOR, line_width=2,
                                  line_dash="dashed", legend_label="fold of cycles"))
        f.y_range.renderers = drawn
        f.legend.location, f.legend.visible = "top_left", False
        self.figure = f

    def curves(self, grazing: list[dict], fold: list[dict]) -> None:
        """The grazing and fold-of-cycles curves, each ``{"mstar": [...], "ustar": [...]}``."""
        for source, curves in ((self.grazing, grazing), (self.fold, fold)):
            source.data = {"xs": [c["mstar"] for c in curves], "ys": [c["ustar"] for c in curves]}
        self.figure.legend.visible = bool(grazing or fold)

    def update(self, points: list[dict]) -> None:
        """The boundary's ``points`` (none: the map cleared, its curves too)."""
        points = [p for p in points if p.get("ustar_crit") is not None]
        if not points and not self.source.data["mstar"]:
            return                                     # nothing drawn, nothing to send
        kinds = [p["kind"] for p in points]
        self.source.data = {"mstar": [p["mstar"] for p in points],
                            "ustar": [p["ustar_crit"] for p in points],
                            "color": [UNSTABLE_COLOR if k == "flutter" else "#9467bd"
                                      for k in kinds]}
        if points:
            m = [p["mstar"] for p in points]
            self.figure.x_range.update(start=min(m), end=max(m))
        else:
            self.curves([], [])

    def crosshair(self, mstar: float, ustar: float) -> None:
        self.vertical.location, self.horizontal.location = mstar, ustar
        self.point.data = {"mstar": [mstar], "ustar": [ustar]}
        x = self.figure.x_range
        if not x.start <= mstar <= x.end:
            x.update(start=mstar / 10, end=mstar * 10)
