"""Write a grounded problem back as PDDL, with another start state or goal.

Backends that run an external planner (pyperplan, clingo) and the plan validator need
the problem as text for each query; this writes it from the parsed problem's objects,
its static facts and the query's fluent atoms.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from gdq_pddl.planning.base import PlanningProblem, State


def write_problem(problem: PlanningProblem, start: State, goal: State) -> str:
    """PDDL problem text for ``problem`` from ``start`` to ``goal`` (atoms as strings)."""
    by_type: dict[str, list[str]] = {}
    for obj, typ in problem.problem.objects.items():
        if obj not in problem.domain.constants:
            by_type.setdefault(typ, []).append(obj)
    objects = "\n".join(f"    {' '.join(objs)} - {typ}" for typ, objs in by_type.items())
    init = sorted(problem.task.statics | set(start))
    goal_text = " ".join(sorted(goal))
    return (f"(define (problem {problem.problem.name})\n"
            f"  (:domain {problem.domain.name})\n"
            f"  (:objects\n{objects})\n"
            "  (:init\n" + "\n".join(f"    {a}" for a in init) + ")\n"
            f"  (:goal (and {goal_text})))\n")
