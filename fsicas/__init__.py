"""fsicas: a flexible cantilever in confined axial flow (bulk-flow model on CasADi).

Data flow: Scene (what) -> build_model (CasADi functions) -> analyses -> results.
The wings (``fsicas.model``, ``fsicas.linear``, ``fsicas.cycles``, ``fsicas.timedomain``,
``fsicas.plots``) hold the rest of the public API, each in its ``__all__``.
"""
from .provenance import __version__

from .cycles import (CollocationImpactSettings, CycleBranch, CyclePoint, CycleSettings,
                     ImpactBranch, ImpactPoint, ImpactSettings, StartCycle, cycle_branch,
                     impacting_cycles)
from .linear import (CriticalVelocityError, HopfPoint, LinearStability, StabilityBoundary,
                     SteadyState, SteadyStateError, critical_velocity, design_for_flow,
                     hopf_points, linear_stability, onset_sensitivity, palate_sensitivity,
                     stability_boundary, steady_state, straight_pressure_drop)
from .model import (FlowFields, ModalBasis, Model, build_model, clamped_free_betas,
                    clamped_free_modes, flow_fields, parameter_names)
from .physical import Flow, Physical, load_physical, parse_flow, preset_names
from .profile import Profile
from .scene import Scene, load_scene
from .timedomain import (Criteria, MapResult, Outcome, PressureSchedule, Run, Trajectory,
                         classify, energy_balance, impact_map, run_case, simulate)
from .units import Scales, friction_from_reynolds

__all__ = [
    "__version__",
    "Scene", "load_scene", "Profile", "Scales", "friction_from_reynolds",
    "Physical", "Flow", "load_physical", "parse_flow", "preset_names",
    "ModalBasis", "clamped_free_betas", "clamped_free_modes", "FlowFields", "flow_fields",
    "Model", "build_model", "parameter_names",
    "SteadyState", "SteadyStateError", "steady_state", "straight_pressure_drop",
    "LinearStability", "linear_stability", "CriticalVelocityError", "HopfPoint",
    "critical_velocity", "hopf_points", "StabilityBoundary", "stability_boundary",
    "onset_sensitivity", "palate_sensitivity", "design_for_flow",
    "CycleSettings", "CyclePoint", "CycleBranch", "cycle_branch",
    "ImpactSettings", "CollocationImpactSettings", "ImpactPoint", "ImpactBranch",
    "StartCycle", "impacting_cycles",
    "PressureSchedule", "Trajectory", "simulate", "Criteria", "Outcome", "classify",
    "Run", "run_case", "MapResult", "impact_map", "energy_balance",
]
