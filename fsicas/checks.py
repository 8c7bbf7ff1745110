"""Input checks shared by every part that validates user input: one ``ValueError``
naming the parameter and what is allowed, raised before any expensive work."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["require", "finite_number"]


def require(ok: bool, message: str) -> None:
    """Raise ``ValueError(message)`` unless ``ok``."""
    if not ok:
        raise ValueError(message)


def finite_number(name: str, value) -> float:
    """``value`` as a float; ValueError naming ``name`` unless it is a finite real number
    (booleans are refused)."""
    require(isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
            and math.isfinite(value), f"{name} must be a finite number, got {value!r}")
    return float(value)
