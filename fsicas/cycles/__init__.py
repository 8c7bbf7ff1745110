"""The cycles wing: flutter limit cycles continued in U* by collocation up to the first
wall contact, and on through contact into the impacting regime by multiple shooting."""

from .collocation import CycleBranch, CyclePoint, CycleSettings, cycle_branch
from .impacting import (ImpactBranch, ImpactPoint, ImpactSettings, cycle_from_trajectory,
                        impacting_branch, pre_contact_start)

__all__ = ["CycleBranch", "CyclePoint", "CycleSettings", "cycle_branch", "ImpactBranch",
           "ImpactPoint", "ImpactSettings", "cycle_from_trajectory", "impacting_branch",
           "pre_contact_start"]
