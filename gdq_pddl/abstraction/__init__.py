"""The mapping O between the planner's vocabulary (PDDL atoms, ground actions) and the
learner's (state and action indices), and the :class:`PlanTable` of plans learners read."""

from gdq_pddl.abstraction.office import OfficeAbstraction
from gdq_pddl.abstraction.table import Abstraction, PlanTable, build_plan_table

__all__ = ["Abstraction", "OfficeAbstraction", "PlanTable", "build_plan_table"]
