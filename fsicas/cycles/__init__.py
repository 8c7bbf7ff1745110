"""The cycles wing: flutter limit cycles continued in U* by collocation up to the first
wall contact, and on through contact into the impacting regime (``impacting_cycles``:
by adaptive collocation of the smoothed contact law, its folds, period doublings,
Neimark-Sacker and branch points located, or by multiple shooting; from the scene alone,
a contact-free branch or one cycle), the period-doubled and symmetry-broken branches
switched onto; and the curves of special cycles in (M*, U*): grazing (first contact) and
fold of cycles, also from the generalized Hopf points of the boundary; the bifurcation
diagram of a scene over U* (``scene_diagram``) and the codimension-two picture over a
window of M* (``window_diagram``)."""

from .bautin import (SwitchedCurve, fold_curves_from_bautin, switched_curves,
                     torus_curves_from_double_hopf)
from .collocation import CycleBranch, CyclePoint, CycleSettings, cycle_branch
from .curves import (CurveMap, CurvePoint, CurveSettings, CycleCurve, cycle_curves, curve_seeds,
                     fold_curves, grazing_curve)
from .impacting import (ImpactBranch, ImpactPoint, ImpactSettings, cycle_from_trajectory,
                        pre_contact_start)
from .branch_switching import period_doubled_branch, symmetry_broken_branch
from .impacting_collocation import (CollocatedImpactBranch, CollocatedImpactPoint,
                                    CollocationImpactSettings, impacting_collocation_problem)
from .impacting_routes import ImpactMethod, StartCycle, impacting_cycles, impacting_start
from .diagram import DiagramBranch, DiagramSettings, SceneDiagram, scene_diagram
from .window import WindowDiagram, window_diagram

__all__ = ["CycleBranch", "CyclePoint", "CycleSettings", "cycle_branch", "ImpactBranch",
           "ImpactPoint", "ImpactSettings", "cycle_from_trajectory", "pre_contact_start",
           "CollocatedImpactBranch", "CollocatedImpactPoint", "CollocationImpactSettings",
           "impacting_collocation_problem", "period_doubled_branch", "symmetry_broken_branch",
           "ImpactMethod", "StartCycle", "impacting_cycles", "impacting_start",
           "CurveMap", "CurvePoint", "CurveSettings",
           "CycleCurve", "cycle_curves", "curve_seeds", "fold_curves", "grazing_curve",
           "SwitchedCurve", "fold_curves_from_bautin", "torus_curves_from_double_hopf",
           "switched_curves", "DiagramBranch", "DiagramSettings", "SceneDiagram",
           "scene_diagram", "WindowDiagram", "window_diagram"]
