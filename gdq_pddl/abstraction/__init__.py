"""The mapping O between the planner's vocabulary and the learner's, and its inverse.

The planner speaks in PDDL atoms and ground actions (``"(approach p0 p2 d1)"``); the
learner in state and action indices. :class:`Abstraction` maps one to the other: every
``(state, action)`` pair of every plan must map, and one that does not is an
:class:`~gdq_pddl.errors.AbstractionError` naming it, never a silent skip.

:class:`PlanTable` is what learners consume: for every learner state, the plans from
it to the goal as flat index arrays, built once per (goal, planner, tolerance), so that
"replan from the current state" during learning is an array lookup.
"""

from gdq_pddl.abstraction.office import OfficeAbstraction
from gdq_pddl.abstraction.table import Abstraction, PlanTable, build_plan_table

__all__ = ["Abstraction", "OfficeAbstraction", "PlanTable", "build_plan_table"]
