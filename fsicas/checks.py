"""Input checks shared by every part that validates user input: one ``ValueError``
naming the parameter and what is allowed, raised before any expensive work."""
from __future__ import annotations

import math

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

__all__ = ["require", "finite_number", "read_toml", "check_points", "MAX_POINTS"]

#: Most points of one sweep (a map or a study): at a second or more a point, 1e5 points
#: are more than a day of one core; 1e7 would not even fit their list in memory.
MAX_POINTS = 100_000


def require(ok: bool, message: str) -> None:
    """Raise ``ValueError(message)`` unless ``ok``."""
    if not ok:
        raise ValueError(message)


def require_forward(scene, analysis: str) -> None:
    """ValueError for a scene of reversed flow (U* < 0) given to ``analysis``, which
    follows the flow from the root to the tip only (docs/model.md, "Reversed flow")."""
    require(scene.direction == "forward",
            f"{analysis} is computed for forward flow only (root to tip, U* >= 0), and the "
            f"scene has reversed flow (U* = {scene.ustar:g}): for reversed flow use steady, "
            "eig, onset, boundary, design, lco (also --through-contact: the impacting "
            "cycles), grazing, simulate or map")


def finite_number(name: str, value) -> float:
    """``value`` as a float; ValueError naming ``name`` unless it is a finite real number
    (booleans are refused)."""
    require(isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
            and math.isfinite(value), f"{name} must be a finite number, got {value!r}")
    return float(value)


def check_points(count: int, what: str, way_round: str) -> None:
    """ValueError, before the points are made, for a sweep of more than
    :data:`MAX_POINTS` points; ``way_round`` says how to ask for fewer."""
    require(count <= MAX_POINTS, f"{what} has {count:.3g} points, more than the {MAX_POINTS:,} "
            f"a run may have (at a second or more a point, days of work): {way_round}")


def read_toml(path, label: str) -> dict:
    """The TOML document at ``path``; ValueError naming ``label`` and the path when it is
    missing, a folder, unreadable or not valid TOML."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ValueError(f"{label} {path}: no such file") from None
    except IsADirectoryError:
        raise ValueError(f"{label} {path}: is a folder, not a TOML file") from None
    except OSError as err:
        raise ValueError(f"{label} {path}: cannot be read ({err.strerror})") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise ValueError(f"{label} {path}: not valid TOML ({err})") from None
    except RecursionError:
        raise ValueError(f"{label} {path}: nested too deeply to be a scene or physical "
                         "file (arrays or tables inside one another hundreds of times)") from None
