"""What a learner is told about a task: start, goal states and the planner's plans."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gdq_pddl.abstraction import OfficeAbstraction, PlanTable, build_plan_table
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import Task, World


@dataclass(frozen=True, eq=False)
class TaskContext:
    """One task as the learners see it.

    ``plans`` (tolerance 0: every shortest plan from every learner state) is GDQ's H;
    ``darling_plans`` (plans up to ``(1 + darling_tolerance)`` x the shortest) defines
    DARLING's allowed actions. Either may be empty (a planner that found nothing).
    """

    s0: int
    """Learner state at the start of every episode."""
    goal: np.ndarray
    """bool[n_states]: the learner states that end an episode with success."""
    plans: PlanTable
    """Shortest plans from every learner state to the goal (tolerance 0)."""
    r_max: float
    """The world's success reward (failure is -r_max)."""
    darling_plans: PlanTable | None = None
    """Plans within the DARLING tolerance, or None if not built."""
    darling_tolerance: float | None = None
    """The tolerance ``darling_plans`` was built with."""
    name: str = ""
    """Human label, e.g. ``"C"``."""

    @property
    def n_states(self) -> int:
        return len(self.goal)

    @property
    def n_actions(self) -> int:
        return int(self.plans.first_actions.shape[1])


def empty_plan_table(n_states: int, n_actions: int) -> PlanTable:
    """A plan table with no plan at all (what a planner that finds nothing yields)."""
    return PlanTable(np.zeros(n_states + 1, dtype=np.int64), np.zeros(1, dtype=np.int64),
                     np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64),
                     np.zeros((n_states, n_actions), dtype=np.bool_),
                     np.full(n_states, -1, dtype=np.int64))


def _domain_text() -> str:
    from gdq_pddl import resources

    try:
        return resources.domain_text()
    except FileNotFoundError:
        # A source checkout: the domain lives at the repository root and is only
        # copied into gdq_pddl/data/ when the wheel is built.
        import gdq_pddl

        return (Path(gdq_pddl.__file__).resolve().parents[1] / "domains" /
                "office.pddl").read_text(encoding="utf-8")


_TABLES: dict[tuple, PlanTable] = {}


def _knowledge_key(world: World) -> tuple:
    """What the planner's knowledge depends on (not the dynamics' probabilities, only
    whether a door can open at all: see :func:`gdq_pddl.pddl.office.office_problem`)."""
    return (world.positions, world.edges,
            tuple((d.name, d.sides, d.success > 0) for d in world.doors))


def office_plan_table(world: World, goal: str, planner: str = "graph",
                      tolerance: float = 0.0) -> PlanTable:
    """Plans from every learner state to ``goal``, cached per (knowledge, goal, planner,
    tolerance) for the life of the process."""
    key = (_knowledge_key(world), goal, planner, float(tolerance))
    table = _TABLES.get(key)
    if table is None:
        from gdq_pddl.pddl.office import office_problem
        from gdq_pddl.planning import PlanningProblem, get_planner

        start = next(p for p in world.positions if p != goal)
        problem = PlanningProblem.from_texts(
            _domain_text(), office_problem(world, Task("plan-table", start, goal)))
        abstraction = OfficeAbstraction(world)
        table = build_plan_table(abstraction, problem, get_planner(planner),
                                 abstraction.goal(goal), tolerance)
        _TABLES[key] = table
    return table


def office_task_context(world: World, task: Task | str, planner: str = "graph",
                        darling_tolerance: float = 0.3) -> TaskContext:
    """The :class:`TaskContext` of ``task`` (a Task or a task name) in an office world."""
    if isinstance(task, str):
        task = world.task(task)
    spaces = LearnerSpaces(world)
    goal = np.array([p == task.goal for p, _ in spaces.states], dtype=np.bool_)
    return TaskContext(
        s0=spaces.state(task.start), goal=goal,
        plans=office_plan_table(world, task.goal, planner, 0.0), r_max=float(world.r_max),
        darling_plans=office_plan_table(world, task.goal, planner, darling_tolerance),
        darling_tolerance=float(darling_tolerance), name=task.name)


_PDDL_TABLES: dict[tuple, tuple[object, PlanTable]] = {}

MAX_MODEL_ENTRIES = 2_000_000_000
"""The learners' model is dense (states x actions x states counts); past this many
entries a PDDL task is refused with a clear message instead of exhausting memory."""


def pddl_plan_table(instance, planner: str = "graph", tolerance: float = 0.0) -> PlanTable:
    """Plans from every reachable state of a :class:`~gdq_pddl.envs.pddl_env.PDDLInstance`.

    The ``graph`` planner's table comes from one backward BFS over the state graph
    (:func:`~gdq_pddl.abstraction.pddl.graph_plan_table`); any other backend is asked
    once per state. Cached per (instance, planner, tolerance).
    """
    from gdq_pddl.abstraction.pddl import PDDLAbstraction, graph_plan_table

    key = (id(instance), planner, float(tolerance))
    hit = _PDDL_TABLES.get(key)
    if hit is not None and hit[0] is instance:
        return hit[1]
    if planner == "graph":
        table = graph_plan_table(instance.graph, tolerance)
    else:
        from gdq_pddl.planning import get_planner

        abstraction = PDDLAbstraction(instance.graph)
        table = build_plan_table(abstraction, instance.problem, get_planner(planner),
                                 abstraction.goal(), tolerance)
    _PDDL_TABLES[key] = (instance, table)
    return table


def pddl_task_context(instance, planner: str = "graph",
                      darling_tolerance: float = 0.3) -> TaskContext:
    """The :class:`TaskContext` of a PDDL problem: learner states are its reachable states
    (0 is the initial one), actions its ground actions, goal where the problem's goal holds."""
    from gdq_pddl.errors import PlanningError

    n_s, n_a = instance.n_states, instance.n_actions
    if n_s * n_s * n_a > MAX_MODEL_ENTRIES:
        raise PlanningError(f"{instance.problem.problem.source}: {n_s} reachable states x "
                            f"{n_a} ground actions: the learners' dense model would need "
                            f"{n_s * n_s * n_a * 8 / 1e9:.0f} GB; make the problem smaller")
    return TaskContext(
        s0=0, goal=np.asarray(instance.graph.is_goal, dtype=np.bool_),
        plans=pddl_plan_table(instance, planner, 0.0), r_max=float(instance.dynamics.r_max),
        darling_plans=pddl_plan_table(instance, planner, darling_tolerance),
        darling_tolerance=float(darling_tolerance), name=instance.name)
