"""The cycles wing: flutter limit cycles continued in U* by collocation up to the first
wall contact, and on through contact into the impacting regime by multiple shooting, or by
adaptive collocation of the smoothed contact law."""

from .collocation import CycleBranch, CyclePoint, CycleSettings, cycle_branch
from .impacting import (ImpactBranch, ImpactPoint, ImpactSettings, cycle_from_trajectory,
                        impacting_branch, pre_contact_start)
from .impacting_collocation import (CollocatedImpactBranch, CollocatedImpactPoint,
                                    CollocationImpactSettings, impacting_collocation_branch,
                                    impacting_collocation_problem)

__all__ = ["CycleBranch", "CyclePoint", "CycleSettings", "cycle_branch", "ImpactBranch",
           "ImpactPoint", "ImpactSettings", "cycle_from_trajectory", "impacting_branch",
           "pre_contact_start", "CollocatedImpactBranch", "CollocatedImpactPoint",
           "CollocationImpactSettings", "impacting_collocation_branch",
           "impacting_collocation_problem"]
