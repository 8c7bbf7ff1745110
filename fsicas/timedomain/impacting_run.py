"""The paper's impacting points (1a-c, Figs. 6-9) as time integrations.

M* = 1, zeta = 0.01, H* = 1/10 (the impact map's scene), N modes, the contact law on,
from a perturbation of 0.3 H*/2, IDAS with rtol 1e-7 and samples every 2e-5; the last
4 cycles are measured and called settled when they agree to ``tol``.

Modal truncation (:func:`with_truncation`): a run with N modes is compared with the same
run with fewer modes N' (N/2); its estimate per measure X (period, tip amplitude, impacts
per cycle, peak impact force, mean flow-rate reduction) is ``|X_N - X_N'| / |X_N|``.
Where X converges in N this bounds the error of X_N (U* = 7: the period moves 3.4e-3
from N = 10 to 20 and 3.4e-4 from 20 to 40); the peak force and the impacts per cycle do
not converge by N = 40 (4267, 3227, 2128 F0; 2, 6, 2 impacts; docs/simulate.md), and
their estimate is their size, not a bound. Above :data:`TRUNCATION_RTOL` (the onsets'
tolerance, :mod:`fsicas.linear.truncation`) the run's JSON says so in ``warnings`` and
its status is "unconverged".
"""
from __future__ import annotations

from ..linear.truncation import TRUNCATION_RTOL
from .impact_map import MAP_SCENE
from .integrators import Settings
from .outcome import Criteria
from .run import run_case

__all__ = ["PAPER_CONTACT", "HOLDING_CONTACT", "IMPACTING_SETTINGS", "impacting_run",
           "TRUNCATION_MEASURES", "with_truncation"]

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


#: The measures of an impacting run's JSON whose truncation is estimated.
TRUNCATION_MEASURES = ("period", "tip_amplitude", "impacts_per_cycle", "max_impact_force",
                       "mean_flow_reduction")


def with_truncation(run: dict, coarser: dict, tol: float = TRUNCATION_RTOL) -> dict:
    """The JSON ``run`` of an impacting run with N modes (``run["modes"]``) with its
    modal truncation estimate from ``coarser``, the same run with fewer modes (module
    docstring): ``truncation_error`` (per measure of :data:`TRUNCATION_MEASURES`,
    ``|X_N - X_N'| / |X_N|``, None where
    either run lacks X), ``truncation_modes`` (N'), ``truncation_tol``. A run that shows
    a cycle gets a warning and status "unconverged" when an estimate exceeds ``tol`` or
    is missing (the coarser run shows no cycle); a failed run is left as it is."""
    if not 0 < tol < 1:
        raise ValueError(f"tol must lie in (0, 1), got {tol!r}")
    if not coarser["modes"] < run["modes"]:
        raise ValueError(f"coarser must have fewer modes than run, got {coarser['modes']} "
                         f"and {run['modes']}")
    error = {k: _change(run[k], coarser[k]) for k in TRUNCATION_MEASURES}
    out = {**run, "truncation_error": error, "truncation_modes": coarser["modes"],
           "truncation_tol": tol}
    if run["period"] is None:
        return out
    above = [f"{k} {e:.2g}" for k, e in error.items() if e is not None and e > tol]
    missing = [k for k, e in error.items() if e is None]
    said = []
    if above:
        said.append(f"from N = {coarser['modes']} to N = {run['modes']} modes the "
                    f"{', '.join(above)} (relative), above the tolerance {tol:g}")
    if missing:
        why = (f"the N = {coarser['modes']} run shows no cycle ({coarser['outcome']})"
               if coarser["period"] is None else f"the N = {coarser['modes']} run lacks it")
        said.append(f"the {', '.join(missing)} not estimated: {why}")
    if said:
        out["warnings"] = [*run["warnings"], f"modal truncation: {'; '.join(said)}: raise modes"]
        out["status"] = "unconverged" if run["status"] == "success" else run["status"]
    return out


def _change(value, coarser) -> float | None:
    """``|value - coarser| / |value|``, None if either is missing."""
    if value is None or coarser is None or value == 0:
        return None
    return abs(value - coarser) / abs(value)
