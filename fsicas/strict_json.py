"""JSON as the standard has it: no NaN or Infinity in anything fsicas writes.

Python's ``json`` writes ``NaN`` and ``Infinity`` by default, which strict readers
(JavaScript, ``jq``, most JSON libraries) refuse. :func:`finite` replaces each
non-finite number by ``null`` and says where it was, so the writer can say so in words;
:func:`dumps` writes with ``allow_nan=False`` after it.
"""
from __future__ import annotations

import json
import math

import numpy as np

__all__ = ["finite", "dumps", "nonfinite_note"]

#: The places named in a note at most.
NOTE_PLACES = 5


def finite(value, where: str = "") -> tuple[object, list[str]]:
    """``value`` with every NaN or infinite number (Python or NumPy, in dicts, lists and
    tuples at any depth) replaced by None, and the places replaced (``a.b[2]: nan``)."""
    if isinstance(value, (float, np.floating)):
        return (float(value), []) if math.isfinite(value) else (None, [f"{where or 'value'}: {value}"])
    if isinstance(value, dict):
        pairs = [(k, finite(v, f"{where}.{k}" if where else str(k))) for k, v in value.items()]
        return {k: v for k, (v, _) in pairs}, [p for _, (_, ps) in pairs for p in ps]
    if isinstance(value, (list, tuple)):
        items = [finite(v, f"{where}[{i}]") for i, v in enumerate(value)]
        return [v for v, _ in items], [p for _, ps in items for p in ps]
    return value, []


def nonfinite_note(places: list[str]) -> str | None:
    """The warning for the places :func:`finite` replaced (None if none)."""
    if not places:
        return None
    shown = ", ".join(places[:NOTE_PLACES]) + (" ..." if len(places) > NOTE_PLACES else "")
    return (f"{len(places)} value(s) not a finite number, written as null: {shown}")


def dumps(value, **kwargs) -> str:
    """``json.dumps`` of :func:`finite` (``value``), refusing any NaN left."""
    return json.dumps(finite(value)[0], allow_nan=False, **kwargs)
