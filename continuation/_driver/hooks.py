"""User hooks of ``continuation()``: events located on the branch, a per-point
``record`` and a ``stop`` predicate, validated before any work."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Mapping

import numpy as np

from .branch import BUILTIN_KINDS


@dataclass(frozen=True)
class Event:
    """A user event: a zero of ``function(problem, X) -> float`` on the branch.

    ``function`` is evaluated at every accepted point (``X``: the problem's
    unknowns); a sign change between consecutive points is located like the
    built-in events (Illinois regula falsi in arclength, each trial point
    corrected by PALC, to ``settings.locate_tol``) and recorded as a
    :class:`SpecialPoint` of kind ``name``. A ``terminal`` event ends the branch
    at the located point (``Branch.status == 'event'``).
    """

    name: str
    function: Callable
    terminal: bool = False

    def __post_init__(self):
        if not (isinstance(self.name, str) and self.name.isidentifier()):
            raise ValueError(f"Event.name must be an identifier string, got {self.name!r}")
        if self.name in BUILTIN_KINDS:
            raise ValueError(f"Event.name {self.name!r} is a built-in special-point kind; "
                             f"use another name (built-in: {BUILTIN_KINDS})")
        if not callable(self.function):
            raise ValueError("Event.function must be callable (problem, X) -> float, got "
                             f"{type(self.function).__name__}")
        if not isinstance(self.terminal, bool):
            raise ValueError(f"Event.terminal must be a bool, got {self.terminal!r}")


@dataclass(frozen=True)
class Hooks:
    events: tuple
    record: Callable | None
    stop: Callable | None


def check_hooks(events, record, stop) -> Hooks:
    """Validated ``events``, ``record``, ``stop`` (ValueError naming the argument)."""
    events = (events,) if isinstance(events, Event) else tuple(events)
    bad = [e for e in events if not isinstance(e, Event)]
    if bad:
        raise ValueError(f"events must be continuation.Event instances, got "
                         f"{type(bad[0]).__name__}")
    names = [e.name for e in events]
    if len(set(names)) != len(names):
        raise ValueError(f"events must have distinct names, got {names}")
    for label, fun in (("record", record), ("stop", stop)):
        if fun is not None and not callable(fun):
            raise ValueError(f"{label} must be None or a callable (problem, X), got "
                             f"{type(fun).__name__}")
    return Hooks(events, record, stop)


def stopped(result, index):
    """``('stopped', message)`` when the ``stop`` predicate's ``result`` is true."""
    if not result:
        return None
    if isinstance(result, str):
        return ("stopped", result)
    return ("stopped", f"stop predicate returned True at point {index}")


def crossed(a: float, b: float) -> bool:
    """A sign change from ``a`` to ``b`` (``b`` exactly zero counts once)."""
    if not (math.isfinite(a) and math.isfinite(b)):
        return False
    return a * b < 0 or (b == 0.0 and a != 0.0)


def scalars(values: Mapping) -> dict:
    """The real scalar entries of ``values`` as floats."""
    out = {}
    for k, v in values.items():
        a = np.asarray(v)
        if a.ndim == 0 and np.isrealobj(a) and a.dtype.kind in "biuf":
            out[str(k)] = float(a)
    return out
