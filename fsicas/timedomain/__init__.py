"""The time-domain wing: integration with wall impacts (IDAS, CVODES, SciPy), breathing
schedules, outcome classification, energy balance, single runs and (U*, M*) maps."""

from .breathing import PressureSchedule
from .energy import EnergyBalance, energy_balance, outlet_flow_rates
from .impact_map import MapResult, impact_map, load_points
from .integrators import Settings, Trajectory, simulate
from .outcome import Criteria, Outcome, classify
from .run import Run, run_case

__all__ = ["PressureSchedule", "EnergyBalance", "energy_balance", "outlet_flow_rates",
           "MapResult", "impact_map", "load_points", "Settings", "Trajectory", "simulate",
           "Criteria", "Outcome", "classify", "Run", "run_case"]
