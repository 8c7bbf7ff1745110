"""Grids of values on the command line: a comma list ``0.1,1,10`` or a range
``LO:HI:COUNT`` (``COUNT`` values from ``LO`` to ``HI``, both included).

One parser for every option that takes a grid; each option states its spacing: M*
ranges are log-spaced (``--mstar 0.01:100:41``), U* ranges evenly spaced
(``--ustar 2:16:15``). A grid has at most :data:`MAX_COUNT` values.
"""
from __future__ import annotations

import numpy as np

__all__ = ["parse_range", "MAX_COUNT"]

#: Most values of one grid (a map of 2000 x 2000 points would take weeks).
MAX_COUNT = 2000


def parse_range(text: str, name: str, log: bool = False) -> np.ndarray:
    """The values of option ``--name`` given as ``text`` (a comma list or ``LO:HI:COUNT``).

    ``log``: a range is log-spaced and every value must be > 0; otherwise a range is
    evenly spaced. Raises ValueError naming ``--name`` and the accepted forms."""
    try:
        values = _range(text, log) if ":" in text else np.array([float(v) for v in text.split(",")])
    except ValueError:
        values = None
    if values is None or not _allowed(values, log):
        raise ValueError(f"--{name} must be a comma list like 1,2,4 or a range LO:HI:COUNT "
                         f"({'log-spaced' if log else 'evenly spaced'}, 1 <= COUNT <= "
                         f"{MAX_COUNT}) of finite "
                         f"values{' > 0' if log else ''}; got {text!r}")
    unique, counts = np.unique(values, return_counts=True)
    if np.any(counts > 1):
        raise ValueError(f"--{name} repeats {', '.join(f'{v:g}' for v in unique[counts > 1])} "
                         f"(in {text!r}): give each value once")
    return values


def _range(text: str, log: bool) -> np.ndarray:
    """``LO:HI:COUNT`` as COUNT values, log- or evenly spaced (ValueError if malformed)."""
    lo, hi, count = text.split(":")
    lo, hi, count = float(lo), float(hi), int(count)
    if not 1 <= count <= MAX_COUNT or (log and (lo <= 0 or hi <= 0)):
        raise ValueError(text)
    return np.geomspace(lo, hi, count) if log else np.linspace(lo, hi, count)


def _allowed(values: np.ndarray, log: bool) -> bool:
    """At least one value, all finite, and all > 0 for a log-spaced option."""
    return 0 < values.size <= MAX_COUNT and bool(np.all(np.isfinite(values))) and (not log or bool(np.all(values > 0)))
