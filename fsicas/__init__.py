"""fsicas: a flexible cantilever in confined axial flow (bulk-flow model on CasADi).

Data flow: Scene (what) -> build_model (CasADi functions) -> analyses -> results.
"""
__version__ = "0.1.0"

from .model.beam import ModalBasis, clamped_free_betas, clamped_free_modes
from .profile import Profile
from .model.fields import FlowFields, flow_fields
from .model.assembly import Model, build_model, parameter_names
from .scene import Scene, load_scene
from .linear.steady import SteadyState, SteadyStateError, steady_state, straight_pressure_drop
from .units import Scales, friction_from_reynolds
from .linear.stability import LinearStability, linear_stability
from .linear.hopf import CriticalVelocityError, HopfPoint, critical_velocity, hopf_points
from .linear.boundary import StabilityBoundary, stability_boundary

__all__ = [
    "ModalBasis", "clamped_free_betas", "clamped_free_modes", "Profile", "FlowFields",
    "flow_fields", "Model", "build_model", "parameter_names", "Scene", "load_scene",
    "SteadyState", "SteadyStateError", "steady_state", "straight_pressure_drop", "Scales",
    "friction_from_reynolds", "LinearStability", "linear_stability", "CriticalVelocityError",
    "HopfPoint", "critical_velocity", "hopf_points", "StabilityBoundary", "stability_boundary",
]
