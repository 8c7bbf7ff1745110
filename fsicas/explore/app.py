"""The explorer's page: inputs, the instant tier (computed on each change), the onset
(its own process, answered within seconds) and the boundary map (a background job),
the reproducing command line, the state in the URL."""
from __future__ import annotations

import functools
import math

import panel as pn
import param

from ..physical import Physical, load_physical, preset_names
from ..scene import BEAM_ENDS, DIRECTIONS, Scene
from .background import RunPanel
from .cycles import CyclePanel
from .curves import CurvePanel
from .compute import (INPUTS, PHYSICAL_INPUTS, boundary_view, export, input_text, instant_view,
                      onset_view, physical_scene, physical_texts, preset_scene, scene_of)
from .files import decode_file, encode_file, matching_preset, read_scene_file
from .figures import BoundaryMap, ModeShape, RootLocus
from .jobs import Jobs
from .reproduce import SceneFile, command_line, python_lines
from .readouts import instant_html, onset_html
from .widgets import ChoiceBox, NumberBox, held, markup, readout

__all__ = ["Explorer", "RESULTS"]

#: Finished onsets and boundaries of this server, by (kind, scene): shared by sessions.
RESULTS: dict = {}
POLL_MS, FRAME_MS = 150, 100
NO_PRESET, FROM_FILE = "none (nondimensional)", "from file"


class LoadedFile(param.Parameterized):
    """The scene file loaded on the page, in its address: its name (``scenefile``) and
    its values (``scene``, :func:`encode_file`), not its path."""

    filename = param.String(default="")
    data = param.String(default="")


def _key(scene: Scene, *drop: str) -> str:
    """The cache key of ``scene`` without the fields ``drop``."""
    d = {**scene.to_dict(), "direction": scene.direction}    # ustar dropped: its sign kept
    for name in drop:
        d.pop(name, None)
    return repr(sorted(d.items()))


