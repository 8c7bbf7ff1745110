"""The background tier's time run: started on request in its own process (``run_view``),
with its elapsed time and a cancel button; the tip's history, the outcome and, for a
physical scene settled on a cycle, the snore as an ``<audio>`` element with its level
and pitch. Cached by scene and t_end."""
from __future__ import annotations

import numpy as np
import panel as pn
from bokeh.models import ColumnDataSource

from ..timedomain.sound import AUDIO_RATE
from .compute import SOUND_DISTANCE, SOUND_DURATION, SPECTRUM_MAX_HZ, run_view
from .figures import figure
from .reproduce import sound_lines
from .jobs import Jobs
from .widgets import NumberBox, held, markup, readout

__all__ = ["BackgroundPanel", "RunPanel"]


#: Why a physical run has no snore on the page: only a settled cycle is looped, and the
#: impacting motion past the wall is neither settled nor quick (docs/sound.md).
NO_SOUND = "none: the run's outcome is {outcome}, not a settled cycle to loop"
NO_SOUND_WALL = (". Past the wall the palate needs the wall's contact law, and there the "
                 "soft palate's preset bounces irregularly (outcome impacting_nonperiodic): "
                 "no period to repeat. fsicas sound --physical PRESET sounds the last 2 s of "
                 "such a run with its quadrature controlled (about 44 min for soft_palate at "
                 "20 L/min on 2 shared cores)")


def _fmt(value, unit: str = "") -> str:
    return "—" if value is None else f"{value:.4g}{unit}"


class BackgroundPanel:
    """A background job's panel: its status readout (``testid``, ``label``), updated
    from the job of ``kind`` in ``jobs``; a subclass shows the result in ``_done``."""

    kind, testid, label, busy = "", "", "", "running"

    def __init__(self, jobs: Jobs, idle: str):
        self.jobs = jobs
        self.status = markup(readout(self.testid, idle, self.label))

    def poll(self) -> None:
        if self.jobs.running.get(self.kind) is not None:
            status, value = self.jobs.poll(self.kind)
            if status != "idle":
                self.show(status, value)

    @held
    def show(self, status: str, value) -> None:
        if status == "running":
            text = f"{self.busy}… {value:.0f} s"
        elif status in ("error", "cancelled"):
            text = status if value is None else f"{status}: {value}"
        else:
            return self._done(value)
        self.status.text = readout(self.testid, text, self.label)

    def _done(self, result: dict) -> None:
        raise NotImplementedError

    def _count(self, box: NumberBox, what: str) -> int | None:
        """The integer in ``box``, or None once the refusal (naming ``what``) is shown."""
        text = str(box.value).strip()
        try:
            return int(text)
        except ValueError:
            self.show("error", f"the {what} must be an integer, got {text!r}")
            return None


class RunPanel(BackgroundPanel):
    """The time run's controls and results for one page."""

    kind, testid, label = "run", "run-status", "time run"

    def __init__(self, jobs: Jobs):
        super().__init__(jobs, "not run")
        self.key, self.command, self.lines = None, "", ""
        self.t_end = NumberBox(value="20", label="t_end (T)", testid="t-end")
        self.start = pn.widgets.Button(name="time run", button_type="primary", width=120)
        self.stop = pn.widgets.Button(name="cancel run", width=110)
        self.stop.on_click(lambda _: self.jobs.cancel("run") and self.show("cancelled", None))
        self.source = ColumnDataSource({"t": [], "tip": []})
        self.figure = figure("tip_history", title="deflection y(x_ref, t) (x_ref: the free tip of a cantilever)", x_axis_label="t / T",
                             y_axis_label="y / L", height=260, sizing_mode="stretch_width")
        self.figure.line("t", "tip", source=self.source)
        self.audio = pn.pane.Audio(None, sample_rate=AUDIO_RATE, name="snore", visible=False)
        self.spectrum = ColumnDataSource({"hz": [], "spl_db": []})
        self.spectrum_figure = figure("snore_spectrum", title="the snore's spectrum at the listener",
                                      x_axis_label="frequency (Hz)", y_axis_label="dB SPL",
                                      height=260, sizing_mode="stretch_width", visible=False)
        self.spectrum_figure.line("hz", "spl_db", source=self.spectrum)

    @held
    def ask(self, scene, key: str, command) -> None:
        """Start (or show the cached) run of ``scene`` to the page's t_end; ``command``
        gives the scene's command lines (:func:`command_line` of the scene)."""
        try:
            t_end = float(str(self.t_end.value))
        except ValueError:
            return self.show("error", f"t_end must be a number, got {self.t_end.value!r}")
        self.key = ("run", f"{key}|{t_end!r}")
        self.command = command("simulate", t_end=t_end)
        self.lines = "" if scene.scales is None else sound_lines(
            scene, t_end, SOUND_DISTANCE, SOUND_DURATION, SPECTRUM_MAX_HZ)
        cached = self.jobs.start(self.key, run_view, scene, t_end)
        self.show("done", cached) if cached is not None else self.show("running", 0.0)

    def _done(self, run: dict) -> None:
        lines = [readout("run-status", run["status"], "time run"),
                 readout("run-outcome", run["outcome"], "outcome"),
                 readout("run-amplitude", _fmt(run["tip_amplitude"]), "tip amplitude"),
                 readout("run-period", _fmt(run["period"]), "period (T)")]
        lines += [readout("warning", w) for w in run["warnings"]]
        lines.append(readout("run-command", self.command))
        self.source.data = {"t": np.asarray(run["t"]).tolist(), "tip": np.asarray(run["tip"]).tolist()}
        sound = run["sound"]
        if sound is not None:
            lines.append(readout("sound-pitch", _fmt(sound["fundamental_hz"], " Hz"), "snore")
                         + ", " + readout("sound-level", _fmt(sound["spl_db"], " dB SPL"))
                         + f" at {sound['distance_m']:g} m")
            peak = float(np.max(np.abs(sound["pressure"]))) or 1.0
            self.audio.object = (np.asarray(sound["pressure"]) / peak * 32767).astype(np.int16)
            self.spectrum.data = dict(sound["spectrum"])
            lines.append(readout("sound-python", self.lines, "the snore in Python", "pre"))
        elif self.lines:                                  # a physical scene: why none
            why = NO_SOUND.format(outcome=run["outcome"])
            lines.append(readout("sound-none", why + (NO_SOUND_WALL if run["outcome"] == "contact"
                                                      else ""), "snore"))
        self.audio.visible = self.spectrum_figure.visible = sound is not None
        self.status.text = "<br>".join(lines)

    def page(self) -> pn.viewable.Viewable:
        return pn.Column("### Time run", self.t_end, pn.Row(self.start, self.stop), self.status,
                         self.audio, pn.pane.Bokeh(self.spectrum_figure), pn.pane.Bokeh(self.figure))
