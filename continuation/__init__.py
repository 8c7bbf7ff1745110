"""Generic continuation and bifurcation analysis of M(x,p) xdot = F(x,p) on CasADi.

Public API (everything else is private)::

    continuation(problem, algorithm=PALC(), settings=ContinuationSettings(), *,
                 events=(), record=None, stop=None) -> Branch
    Event(name, function, terminal=False)     # function(problem, X) -> float
    Status                                    # Literal type of Branch.status
    EquilibriumProblem(F, x0, params, active, *, M=None)
    HopfCurveProblem(vf, x, params, omega, free) / .from_point(problem, point, second)
    FoldCurveProblem(vf, x, params, free) / .from_point(problem, point, second)
        # special points on them, coefficients in point.data: 'gh' (l1, l2), 'hh' (omega1,
        # omega2, p11..p22, theta, delta, simple, stable_torus), 'zh' (B, C, D_re, D_im,
        # s, theta), 'bt' (a, b)
    VectorField(F, M, par_names, *, mass_action, jacobian, mass_action_jacobian)
    Lifted(D, P, L, A)                        # a matrix A(p) + P D(x, p) L (Galerkin structure)
    first_lyapunov(vf, x, p, omega)
    CycleProblem(F, orbit, period, params, active, *, M=None, settings=CollocationSettings())
    cycle_from_hopf(problem, hopf_point, *, dp=1e-3, settings=None, active=None) -> CycleProblem
        # also from any point of a HopfCurveProblem's curve (active: one of its two)
    lpc_from_gh(hopf_curve, gh_point, *, epsilon=1e-2, active=None, settings=None)
        -> CycleCurveProblem   # fold-of-cycles curve born at a generalized Hopf point
    ns_from_hh(hopf_curve, hh_point, *, epsilon=1e-2, active=None, settings=None)
        -> CycleCurveProblem   # torus curve of the curve's cycles born at a double Hopf point
    ns_from_zh(hopf_curve, zh_point, *, epsilon=1e-2, active=None, settings=None)
        -> CycleCurveProblem   # ... and at a zero-Hopf point (where s theta < 0)
    cycle_from_pd(cycle_problem, pd_point, *, amplitude=1e-2, settings=None) -> CycleProblem
    cycle_from_bp(cycle_problem, bp_point, *, amplitude=1e-2) -> CycleProblem   # pitchfork
    equilibrium_from_bp(problem, bp_point, *, amplitude=1e-2) -> EquilibriumProblem
        # the other branch at a transcritical or pitchfork point, by the branching equation
    CycleCurveProblem(cycle_problem, X, free, condition)   # a cycle with one more equation:
        # its curves' codimension-two points: 'cpc', 'gpd', 'ch', 'r1'..'r4', 'lppd',
        # 'lpns', 'pdns', 'nsns' (and 'lpc', 'pd', 'ns' on a grazing curve)
    locate_cycle(cycle_problem, X, condition) -> (problem, NewtonResult)   # curve / located
    Extremum(rows, offset, level), CycleFold(), PeriodDoubling(), NeimarkSacker()   # conditions
    locate_symmetry_breaking(cycle_problem, X, symmetry, shift=0.5) -> (problem, NewtonResult)
    symmetric_multipliers(cycle_problem, X, symmetry, shift=0.5) -> (trivial, rest)
    keeps_symmetry(cycle_problem, X, symmetry, shift=0.5) -> bool   # what those two accept
    ShootingProblem(F, orbit, period, params, active, *, M=None, settings=ShootingSettings())
    bifurcation_diagram(problem, settings=None, depth=2, *, cycle_settings=None,
                        collocation=None, amplitude=1e-2, dp=1e-3, switch=("bp", "hopf", "pd"))
        -> Diagram   # the branch, every branch switched onto from it, recursively
    Diagram(root, depth, skipped, warnings) / .nodes() / .save(path) / Diagram.load(path)
    DiagramNode(branch, birth, children), Birth(kind, point, side, params)
    Branch, SpecialPoint, ContinuationIterator, PALC, ContinuationSettings,
    NewtonSettings, EigenSettings, CollocationSettings, ShootingSettings
    BufferedFunction(fun)                     # a CasADi Function called zero-copy on NumPy
    Problem, CompiledSystem(Y, P, D, G, name) # a new kind of problem: a Problem subclass
                                              # whose builder(vf) returns its CompiledSystem

Plotting lives in ``continuation.plotting`` (Matplotlib is imported there only).
"""

from ._casadi.lifted import Lifted
from ._casadi.symbolic import BufferedFunction, CompiledSystem
from ._casadi.vectorfield import VectorField
from ._cycles.codim2 import lpc_from_gh, ns_from_hh, ns_from_zh
from ._cycles.conditions import (Condition, CycleFold, Extremum, NeimarkSacker,
                                 PeriodDoubling)
from ._cycles.cycle_curves import CycleCurveProblem, locate_cycle
from ._cycles.cycles import CycleProblem
from ._cycles.settings import MAX_NTST, CollocationSettings, ShootingSettings
from ._cycles.shooting import ShootingProblem
from ._cycles.switching import cycle_from_bp, cycle_from_hopf, cycle_from_pd
from ._cycles.symmetric import keeps_symmetry, locate_symmetry_breaking, symmetric_multipliers
from ._diagram.diagram import Birth, Diagram, DiagramNode, bifurcation_diagram
from ._driver.branch import Branch, SpecialPoint, Status
from ._driver.driver import continuation, observing
from ._driver.hooks import Event
from ._driver.palc import ContinuationIterator, Step, correct
from ._driver.problem import Problem
from ._driver.settings import ContinuationSettings, EigenSettings, NewtonSettings, PALC
from ._equilibria.branching import equilibrium_from_bp
from ._equilibria.curves import FoldCurveProblem, HopfCurveProblem
from ._equilibria.equilibrium import EquilibriumProblem, hopf_point
from ._equilibria.lyapunov import first_lyapunov

__all__ = [
    "MAX_NTST", "Branch", "BufferedFunction", "CompiledSystem", "Event", "Status", "CollocationSettings", "Condition", "CycleCurveProblem",
    "CycleFold", "Extremum", "NeimarkSacker", "PeriodDoubling", "locate_cycle", "ContinuationIterator", "ContinuationSettings",
    "CycleProblem", "EigenSettings", "ShootingProblem", "ShootingSettings", "cycle_from_hopf",
    "cycle_from_bp", "cycle_from_pd", "lpc_from_gh", "ns_from_hh", "ns_from_zh",
    "equilibrium_from_bp",
    "EquilibriumProblem", "FoldCurveProblem", "HopfCurveProblem", "Lifted", "NewtonSettings",
    "PALC", "Problem", "SpecialPoint", "Step", "VectorField", "continuation", "correct", "observing",
    "first_lyapunov", "hopf_point", "keeps_symmetry", "locate_symmetry_breaking",
    "symmetric_multipliers", "Birth", "Diagram", "DiagramNode", "bifurcation_diagram",
]
