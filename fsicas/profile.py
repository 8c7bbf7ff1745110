"""Channel walls: the distance H_c(x) from the beam's rest line to wall c, in units of L.

Channel 1 lies above the beam (y > 0 points into it), channel 2 below:
``h1 = H1(x) - y``, ``h2 = H2(x) + y``. The model never needs H_c'(x) (see
``docs/model.md``): any positive profile works, sampled at the quadrature nodes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

__all__ = ["Profile"]

_KINDS = ("constant", "linear", "table")


@dataclass(frozen=True)
class Profile:
    """A wall profile: ``constant`` (heights=(h,)), ``linear`` (heights=(h_inlet, h_outlet))
    or ``table`` (heights at abscissae ``x`` in [0, 1], joined by a C2 cubic spline)."""

    kind: str
    heights: tuple[float, ...]
    x: tuple[float, ...] = ()

    @classmethod
    def constant(cls, h: float) -> "Profile":
        return cls("constant", (float(h),))

    @classmethod
    def linear(cls, h_inlet: float, h_outlet: float) -> "Profile":
        return cls("linear", (float(h_inlet), float(h_outlet)))

    @classmethod
    def table(cls, x, h) -> "Profile":
        return cls("table", tuple(map(float, h)), tuple(map(float, x)))

    @classmethod
    def from_dict(cls, d: dict, name: str) -> "Profile":
        """Build from a TOML table: ``{kind=..., heights=[...], x=[...]}``."""
        unknown = set(d) - {"kind", "heights", "x"}
        if unknown:
            raise ValueError(f"{name}: unknown keys {sorted(unknown)}; allowed: kind, heights, x")
        heights = d.get("heights")
        if heights is None:
            raise ValueError(f"{name}.heights is required")
        heights = [heights] if np.isscalar(heights) else list(heights)
        return cls(d.get("kind", "constant"), tuple(map(float, heights)),
                   tuple(map(float, d.get("x", ()))))

    def validate(self, name: str) -> None:
        """Raise ValueError naming ``name`` unless the profile is well formed and positive."""
        need = {"constant": 1, "linear": 2}
        if self.kind not in _KINDS:
            raise ValueError(f"{name}.kind must be one of {_KINDS}, got {self.kind!r}")
        if self.kind in need and len(self.heights) != need[self.kind]:
            raise ValueError(f"{name}: a {self.kind} profile takes {need[self.kind]} height(s)")
        if self.kind == "table":
            x = np.asarray(self.x)
            if len(x) != len(self.heights) or len(x) < 2:
                raise ValueError(f"{name}: table needs x and heights of equal length >= 2")
            if x[0] != 0.0 or x[-1] != 1.0 or np.any(np.diff(x) <= 0):
                raise ValueError(f"{name}.x must increase strictly from 0 to 1")
        if not np.all(np.isfinite(self.heights)):
            raise ValueError(f"{name}.heights must be finite")
        xs = np.union1d(np.linspace(0.0, 1.0, 2001), self.x)
        hmin = float(np.min(self(xs)))
        if hmin <= 0.0:
            raise ValueError(f"{name}: the profile must be > 0 on all of [0, 1]; min is {hmin:g}")

    def __call__(self, x) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if self.kind == "constant":
            return np.full_like(x, self.heights[0])
        if self.kind == "linear":
            h0, h1 = self.heights
            return h0 + (h1 - h0) * x
        return CubicSpline(self.x, self.heights, bc_type="not-a-knot")(x)

    @property
    def is_constant(self) -> bool:
        return self.kind == "constant"
