"""The summary of a study's table: each output's median and spread over the points.

For every numeric column (booleans and the index aside) over the rows that computed it::

    count, median, p05, p95 (the 5th and 95th percentiles), min, max

and for every text column (criticality, kind, outcome) the count of each value. The
points that failed (their ``error`` set) are counted apart and enter no statistic.
"""
from __future__ import annotations

import numpy as np

__all__ = ["summarize", "SPREAD"]

SPREAD = (5.0, 95.0)
"""The percentiles that give a study's spread."""

_NOT_SUMMARIZED = ("index", "error", "warnings")


def summarize(rows: list[dict]) -> dict:
    """``{"points", "failed", "columns": {name: statistics}}`` of a study's rows."""
    good = [row for row in rows if not row.get("error")]
    names = dict.fromkeys(k for row in good for k in row if k not in _NOT_SUMMARIZED)
    columns = {}
    for name in names:
        values = [row[name] for row in good if row.get(name) is not None]
        if values and all(_is_number(v) for v in values):
            columns[name] = _numeric(np.asarray(values, dtype=float))
        elif values and all(isinstance(v, str) for v in values):
            columns[name] = {"count": len(values), "values": _counts(values)}
    return {"points": len(rows), "failed": len(rows) - len(good), "columns": columns}


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _numeric(values: np.ndarray) -> dict:
    finite = values[np.isfinite(values)]
    if not finite.size:
        return {"count": 0}
    low, high = np.percentile(finite, SPREAD)
    return {"count": int(finite.size), "median": float(np.median(finite)), "p05": float(low),
            "p95": float(high), "min": float(finite.min()), "max": float(finite.max())}


def _counts(values: list[str]) -> dict:
    kinds, counts = np.unique(values, return_counts=True)
    return {str(k): int(c) for k, c in zip(kinds, counts)}