class Explorer:
    """One session's page."""

    def __init__(self, preset: str | None = None):
        self.base = preset_scene(preset)
        #: The physical input (a preset or a loaded file) the scene comes from, or None;
        #: the nondimensional scene file loaded, or None.
        self.source: Physical | None = None if preset is None else load_physical(preset)
        self.file: SceneFile | None = None
        self.presets = pn.widgets.Select(name="physical preset", value=preset or NO_PRESET,
                                         options=[NO_PRESET, *preset_names()], width=200)
        self.holding = False
        self.upload = pn.widgets.FileInput(accept=".toml", multiple=False, width=220)
        self.loaded = markup(readout("scene-file", ""))
        self.address = LoadedFile()
        self.jobs = Jobs(RESULTS)
        self.scene = self.base
        self.boxes = {k: NumberBox(value=input_text(getattr(self.base, k)), label=label, testid=k)
                      for k, (label, _) in INPUTS.items()}
        self.boxes["ustar"].value = input_text(abs(self.base.ustar))    # the speed |U*|
        self._menus()
        self.physical = {k: NumberBox(label=label, testid=f"phys-{k}", visible=False)
                         for k, label in PHYSICAL_INPUTS.items()}
        self._show_physical()
        self.error = markup(readout("error", ""), color="#b00")
        self.readouts = markup("")
        self.onset = markup(readout("onset-kind", "…", "onset"))
        self.background = markup(readout("boundary-status", "…", "boundary map"))
        self.command = markup("")
        self.locus, self.shape, self.map = RootLocus(), ModeShape(), BoundaryMap()
        self.animate = pn.widgets.Toggle(name="animate the mode", value=False, width=160)
        self.phase = 0.0
        self.run = RunPanel(self.jobs)
        self.cycles = CyclePanel(self.jobs)
        self.curves = CurvePanel(self.jobs, self.map)
        self.download = pn.widgets.FileDownload(callback=self._export, filename="fsicas_explore.json",
                                                label="export the view (JSON)", width=220)
        self._wire()

    def _menus(self) -> None:
        """The beam, its e/L and ends, and the flow direction, from the scene's."""
        self.beam = pn.widgets.Select(name="beam", value=self.base.beam,
                                      options=["euler-bernoulli", "timoshenko"], width=200)
        self.slenderness = NumberBox(value=input_text(self.base.slenderness), label="e/L",
                                     testid="slenderness")
        self.ends = ChoiceBox(value=self.base.ends, options=list(BEAM_ENDS), label="beam ends",
                              testid="ends")
        self.direction = ChoiceBox(value=self.base.direction, options=list(DIRECTIONS),
                                   label="flow direction", testid="direction")

    # -- wiring ---------------------------------------------------------------------
    def _wire(self) -> None:
        for box in self.boxes.values():
            box.param.watch(self._changed, "value")
        self.presets.param.watch(self._preset, "value")
        self.upload.param.watch(self._uploaded, "value")
        self.address.param.watch(self._from_address, "data")
        for box in self.physical.values():
            box.param.watch(self._physical_changed, "value")
        for menu in (self.beam, self.ends, self.direction):
            menu.param.watch(self._changed, "value")
        self.slenderness.param.watch(self._changed, "value")
        from bokeh.events import Tap
        self.map.figure.on_event(Tap, self._tapped)
        self.cancel = pn.widgets.Button(name="cancel", width=90)
        self.cancel.on_click(lambda _: self._cancel("boundary"))
        self.draw_map = pn.widgets.Button(name="compute the map", button_type="primary", width=150)
        self.draw_map.on_click(lambda _: self._ask("boundary", self._map_key(), boundary_view,
                                                   self.scene))
        self.run.start.on_click(lambda _: self.run.ask(self.scene, _key(self.scene),
                                                       self._commands()))
        self.cycles.start.on_click(lambda _: self.cycles.ask(
            self.scene, _key(self.scene, "ustar"), self._commands()))
        self.curves.start.on_click(lambda _: self.curves.ask(self.scene, self._map_key(),
                                                             self._commands()))
        self.refresh()

    def start(self) -> None:
        """Once the page is served: URL sync, polling of the jobs, the animation."""
        if pn.state.location is not None:                   # the file first, then the boxes
            pn.state.location.sync(self.address, {"filename": "scenefile", "data": "scene"})
            pn.state.location.sync(self.presets, {"value": "preset"})
            for name, box in self.physical.items():
                pn.state.location.sync(box, {"value": name})
            for name, box in self.boxes.items():
                pn.state.location.sync(box, {"value": name})
            for name, menu in (("beam", self.beam), ("ends", self.ends),
                               ("direction", self.direction)):
                pn.state.location.sync(menu, {"value": name})
            pn.state.location.sync(self.slenderness, {"value": "slenderness"})
        pn.state.add_periodic_callback(self.poll, period=POLL_MS)
        frames = pn.state.add_periodic_callback(self._frame, period=FRAME_MS, start=False)
        self.animate.param.watch(lambda e: frames.start() if e.new else frames.stop(), "value")
        pn.state.on_session_destroyed(lambda _: self.jobs.close())

    def _changed(self, _event=None) -> None:
        if not self.holding:
            self.refresh()

    def _preset(self, event) -> None:
        """Start again from the preset's scene (or the default one): every box at once,
        the preset's physical inputs shown as its file writes them."""
        if self.holding or event.new == FROM_FILE:
            return
        self.source = None if event.new == NO_PRESET else load_physical(event.new)
        self.presets.options = [NO_PRESET, *preset_names()]
        self.address.param.update(filename="", data="")
        self._start_from(Scene() if self.source is None else physical_scene(self.source), None)

    def _uploaded(self, event) -> None:
        """A scene file loaded in the page, read by the library as the CLI reads it: a
        physical file as ``--physical`` (its physical inputs shown), any other as
        ``--scene`` (written as ``--scene NAME`` in the commands); its message if it
        refuses the file (the last valid view stays)."""
        if not event.new:
            return
        name = self.upload.filename or "scene.toml"
        with param.parameterized.discard_events(self.upload):
            self.upload.value = None             # the same file loaded again is a change,
        self.upload.clear()                      # here and in the browser's file input
        try:
            read = read_scene_file(name, event.new)
        except ValueError as err:
            return self._refuse(err)
        self._load(name, read, "")

    def _from_address(self, event) -> None:
        """The scene file of the address (its values, :func:`decode_file`), as loaded."""
        if self.holding or not event.new:
            return
        name = self.address.filename or "scene.toml"
        try:
            read = decode_file(name, event.new)
        except ValueError as err:
            return self._refuse(err)
        self._load(name, read, ", from the address")

    def _load(self, name: str, read: Scene | Physical, how: str) -> None:
        """The file ``name`` read as ``read`` as the page's scene: the preset menu shows
        the preset it is (a physical file of a preset's values) or "from file", the
        address its values."""
        try:
            base = physical_scene(read) if isinstance(read, Physical) else read
        except ValueError as err:
            return self._refuse(err)
        preset = matching_preset(read) if isinstance(read, Physical) else None
        kind = "physical file" if isinstance(read, Physical) else "scene file"
        if preset is not None:
            kind += f": the preset {preset}"
        self.source = read if isinstance(read, Physical) else None
        self.holding = True
        self.presets.options = [NO_PRESET, *preset_names(), FROM_FILE]
        self.presets.value = preset or FROM_FILE
        self.address.param.update(filename="" if preset else name,
                                  data="" if preset else encode_file(read))
        self._start_from(base, None if self.source else SceneFile(name, base),
                         f"{name} ({kind}{how})")

    def _start_from(self, base: Scene, file: SceneFile | None, loaded: str = "") -> None:
        """``base`` as the page's scene, its physical inputs shown, ``file`` the scene
        file the commands name, ``loaded`` the file's name and kind (for the readout)."""
        self.file = file
        self.loaded.text = readout("scene-file", loaded, "loaded" if loaded else "")
        self.holding = True
        self._show_physical()
        self._apply(base)

    def _show_physical(self) -> None:
        """The physical inputs as the preset's or file's table writes them (none without
        one)."""
        texts = {} if self.source is None else physical_texts(self.source)
        for name, box in self.physical.items():
            box.value, box.visible = texts.get(name, ""), name in texts

    def _physical_changed(self, _event=None) -> None:
        """The preset's scene with the physical inputs, converted by the library; its
        message if it refuses them (the last valid view stays)."""
        if self.holding or self.source is None:
            return
        texts = {k: box.value for k, box in self.physical.items() if box.visible}
        try:
            base = physical_scene(self.source, texts)
        except ValueError as err:
            return self._refuse(err)
        self._apply(base)

    def _apply(self, base: Scene) -> None:
        """``base`` as the page's scene: its values in the boxes (held: one refresh)."""
        self.base, self.holding = base, True
        for name, box in self.boxes.items():
            box.value = input_text(getattr(self.base, name))
        self.boxes["ustar"].value = input_text(abs(self.base.ustar))
        self.beam.value, self.ends.value = self.base.beam, self.base.ends
        self.direction.value = self.base.direction
        self.slenderness.value = input_text(self.base.slenderness)
        self.holding = False
        self.refresh()

    @held
    def _refuse(self, err: ValueError) -> None:
        self.error.text = readout("error", str(err))

    def _tapped(self, event) -> None:
        """A click on the map: its (M*, U*) the point (a negative U*: reversed flow)."""
        if event.x is not None and event.y is not None and event.x > 0:
            self.holding = True                           # all three set, one refresh
            self.boxes["mstar"].value = f"{event.x:.4g}"
            self.direction.value = DIRECTIONS[1] if event.y < 0 else DIRECTIONS[0]
            self.boxes["ustar"].value = f"{abs(event.y):.4g}"
            self.holding = False
            self.refresh()

    @held
    def _cancel(self, kind: str) -> None:
        if self.jobs.cancel(kind):
            self.background.text = readout("boundary-status", "cancelled", "boundary map")

    # -- the tiers ------------------------------------------------------------------
    def refresh(self) -> None:
        """Read the inputs; show the readouts, alone in a first message (the browser shows
        them before it redraws any figure); then the figures, the command line, the onset
        and the map."""
        if self._readouts():
            self._draw()

    @held
    def _readouts(self) -> bool:
        """The scene of the inputs and its instant view in the readouts (True), or the
        library's message in the error line (False: the last valid view stays)."""
        try:
            texts = {k: b.value for k, b in self.boxes.items()}
            texts.update(beam=self.beam.value, slenderness=self.slenderness.value,
                         ends=self.ends.value, direction=self.direction.value)
            scene = scene_of(self.base, texts)
            view = instant_view(scene)
        except ValueError as err:
            self._refuse(err)
            return False
        self.error.text = readout("error", "")
        self.scene, self.view = scene, view
        self.readouts.text = instant_html(view)
        return True

    @held
    def _draw(self) -> None:
        scene, view = self.scene, self.view
        self.locus.update(view["eigenvalues"])
        self.shape.update(view["x"], view["y"], scene.hstar)
        self.command.text = (readout("command", command_line(scene, "eig", self.file))
                             + readout("python", python_lines(scene, self.file), tag="pre"))
        self._ask("onset", _key(scene, "ustar"), onset_view, scene)
        self.map.crosshair(scene.mstar, scene.ustar)
        self.cycles.here.location = scene.ustar
        cached = RESULTS.get(("boundary", self._map_key()))
        self._show("boundary", "done" if cached else "idle", cached)

    def _commands(self):
        """The command lines of the current scene: ``(command, **extra) -> str``."""
        return functools.partial(command_line, self.scene, file=self.file)

    def _map_key(self) -> str:
        """The boundary's cache key: the scene but U* and M*, and the decade of M*."""
        decade = math.floor(math.log10(self.scene.mstar))
        return _key(self.scene, "ustar", "mstar") + str(decade)

    def _ask(self, kind: str, key: str, target, scene: Scene) -> None:
        result = self.jobs.start((kind, key), target, scene)
        if result is not None:
            self._show(kind, "done", result)
        else:
            self._show(kind, "running", 0.0)

    # -- results --------------------------------------------------------------------
    @held
    def poll(self) -> None:
        for kind in ("onset", "boundary"):
            status, value = self.jobs.poll(kind)
            if kind == "boundary" and status == "done" and value is not RESULTS.get(
                    ("boundary", self._map_key())):
                status = "idle"                      # a map of a scene left meanwhile
            if status != "idle":
                self._show(kind, status, value)
        for panel in (self.run, self.cycles, self.curves):
            panel.poll()

    def _show(self, kind: str, status: str, value) -> None:
        if kind == "onset":
            self.onset.text = onset_html(status, value)
        elif status == "done":
            self.map.update(value["points"])
            self.background.text = readout("boundary-status", "done", "boundary map")
        elif status == "running":
            self.background.text = readout("boundary-status",
                                             f"computing… {value:.0f} s", "boundary map")
        elif status == "idle":
            self.map.update([])                  # no other scene's boundary on the map
            self.background.text = readout("boundary-status", "not computed (tens of seconds "
                                             "at N = 10, in the background)", "boundary map")
        else:
            self.background.text = readout("boundary-status", f"failed: {value}")

    def _export(self):
        """The JSON of the current view (:func:`export`) for the download button, with the
        map, the limit-cycle branch and the time run of this scene where computed."""
        import io
        onset = RESULTS.get(("onset", _key(self.scene, "ustar")))
        of_scene = lambda key, scene: (RESULTS.get(key) if key and key[1].startswith(scene + "|")
                                       else None)       # the last job asked for, if of this scene
        return io.StringIO(export(self.scene, self.view, onset,
                                  command_line(self.scene, "eig", self.file),
                                  boundary=RESULTS.get(("boundary", self._map_key())),
                                  cycles=of_scene(self.cycles.key, _key(self.scene, "ustar")),
                                  run=of_scene(self.run.key, _key(self.scene)),
                                  curves=of_scene(self.curves.key, self._map_key())))

    @held
    def _frame(self) -> None:
        """One step of the mode's animation (called only while "animate the mode" is on)."""
        self.phase = (self.phase + 0.3) % (2 * math.pi)
        self.shape.animate(self.phase)

    # -- the page -------------------------------------------------------------------
    def page(self) -> pn.viewable.Viewable:
        inputs = pn.Column("### Inputs", self.presets, "scene file (TOML)", self.upload,
                           self.loaded, *self.physical.values(),
                           *self.boxes.values(), self.direction, self.beam, self.slenderness,
                           self.ends, self.error,
                           width=260)
        instant = pn.Column("### Now", self.readouts, self.animate,
                            pn.pane.Bokeh(self.shape.figure), pn.pane.Bokeh(self.locus.figure))
        slower = pn.Column("### Onset", self.onset, "### Map", self.background,
                           pn.Row(self.draw_map, self.cancel),
                           pn.pane.Bokeh(self.map.figure), self.curves.page(), self.cycles.page(),
                           self.run.page())
        title = "fsicas explore"
        return pn.Column(f"## {title}", pn.Row(inputs, instant, slower, sizing_mode="stretch_width"),
                         "### Reproduce", self.command, self.download,
                         sizing_mode="stretch_width")
