"""fsicas: a flexible cantilever in confined axial flow (bulk-flow model on CasADi).

Data flow: Scene (what) -> build_model (CasADi functions) -> analyses -> results.
The wings (``fsicas.model``, ``fsicas.linear``, ``fsicas.cycles``, ``fsicas.timedomain``,
``fsicas.plots``) hold the rest of the public API, each in its ``__all__``.

The names below are loaded on first use (PEP 562), so ``import fsicas`` is quick and a
command pays only for the wings it uses.
"""
from __future__ import annotations

import importlib
import importlib.util

#: Each public name and the wing it comes from.
_WINGS = {
    ".provenance": ("__version__",),
    ".cycles": ("CollocationImpactSettings", "CycleBranch", "CyclePoint", "CycleSettings",
                "ImpactBranch", "ImpactPoint", "ImpactSettings", "StartCycle",
                "cycle_branch", "impacting_cycles", "scene_diagram"),
    ".linear": ("CriticalVelocityError", "HopfPoint", "LinearStability", "StabilityBoundary",
                "SteadyState", "SteadyStateError", "critical_velocity", "design_for_flow",
                "hopf_points", "linear_stability", "onset_sensitivity", "palate_sensitivity",
                "stability_boundary", "steady_state", "straight_pressure_drop"),
    ".model": ("FlowFields", "ModalBasis", "Model", "build_model", "clamped_free_betas",
               "clamped_free_modes", "flow_fields", "parameter_names"),
    ".physical": ("Flow", "Physical", "load_physical", "parse_flow", "preset_names"),
    ".profile": ("Profile",),
    ".scene": ("Scene", "load_scene"),
    ".timedomain": ("Criteria", "MapResult", "Outcome", "PressureSchedule", "Run",
                    "Trajectory", "classify", "energy_balance", "impact_map", "run_case",
                    "simulate"),
    ".units": ("Scales", "friction_from_reynolds"),
}
_HOME = {name: wing for wing, names in _WINGS.items() for name in names}

__all__ = list(_HOME)


def __getattr__(name: str):
    """Load a public name from its wing, or a wing itself (``fsicas.plots``), on first
    use, and keep it."""
    if name in _HOME:
        value = getattr(importlib.import_module(_HOME[name], __name__), name)
    elif importlib.util.find_spec(f"{__name__}.{name}") is not None:
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module 'fsicas' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
