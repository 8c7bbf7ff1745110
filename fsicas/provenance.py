"""What made a result and when: the versions of fsicas and its numerical libraries and a
UTC time stamp, written with every result file and JSON, in its ``meta``."""
from __future__ import annotations

import platform
from datetime import datetime, timezone
from importlib.metadata import PackageNotFoundError, version

__all__ = ["__version__", "versions", "created", "provenance", "with_meta"]

try:   # the one version source: pyproject.toml, through the installed package's metadata
    __version__ = version("fsicas")
except PackageNotFoundError:   # run from a source tree that was never installed
    __version__ = "unknown (not installed)"


def versions() -> dict:
    """The versions of fsicas, CasADi, NumPy, SciPy and Python."""
    import casadi
    import numpy
    import scipy
    return {"fsicas": __version__, "casadi": casadi.__version__, "numpy": numpy.__version__,
            "scipy": scipy.__version__, "python": platform.python_version()}


def created() -> str:
    """The current UTC time, ISO 8601 to the second."""
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def provenance() -> dict:
    """:func:`versions` and ``created``."""
    return {**versions(), "created": created()}


def with_meta(data: dict, meta: dict) -> dict:
    """``data`` with ``meta``, whose ``units`` (field -> unit) keep only the fields
    ``data`` has: a unit is never given for a field that was not written."""
    units = {k: v for k, v in (meta.get("units") or {}).items() if k in data}
    return {**data, "meta": {**meta, "units": units}}
