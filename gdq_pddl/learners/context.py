"""What a learner is told about a task: start, goal states and the planner's plans.

:func:`task_context` is the last step of the one pipeline: the :class:`TaskContext` of an
instance, a PDDL problem (:class:`~gdq_pddl.envs.pddl_env.PDDLInstance`: the learner's
states are its reachable states) or a world's task seen through the office's map
(:class:`~gdq_pddl.envs.office.OfficeInstance`: the learner's 31 states).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from gdq_pddl.abstraction import OfficeAbstraction, PlanTable, build_plan_table
from gdq_pddl.abstraction.pddl import PDDLAbstraction, graph_plan_table
from gdq_pddl.abstraction.prior import PriorModel, prior_from_graph, prior_from_task
from gdq_pddl.abstraction.routes import route_plan_table
from gdq_pddl.envs.compact import CompactModel, compile_compact
from gdq_pddl.envs.office import OfficeInstance
from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.envs.solve_compact import next_states
from gdq_pddl.errors import PlanningError
from gdq_pddl.learners.tables import table_bytes
from gdq_pddl.planning import PlanningProblem, get_planner
from gdq_pddl.resources import domain_text
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import Task, World, office_problem


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
    max_successors: int | None = None
    """The most distinct next learner states any (state, action) pair can have, from the
    world's true model (:func:`successor_capacity`): how many successor slots per pair the
    model-based learners allocate. A capacity, not knowledge the learners use; None:
    every learner state (always enough, and as large as a dense model)."""
    prior: PriorModel | None = None
    """The action knowledge as a deterministic model over every learner pair (where each
    action leads if the knowledge is right; :mod:`gdq_pddl.abstraction.prior`): what
    GDQ's default variant plans on. None: not built (that variant then refuses)."""

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


