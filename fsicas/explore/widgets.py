"""The page's own elements: a number box, a block of readouts and a readout, each
carrying a stable ``data-testid`` attribute (for the browser tests and users' scripts)."""
from __future__ import annotations

import functools
import html

import param
from panel.io import hold
from panel.custom import JSComponent
from panel.reactive import ReactiveHTML

__all__ = ["ChoiceBox", "Markup", "NumberBox", "held", "markup", "readout"]


class NumberBox(ReactiveHTML):
    """A labelled text input whose ``value`` (a string, parsed by the app) is sent on
    change (Enter or leaving the box): one message, the DOM event carrying the text (the
    attribute sync is off: it would send the value a second time)."""

    value = param.Parameter(default="")
    label = param.String(default="")
    testid = param.String(default="")

    _template = ('<label class="box">{{ label }} <input id="box" data-testid="{{ testid }}" '
                 'value="${value}" size="11"></input></label>')
    _dom_events = {"box": {"change": False}}
    _stylesheets = [":host { margin: 2px 6px; } input { font: inherit; }"]

    def _box_change(self, event) -> None:
        self.value = str(event.data["target"]["value"])



class ChoiceBox(ReactiveHTML):
    """A labelled menu of ``options`` whose ``value`` is sent on change, as
    :class:`NumberBox` (the ``<select>`` carries ``data-testid``)."""

    value = param.String(default="")
    options = param.List(default=[])
    label = param.String(default="")
    testid = param.String(default="")

    _template = ('<label class="box">{{ label }} <select id="box" data-testid="{{ testid }}" '
                 'value="${value}">{% for option in options %}<option value="{{ option }}">'
                 '{{ option }}</option>{% endfor %}</select></label>')
    _dom_events = {"box": {"change": False}}
    _stylesheets = [":host { margin: 2px 6px; } select { font: inherit; }"]

    def _box_change(self, event) -> None:
        self.value = str(event.data["target"]["value"])


def readout(testid: str, text: str, label: str = "", tag: str = "span") -> str:
    """The HTML of one readout: ``label`` and ``text`` in a ``tag`` (a span; ``pre`` for
    lines of code) with ``data-testid``."""
    head = f"{html.escape(label)}: " if label else ""
    return f'{head}<{tag} data-testid="{testid}">{html.escape(text)}</{tag}>'


class Markup(JSComponent):
    """A block of HTML whose ``text`` the app sets, written into the page by the
    component's own render function (``innerHTML``): a change redraws this block alone.
    (A Bokeh ``Div`` re-renders itself and then recomputes the layout of the whole page,
    every figure measured and repainted: 20-70 ms of the browser's time per change,
    measured with Chromium's profiler.)"""

    text = param.String(default="")

    _esm = """export function render({ model, el }) {
  const out = document.createElement("div");
  out.className = "markup";
  const show = () => { out.innerHTML = model.text; };
  show();
  model.on("text", show);
  el.appendChild(out);
}"""
    _stylesheets = [".markup { overflow-wrap: anywhere; } pre { white-space: pre-wrap; margin: 0; }"]


def markup(text: str = "", **styles: str) -> Markup:
    """A :class:`Markup` block showing ``text``, with the CSS ``styles``."""
    return Markup(text=text, sizing_mode="stretch_width", styles=styles)


def held(method):
    """``method`` with the document held (``panel.io.hold``): the Bokeh models it changes
    directly are changed under the document's lock, whichever callback calls it (a DOM
    event's runs outside it), and sent once it returns."""
    @functools.wraps(method)
    def run(*args, **kwargs):
        with hold():
            return method(*args, **kwargs)
    return run
