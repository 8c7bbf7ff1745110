"""Immutable, validated settings of periodic orbits: orthogonal collocation and multiple
shooting (frozen dataclasses checked at construction, like the driver's)."""

from __future__ import annotations

import os
from dataclasses import dataclass

from .._driver.settings import positive, positive_int


#: kernel backends of CollocationSettings.backend; the first is the default
BACKENDS = ("auto", "mx", "compiled")


def kernel_backend(backend: str | None) -> str:
    """``backend``, or when None ``$CONTINUATION_BACKEND`` (validated), else 'auto'."""
    if backend is not None:
        return backend
    env = os.environ.get("CONTINUATION_BACKEND", "").strip()
    if env and env not in BACKENDS:
        raise ValueError(f"CONTINUATION_BACKEND must be 'auto', 'mx' or 'compiled', got {env!r}")
    return env or BACKENDS[0]


MAX_NTST = 5000
"""The most mesh intervals of a collocated cycle: beyond it one Newton step of a system of
a few states already takes minutes and gigabytes; a cycle that needs more is better
split by shooting or its mesh adapted (``adapt_every``)."""


@dataclass(frozen=True)
class CollocationSettings:
    """Orthogonal collocation of periodic orbits.

    ntst : number of mesh intervals (2 to :data:`MAX_NTST`); ncol : Gauss-Legendre collocation
    points per interval (2 to 7). floquet : 'schur' (a periodic Schur form of the
    condensed transfer matrices: every multiplier accurate relative to its own size,
    whatever their spread; see ``docs/continuation.md``), 'pencil' (QZ of their
    block-cyclic pencil), 'product' (eigenvalues of their product: multipliers below
    about 1e-16 times the largest are lost) or 'auto' (default: 'schur').
    unstable_tol : a non-trivial multiplier counts as unstable when
    ``|mu| > 1 + unstable_tol``. adapt_every : re-mesh (equidistribution of
    the error indicator) after every ``adapt_every`` accepted points; 0 = never.
    jacobian : how the collocation residual and its sparse Jacobian are evaluated:
    'blocks' (default; one mapped CasADi call for ``F``, ``F_x``, ``M``, ... at all
    collocation points, the matrix assembled by NumPy) or 'graph' (CasADi AD of the
    whole discretised residual; the reference path).
    backend : how the 'blocks' kernel is evaluated: 'mx' (CasADi's virtual machine),
    'compiled' (C compiled once per vector field and cached on disk, see
    ``docs/performance.md``; falls back to 'mx' without a C compiler) or 'auto'
    ('compiled' for MX vector fields and small SX ones, 'mx' for large SX ones); None
    (default):
    ``$CONTINUATION_BACKEND`` if set, else 'auto'.
    linear_solver : how the Newton and tangent systems are solved: 'condensed' (the
    interior nodes of every interval eliminated by dense QR, then SuperLU on the
    reduced system of the mesh points, as AUTO-07p does; 'blocks' only), 'sparse'
    (SuperLU on the whole sparse matrix) or 'auto' (default: 'condensed' where the
    interval blocks are dense enough, see ``docs/continuation.md``).
    """

    ntst: int = 20
    ncol: int = 4
    floquet: str = "auto"
    unstable_tol: float = 1e-8
    adapt_every: int = 0
    jacobian: str = "blocks"
    backend: str | None = None
    linear_solver: str = "auto"

    def __post_init__(self):
        positive_int(self, "ntst", "ncol")
        if self.linear_solver not in ("auto", "condensed", "sparse"):
            raise ValueError("CollocationSettings.linear_solver must be 'auto', 'condensed' "
                             f"or 'sparse', got {self.linear_solver!r}")
        if self.linear_solver == "condensed" and self.jacobian != "blocks":
            raise ValueError("CollocationSettings.linear_solver = 'condensed' needs "
                             f"jacobian = 'blocks', got jacobian = {self.jacobian!r}")
        if self.backend is not None and self.backend not in BACKENDS:
            raise ValueError("CollocationSettings.backend must be None, 'auto', 'mx' or "
                             f"'compiled', got {self.backend!r}")
        if self.jacobian not in ("blocks", "graph"):
            raise ValueError("CollocationSettings.jacobian must be 'blocks' or 'graph', "
                             f"got {self.jacobian!r}")
        if not (isinstance(self.adapt_every, int) and self.adapt_every >= 0):
            raise ValueError("CollocationSettings.adapt_every must be an integer >= 0, got "
                             f"{self.adapt_every!r}")
        positive(self, "unstable_tol")
        if not 2 <= self.ntst <= MAX_NTST:
            raise ValueError(f"CollocationSettings.ntst must be in 2..{MAX_NTST}, got "
                             f"{self.ntst}")
        if not 2 <= self.ncol <= 7:
            raise ValueError(f"CollocationSettings.ncol must be in 2..7, got {self.ncol}")
        if self.floquet not in ("auto", "schur", "pencil", "product"):
            raise ValueError("CollocationSettings.floquet must be 'auto', 'schur', 'pencil' "
                             f"or 'product', got {self.floquet!r}")


