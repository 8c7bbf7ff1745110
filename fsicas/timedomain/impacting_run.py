"""The paper's impacting points (1a-c, Figs. 6-9) as time integrations.

M* = 1, zeta = 0.01, H* = 1/10 (the impact map's scene), N modes, the contact law on,
from a perturbation of 0.3 H*/2, IDAS with rtol 1e-7 and samples every 2e-5; the last
4 cycles are measured and called settled when they agree to ``tol``.
"""
from __future__ import annotations

from .impact_map import MAP_SCENE
from .integrators import Settings
from .outcome import Criteria
from .run import run_case

__all__ = ["PAPER_CONTACT", "HOLDING_CONTACT", "IMPACTING_SETTINGS", "impacting_run"]

#: The paper's contact law (Figs. 6-9), which does not hold the beam under our
#: reading, and the stiffest tested law that does (docs/simulate.md, "Decision").
PAPER_CONTACT = dict(contact_stiffness=1e6, contact_eps=1e-3)
HOLDING_CONTACT = dict(contact_stiffness=1e8, contact_eps=1e-2)
#: Integrator settings of the impacting runs (fine sampling resolves each impact).
IMPACTING_SETTINGS = Settings(method="idas", rtol=1e-7, atol=1e-9, dt_out=2e-5, chunk=0.25)


def impacting_run(ustar: float, modes: int = 10, contact: dict = HOLDING_CONTACT,
                  t_end: float = 4.0, tol: float = 2e-2, *, quad_nodes: int | None = None,
                  quadrature_tol: float | str | None = "auto"):
    """One run of the paper's impacting points at ``ustar`` with ``modes`` modes and the
    contact law ``contact`` (``contact_stiffness``, ``contact_eps``), to ``t_end`` without
    an early stop; its outcome's ``convergence`` says how closely the last 4 cycles agree
    (settled below ``tol``). ``quad_nodes`` (None: 2N + 20) and ``quadrature_tol``: the
    quadrature and its control (:func:`fsicas.timedomain.run.run_case`)."""
    scene = MAP_SCENE.replace(ustar=ustar, modes=modes, contact=True, quad_nodes=quad_nodes,
                              **contact)
    return run_case(scene, t_end, settings=IMPACTING_SETTINGS, perturbation=0.3,
                    stop_early=False, criteria=Criteria(cycles=4, tol_impacting=tol),
                    quadrature_tol=quadrature_tol)