def successor_capacity(model) -> int:
    """The most distinct next learner states of one (learner state, action) pair in a
    true model, at least 1: a :class:`~gdq_pddl.envs.model.ModelArrays` (exact: the
    union over the full states a learner state stands for) or a
    :class:`~gdq_pddl.envs.compact.CompactModel` (an upper bound: an outcome whose next
    position has a door other than the one acted at may show it open or closed; a pair
    with no outcome stays put). Cached per model."""
    hit = _CAPACITY.get(id(model.ptr))
    if hit is not None and hit[0]() is model.ptr:
        return hit[1]
    n_pairs = len(model.ptr) - 1
    pair = np.repeat(np.arange(n_pairs, dtype=np.int64), np.diff(model.ptr))
    if isinstance(model, CompactModel):
        n_states = len(model.pos_of_state)
        first, second = next_states(model)  # the two door states an outcome may show
        keys = np.concatenate([pair * n_states + first, pair * n_states + second])
    else:
        n_states = int(model.obs_of.max()) + 1
        learner_pair = model.obs_of[pair // model.n_actions] * model.n_actions + \
            pair % model.n_actions
        keys = learner_pair * n_states + model.obs_of[model.next]
    per_pair = np.bincount(np.unique(keys) // n_states) if len(keys) else np.zeros(1)
    capacity = max(1, int(per_pair.max()))
    _CAPACITY[id(model.ptr)] = (weakref.ref(model.ptr), capacity)
    return capacity


_CAPACITY: dict[int, tuple[weakref.ref, int]] = {}


def office_successor_capacity(world: World) -> int:
    """:func:`successor_capacity` of the world's compact model (learner-level, so any
    size of world), cached per world."""
    hit = _WORLD_CAPACITY.get(id(world))
    if hit is not None and hit[0]() is world:
        return hit[1]
    capacity = successor_capacity(compile_compact(world))
    _WORLD_CAPACITY[id(world)] = (weakref.ref(world), capacity)
    return capacity


_WORLD_CAPACITY: dict[int, tuple[weakref.ref, int]] = {}

_TABLES: dict[tuple, PlanTable] = {}


def _knowledge_key(world: World) -> tuple:
    """What the planner's knowledge depends on (not the dynamics' probabilities, only
    whether a door can open at all: see :func:`gdq_pddl.world.office_problem`)."""
    return (world.positions, world.edges,
            tuple((d.name, d.sides, d.success > 0) for d in world.doors))


TOLERANT_KINDS = ("all", "routes")
"""How a tolerant plan table is built: ``"all"``, every loop-free plan within the
tolerance (the planner's); ``"routes"``, every shortest plan plus one plan per door
route within the tolerance (:func:`gdq_pddl.abstraction.routes.route_plan_table`, for
buildings, where every plan is too many)."""


def office_plan_table(world: World, goal: str, planner: str = "graph",
                      tolerance: float = 0.0, kind: str = "all") -> PlanTable:
    """Plans from every learner state to ``goal``, cached per (knowledge, goal, planner,
    tolerance, kind) for the life of the process; ``kind`` as in :data:`TOLERANT_KINDS`."""
    if kind not in TOLERANT_KINDS:
        raise ValueError(f"unknown plan table kind {kind!r} (known: {', '.join(TOLERANT_KINDS)})")
    if tolerance == 0:
        kind = "all"  # the shortest plans either way
    key = (_knowledge_key(world), goal, planner, float(tolerance), kind)
    table = _TABLES.get(key)
    if table is None:
        problem = _office_planning_problem(world, goal)
        abstraction = OfficeAbstraction(world)
        if kind == "routes":
            spaces = abstraction.spaces
            crossings = {spaces.action("gothrough", p) for p in world.door_at}
            table = route_plan_table(abstraction, problem,
                                     office_plan_table(world, goal, planner, 0.0),
                                     tolerance, crossings.__contains__)
        else:
            table = build_plan_table(abstraction, problem, get_planner(planner),
                                     abstraction.goal(goal), tolerance)
        _TABLES[key] = table
    return table


def _office_planning_problem(world: World, goal: str):
    """The knowledge of ``world`` as a :class:`~gdq_pddl.planning.PlanningProblem` with
    goal ``goal`` (and any other position as its start)."""
    start = next(p for p in world.positions if p != goal)
    return PlanningProblem.from_texts(
        domain_text(), office_problem(world, Task("plan-table", start, goal)))


_PRIORS: dict[tuple, PriorModel] = {}


def office_prior(world: World) -> PriorModel:
    """The prior model of an office world's knowledge (goal-independent), cached per
    knowledge for the life of the process."""
    key = _knowledge_key(world)
    prior = _PRIORS.get(key)
    if prior is None:
        task = _office_planning_problem(world, world.positions[-1]).task
        abstraction = OfficeAbstraction(world)
        prior = _PRIORS[key] = prior_from_task(abstraction, task,
                                               abstraction.mask_reader(task))
    return prior


def office_task_context(world: World, task: Task | str, planner: str = "graph",
                        darling_tolerance: float = 0.3, darling_kind: str = "all") -> TaskContext:
    """The :class:`TaskContext` of ``task`` (a Task or a task name) in an office world;
    ``darling_kind`` says how its tolerant table is built (:data:`TOLERANT_KINDS`)."""
    if not isinstance(task, Task):
        task = world.task(task)  # a name; anything else is refused there
    spaces = LearnerSpaces(world)
    goal = np.array([p == task.goal for p, _ in spaces.states], dtype=np.bool_)
    return TaskContext(
        s0=spaces.state(task.start), goal=goal,
        plans=office_plan_table(world, task.goal, planner, 0.0), r_max=float(world.r_max),
        darling_plans=office_plan_table(world, task.goal, planner, darling_tolerance,
                                        darling_kind),
        darling_tolerance=float(darling_tolerance), name=task.name,
        max_successors=office_successor_capacity(world), prior=office_prior(world))


_PDDL_TABLES: dict[tuple, tuple[object, PlanTable]] = {}

MAX_TABLE_BYTES = 16_000_000_000
"""A learner keeps arrays per (state, action) pair, with ``max_successors`` successor
slots each (:func:`gdq_pddl.learners.tables.table_bytes`); a PDDL task whose tables would
exceed this is refused with a clear message instead of exhausting memory."""


def pddl_plan_table(instance, planner: str = "graph", tolerance: float = 0.0) -> PlanTable:
    """Plans from every reachable state of a :class:`~gdq_pddl.envs.pddl_env.PDDLInstance`.

    The ``graph`` planner's table comes from one backward BFS over the state graph
    (:func:`~gdq_pddl.abstraction.pddl.graph_plan_table`); any other backend is asked
    once per state. Cached per (instance, planner, tolerance).
    """
    key = (id(instance), planner, float(tolerance))
    hit = _PDDL_TABLES.get(key)
    if hit is not None and hit[0] is instance:
        return hit[1]
    if planner == "graph":
        table = graph_plan_table(instance.graph, tolerance)
    else:
        abstraction = PDDLAbstraction(instance.graph)
        table = build_plan_table(abstraction, instance.problem, get_planner(planner),
                                 abstraction.goal(), tolerance)
    _PDDL_TABLES[key] = (instance, table)
    return table


def pddl_task_context(instance, planner: str = "graph",
                      darling_tolerance: float = 0.3) -> TaskContext:
    """The :class:`TaskContext` of a PDDL problem: learner states are its reachable states
    (0 is the initial one), actions its ground actions, goal where the problem's goal holds."""
    n_s, n_a = instance.n_states, instance.n_actions
    k = successor_capacity(instance.model)
    if table_bytes(n_s, n_a, k) > MAX_TABLE_BYTES:
        raise PlanningError(f"{instance.problem.problem.source}: {n_s} reachable states x "
                            f"{n_a} ground actions (up to {k} successors each): the "
                            f"learners' tables would need "
                            f"{table_bytes(n_s, n_a, k) / 1e9:.0f} GB; make the problem "
                            f"smaller")
    return TaskContext(
        s0=0, goal=np.asarray(instance.graph.is_goal, dtype=np.bool_),
        plans=pddl_plan_table(instance, planner, 0.0), r_max=float(instance.dynamics.r_max),
        darling_plans=pddl_plan_table(instance, planner, darling_tolerance),
        darling_tolerance=float(darling_tolerance), name=instance.name, max_successors=k,
        prior=prior_from_graph(instance.graph))


def shortest_plans(instance: PDDLInstance | OfficeInstance,
                   planner: str = "graph") -> PlanTable:
    """The shortest plans of every learner state of an instance (cached)."""
    if isinstance(instance, OfficeInstance):
        return office_plan_table(instance.world, instance.task.goal, planner, 0.0)
    return pddl_plan_table(instance, planner, 0.0)


def task_context(instance: PDDLInstance | OfficeInstance, planner: str = "graph",
                 darling_tolerance: float = 0.3, knowledge: World | None = None,
                 darling_kind: str = "all") -> TaskContext:
    """The :class:`TaskContext` of an instance of the one pipeline. A world's task is
    planned on ``knowledge`` (another world's building: knowledge that differs from
    reality on purpose; None: the instance's own); ``darling_kind`` as in
    :func:`office_task_context`."""
    if isinstance(instance, OfficeInstance):
        return office_task_context(knowledge or instance.world, instance.task, planner,
                                   darling_tolerance, darling_kind)
    return pddl_task_context(instance, planner, darling_tolerance)