@dataclass(frozen=True)
class ShootingSettings:
    """Multiple shooting of periodic orbits with a CasADi integrator.

    segments : number of shooting segments (>= 1); integrator : CasADi plugin
    ('cvodes', 'idas', 'rk'); abstol, reltol : integrator tolerances (their
    sensitivities give the exact Jacobian of the discrete map); floquet :
    'schur' (default), 'pencil' or 'product' of the segments' sensitivities (see
    CollocationSettings); unstable_tol as there.
    jacobian : 'blocks' (default: one integration with forward sensitivities per
    segment in the directions ``(x_i, T, p_free)`` only, assembled sparse and kept
    for the last ``X``) or 'graph' (CasADi differentiates the whole mapped
    integrator in all parameter directions; the reference). Both are CasADi
    forward derivatives of the integrator (the sensitivity equations appended to
    the ODE and integrated by the plugin at ``abstol``/``reltol``).
    sensitivities : how the 'blocks' route integrates the sensitivities: 'exact'
    (default: CasADi's AD of the rate ``R = M^{-1} F`` in every direction, with the
    second-order term of the augmented Newton matrix; the previous route) or 'fast'
    (``[dR/dx, dR/dp_free] = M^{-1} [F_x - d(M v)/dx, F_p - d(M v)/dp]`` at
    ``v = R`` from the field's Jacobians, evaluated once per right-hand side and
    multiplied into all directions, the non-free parameters fixed in the
    integrator, and without that second-order term: 6-15x faster on a modal
    model with wall impacts). The two integrate the same residual and their
    Jacobians differ by integration error only: each is equally far from the limit
    both reach as the tolerances shrink (the tests check 'fast' against a reference
    at 1e-13), so at equal tolerance neither is the more accurate. threads : segments
    integrated in parallel by the 'blocks' route (CasADi ``map`` with threads; the
    same numbers as one thread).
    """

    segments: int = 4
    integrator: str = "cvodes"
    abstol: float = 1e-12
    reltol: float = 1e-12
    floquet: str = "schur"
    unstable_tol: float = 1e-8
    jacobian: str = "blocks"
    sensitivities: str = "exact"
    threads: int = 1

    def __post_init__(self):
        positive_int(self, "segments", "threads")
        if self.sensitivities not in ("exact", "fast"):
            raise ValueError("ShootingSettings.sensitivities must be 'exact' or 'fast', got "
                             f"{self.sensitivities!r}")
        positive(self, "abstol", "reltol", "unstable_tol")
        if self.jacobian not in ("blocks", "graph"):
            raise ValueError("ShootingSettings.jacobian must be 'blocks' or 'graph', got "
                             f"{self.jacobian!r}")
        if self.integrator not in ("cvodes", "idas", "rk"):
            raise ValueError("ShootingSettings.integrator must be 'cvodes', 'idas' or 'rk', "
                             f"got {self.integrator!r}")
        if self.floquet not in ("schur", "pencil", "product"):
            raise ValueError("ShootingSettings.floquet must be 'schur', 'pencil' or "
                             f"'product', got {self.floquet!r}")
