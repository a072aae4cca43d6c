"""The mapping O between the planner's vocabulary (PDDL atoms, ground actions) and the
learner's (state and action indices), and the :class:`PlanTable` learners consume: the
plans from every learner state to the goal as index arrays. A plan pair that O cannot
map is an :class:`~gdq_pddl.errors.AbstractionError`, never a silent skip.
"""

from gdq_pddl.abstraction.office import OfficeAbstraction
from gdq_pddl.abstraction.table import Abstraction, PlanTable, build_plan_table

__all__ = ["Abstraction", "OfficeAbstraction", "PlanTable", "build_plan_table"]
