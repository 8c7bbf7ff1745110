"""The linear wing: steady state, linear stability, the onset (Hopf points: flutter; a
real eigenvalue crossing zero: divergence, and the deflected states of a pitchfork), its
modal truncation error, the sensitivities of a flutter onset and the palate design built
on them, and the stability boundary in (M*, U*) with its stretches per branch, through the generic ``continuation``
library."""

from .boundary import BoundaryPoint, OnsetCurve, ModeSwitch, StabilityBoundary, stability_boundary
from .deflected import DeflectedBranch, deflected_branch
from .divergence import DivergencePoint
from .design import Change, Design, design_for_flow
from .elasticity import DesignError, PalateSensitivity, Sensitivity, palate_sensitivity
from .hopf import CriticalVelocityError, HopfPoint, critical_velocity, first_hopf, hopf_points
from .onset import onset_at_own_flow
from .sensitivity import OnsetSensitivity, onset_sensitivity
from .stability import LinearStability, eigenvalues, linear_stability
from .steady import SteadyState, SteadyStateError, steady_state, straight_pressure_drop
from .stretches import BranchLine, boundary_function, branch_lines

__all__ = ["BoundaryPoint", "OnsetCurve", "ModeSwitch", "StabilityBoundary", "stability_boundary",
           "BranchLine", "branch_lines", "boundary_function",
           "DeflectedBranch", "deflected_branch", "DivergencePoint", "first_hopf",
           "CriticalVelocityError", "HopfPoint", "critical_velocity", "hopf_points", "onset_at_own_flow",
           "LinearStability", "eigenvalues", "linear_stability", "SteadyState",
           "SteadyStateError", "steady_state", "straight_pressure_drop", "OnsetSensitivity",
           "onset_sensitivity", "Change", "Design", "DesignError", "PalateSensitivity", "Sensitivity",
           "design_for_flow", "palate_sensitivity"]
