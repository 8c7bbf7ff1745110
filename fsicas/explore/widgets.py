"""The page's own elements: a number box and a readout, each carrying a stable
``data-testid`` attribute (for the browser tests and users' scripts)."""
from __future__ import annotations

import html

import panel as pn
import param
from panel.reactive import ReactiveHTML

__all__ = ["NumberBox", "readout"]


class NumberBox(ReactiveHTML):
    """A labelled text input whose ``value`` (a string, parsed by the app) is sent on
    change (Enter or leaving the box)."""

    value = param.Parameter(default="")
    label = param.String(default="")
    testid = param.String(default="")

    _template = ('<label class="box">{{ label }} <input id="box" data-testid="{{ testid }}" '
                 'value="${value}" size="9"></input></label>')
    _dom_events = {"box": ["change"]}
    _stylesheets = [":host { margin: 2px 6px; } input { font: inherit; }"]


def readout(testid: str, text: str, label: str = "") -> str:
    """The HTML of one readout: ``label`` and ``text`` in a span with ``data-testid``."""
    head = f"{html.escape(label)}: " if label else ""
    return f'{head}<span data-testid="{testid}">{html.escape(text)}</span>'
