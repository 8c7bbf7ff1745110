"""Records of cycle branches: a cycle point's JSON, a branch's columns and its file.

:class:`CycleRecord` is the base of the frozen point dataclasses of both routes
(collocation and shooting); :class:`BranchRecord` of their branches.
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, fields

import numpy as np

from .. import strict_json
from ..checks import finite_number, require

__all__ = ["CycleRecord", "CycleMeasures", "BranchRecord", "plain_value", "check_settings",
           "branch_end", "START_FAILED"]

#: Why an impacting branch has no point: its start could not be integrated.
START_FAILED = "the start cycle could not be integrated over one period: {}"


class CycleRecord:
    """JSON of a frozen cycle dataclass with complex array fields (``_complex``:
    ``multipliers``) and ``state``; ``_derived`` names properties written for readers
    and skipped on reading."""

    _derived: tuple = ()

    @property
    def nontrivial_multipliers(self) -> np.ndarray:
        """All multipliers but the one nearest 1 (the trivial one)."""
        mu = np.asarray(self.multipliers)
        return np.delete(mu, np.argmin(np.abs(mu - 1.0)))

    #: complex array fields, written as [re, im] pairs
    _complex: tuple = ("multipliers",)

    def to_json(self) -> dict:
        d = {k: v for k, v in asdict(self).items() if k not in ("state",) + self._complex}
        d.update({k: getattr(self, k) for k in self._derived})
        d["state"] = [float(v) for v in self.state]
        d.update({k: [[float(m.real), float(m.imag)] for m in np.asarray(getattr(self, k))]
                  for k in self._complex})
        return d

    @classmethod
    def from_columns(cls, columns: dict, k: int, **fixed):
        """The record of point ``k`` of a branch's (or a special point's) columns;
        ``period`` is read from the ``cycle_period`` column; ``fixed`` sets fields."""
        names = {f.name: "cycle_period" if f.name == "period" else f.name for f in fields(cls)}
        values = {f: plain_value(columns[c][k] if k is not None else columns[c])
                  for f, c in names.items() if c in columns}
        return cls(**{**values, **fixed})

    @classmethod
    def from_json(cls, d: dict):
        """The record of ``to_json``'s dict, also read back from strict JSON: a null
        where a number was (NaN or infinite when written) reads as NaN."""
        unmeasured = {f.name for f in fields(cls) if _is_nan(f.default)}
        d = {k: math.nan if v is None and k in unmeasured else v
             for k, v in d.items() if k not in cls._derived}
        d.update({k: np.array([complex(_nan(a), _nan(b)) for a, b in d[k]], dtype=complex)
                  for k in cls._complex if k in d})
        d["state"] = np.array([_nan(v) for v in d["state"]], dtype=float)
        return cls(**d)


@dataclass(frozen=True)
class CycleMeasures(CycleRecord):
    """What both routes measure of a cycle (:mod:`fsicas.cycles.gauge`): U* and Δp of
    the steady state at the same pressure drop, the period (units of T), the tip
    half-amplitude, the minimal gap over the cycle and its ratio to eps."""

    ustar: float
    pressure_drop: float
    period: float
    tip_amplitude: float
    min_gap: float
    gap_ratio: float


def _is_nan(value) -> bool:
    return isinstance(value, float) and math.isnan(value)


def _nan(value) -> float:
    """A number of a strict JSON file: null as NaN."""
    return math.nan if value is None else value


def plain_value(value):
    """A column entry as a plain Python value (arrays are copied)."""
    if isinstance(value, np.ndarray) and value.ndim:
        return value.copy()
    return value.item() if isinstance(value, (np.generic, np.ndarray)) else value


class BranchRecord:
    """A branch of cycle points: ``column(name)`` along it, ``save(path)`` / ``load(path)``
    through its ``to_json`` / ``from_json``."""

    def column(self, name: str) -> np.ndarray:
        """One quantity along the branch, e.g. ``column("ustar")``."""
        return np.array([getattr(p, name) for p in self.points])

    def save(self, path) -> None:
        """Write the branch as strict JSON (NaN and infinities as null)."""
        with open(path, "w") as f:
            f.write(strict_json.dumps(self.to_json(), indent=1))

    @classmethod
    def load(cls, path):
        with open(path) as f:
            return cls.from_json(json.load(f))


def check_settings(settings, integers: tuple = (), positives: tuple = (),
                   nonnegative_integers: tuple = ()) -> None:
    """ValueError naming the first field of ``settings`` that is not a positive integer,
    a positive finite number or a non-negative integer, as its group requires."""
    kind = type(settings).__name__
    for name in integers + nonnegative_integers:
        v, low = getattr(settings, name), 0 if name in nonnegative_integers else 1
        what = "a non-negative" if low == 0 else "a positive"
        require(isinstance(v, int) and not isinstance(v, bool) and v >= low,
                f"{kind}.{name} must be {what} integer, got {v!r}")
    for name in positives:
        v = getattr(settings, name)
        require(finite_number(f"{kind}.{name}", v) > 0,
                f"{kind}.{name} must be a positive number, got {v!r}")


def branch_end(status: str, points: list, max_points: int) -> str:
    """Why a branch of at most ``max_points`` ``points`` ended, from the library's
    ``status``: "max_points" (the budget), "bound" (U* left its range) or "failed"."""
    return "max_points" if len(points) == max_points else \
        {"bound": "bound", "max_steps": "max_points"}.get(status, "failed")
