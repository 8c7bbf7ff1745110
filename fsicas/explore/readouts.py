"""The explorer's readouts as HTML: the instant view's and the onset's, each number in an
element with its stable ``data-testid``."""
from __future__ import annotations

import math

from .widgets import readout

__all__ = ["instant_html", "onset_html"]


def _fmt(value, digits: int = 4, unit: str = "") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"
    return f"{value:.{digits}g}{unit}"


def instant_html(view: dict) -> str:
    """The instant view's readouts: stability, growth rate, frequency (and Hz), ω/ω₁,
    pressure drop, static deflection (and the airflow in L/min), the warnings."""
    hz = "" if view["hz"] is None else f" ({_fmt(view['hz'], 4, ' Hz')})"
    flow = ("" if view["l_per_min"] is None else
            "<br>" + readout("flow", _fmt(view["l_per_min"], 4, " L/min"), "airflow"))
    lines = [readout("stability", "stable" if view["stable"] else "unstable", "steady state"),
             readout("growth-rate", _fmt(view["growth_rate"], 6), "growth rate σ"),
             readout("frequency", _fmt(view["omega"], 6), "frequency ω") + hz,
             readout("freq-ratio", _fmt(view["freq_ratio"]), "ω/ω₁"),
             readout("pressure-drop", _fmt(view["pressure_drop"]), "pressure drop Δp"),
             readout("tip", _fmt(view["tip"]), "static tip deflection"
                     if view["x_ref"] == 1.0 else f"static deflection at x = {view['x_ref']:.3g} L")
             + flow]
    lines += [readout("warning", w) for w in view["warnings"]]
    return "<br>".join(lines)


def onset_html(status: str, value) -> str:
    """The onset's readouts: kind, U*_c, ω_c, for flutter l1 and the criticality, the
    physical units where known; or its status (computing, failed)."""
    if status == "running":
        return readout("onset-kind", "computing…", "onset")
    if status == "error":
        return readout("onset-kind", "failed", "onset") + f": {value}"
    if value["kind"] == "none":
        return readout("onset-kind", "none", "onset") + " (stable up to U* = 40)"
    units = [_fmt(value.get(k), 4, u) for k, u in (("l_per_min", " L/min"), ("hz", " Hz"),
                                                   ("pa", " Pa")) if k in value]
    lines = [readout("onset-kind", value["kind"], "onset"),
             readout("onset-ustar", _fmt(value["ustar_crit"], 6), "U*_c"),
             readout("onset-omega", _fmt(value.get("omega"), 5), "ω_c")]
    if value["kind"] == "flutter":
        lines += [readout("onset-l1", _fmt(value["l1"], 4), "l1"),
                  readout("onset-criticality", value["criticality"], "criticality")]
    if units:
        lines.append("physical: " + ", ".join(units))
    return "<br>".join(lines)
