"""What a learner is told about a task: start, goal states and the planner's plans.

:func:`task_context` is the last step of the one pipeline: the :class:`TaskContext` of any
:class:`Instance`, a PDDL problem (:class:`~gdq_pddl.envs.pddl_env.PDDLInstance`: the
learner's states are its reachable states) or a world's task seen through the office's map
(:class:`~gdq_pddl.envs.office.OfficeInstance`: the learner's 31 states). What differs
between them, each instance says through :class:`Instance`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import MISSING, dataclass, replace
from functools import partial
from typing import Any, Protocol

import numpy as np

from gdq_pddl.abstraction import PlanTable
from gdq_pddl.abstraction.prior import PriorModel, prior_rewards
from gdq_pddl.abstraction.table import pack_plans
from gdq_pddl.envs.office import TOLERANT_KINDS, OfficeInstance
from gdq_pddl.envs.solve import expected_costs
from gdq_pddl.envs.step import ModelArrays
from gdq_pddl.errors import ConfigError, PlanningError
from gdq_pddl.learners.tables import table_bytes
from gdq_pddl.limits import MAX_TOLERANCE, check_real, human_bytes, physical_memory
from gdq_pddl.world_types import Task, World


class Instance(Protocol):
    """What :func:`task_context` reads of an instance, in the learner's states and actions
    (the image of its observation map): ``columns`` the actions each state offers
    (:attr:`TaskContext.columns`); ``learner_goal`` is bool[n_states];
    ``max_successors`` bounds the distinct next learner states of a pair in the true
    model; ``source`` is the file named when the learners' tables would not fit."""

    name: str
    source: str
    n_states: int
    n_actions: int
    columns: np.ndarray | None
    learner_start: int
    learner_goal: np.ndarray
    r_max: float
    max_successors: int
    prior: PriorModel

    def plan_table(self, planner: str = "graph", tolerance: float = 0.0,
                   kind: str = "all") -> PlanTable: ...


class BuiltWhenRead:
    """A field of :class:`TaskContext` that may be given as a function of no arguments,
    called when the field is first read (a plan table is a planner's run, which a learner
    that reads no plans never pays for); ``default`` as a dataclass field's."""

    def __init__(self, default: Any = MISSING) -> None:
        self.default = default

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, context: Any, owner: type | None = None) -> Any:
        if context is None:  # the dataclass asks for the default
            if self.default is MISSING:
                raise AttributeError(self.name)
            return self.default
        value = context.__dict__[self.name]
        if callable(value):
            value = context.__dict__[self.name] = value()
        return value

    def __set__(self, context: Any, value: Any) -> None:
        context.__dict__[self.name] = value

    @staticmethod
    def built(context: Any, name: str) -> bool:
        """Whether field ``name`` of ``context`` holds its value (was given or read)."""
        return not callable(vars(context).get(name))


@dataclass(frozen=True, eq=False)
class TaskContext:
    """One task as the learners see it.

    ``plans`` (tolerance 0: every shortest plan from every learner state) is GDQ's H;
    ``darling_plans`` (plans up to ``(1 + darling_tolerance)`` x the shortest) defines
    DARLING's allowed actions. Either may be empty (a planner that found nothing), and
    either may be given as a function that makes it, called when it is first read
    (:class:`BuiltWhenRead`: :func:`task_context` plans only for a learner that reads the
    plans).
    """

    s0: int
    """Learner state at the start of every episode."""
    goal: np.ndarray
    """bool[n_states]: the learner states that end an episode with success."""
    plans: PlanTable = BuiltWhenRead()  # type: ignore[assignment]
    """Shortest plans from every learner state to the goal (tolerance 0)."""
    r_max: float
    """The world's success reward (failure is -r_max)."""
    darling_plans: PlanTable | None = BuiltWhenRead(None)  # type: ignore[assignment]
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
    columns: np.ndarray | None = None
    """int64[n_states, n_actions]: the env action of each column of a state's row in the
    learner's tables, the plans and the prior (a PDDL problem: the ground actions
    applicable in the state, -1 padding the row to the longest); None: column ``j`` is
    action ``j`` in every state (the office's learner actions)."""
    n_ground_actions: int | None = None
    """The env's number of actions where :attr:`columns` is given."""
    own_scale: bool = False
    """Returns are on the problem's own reward scale (an IPPC file's rewards): a stuck or
    late end costs no -r_max (:attr:`~gdq_pddl.learners.tables.Params.own_scale`)."""
    step_limit: int | None = None
    """The env's step limit where :attr:`own_scale` (GDQ's prior caps its flat step cost
    by ``r_max / step_limit`` there)."""
    prior_reward: np.ndarray | None = None
    """float64[n_states, n_actions], only where :attr:`own_scale`: the most the problem's
    file pays for a trial of each pair (its outcomes' largest reward less the action's
    mean cost, :func:`~gdq_pddl.abstraction.prior.prior_rewards`; reaching the goal pays
    ``r_max`` besides), which GDQ's prior pays besides its flat step cost. None: the flat
    cost alone."""
    exact_knowledge: bool = False
    """The knowledge is reality's own actions and outcomes: a PPDDL domain (a dynamics
    file may add only a step limit and costs), whose planner and prior read the actions
    and outcomes the env samples, leaving their probabilities and costs to learn. False
    where reality may differ (the office, a STRIPS domain with a dynamics file); GDQ
    then tries untried actions (:attr:`~gdq_pddl.learners.config.GDQConfig.explore_all`)."""
    identity: Callable[[], dict[str, str]] | None = None
    """What the task is, said now (the instance's ``identity``:
    :mod:`~gdq_pddl.envs.identity`): what :func:`~gdq_pddl.learners.saving.save_learner`
    records and :func:`~gdq_pddl.learners.saving.load_learner` compares. A call, since a
    problem explored online numbers more states as its episodes reach them. None: not
    known (a context made by hand), nothing is compared."""

    horizon: int | None = None
    """The env's step limit (actions per episode at most): how far from the goal the
    knowledge-shaped learners put a state the knowledge reaches no goal from
    (:func:`~gdq_pddl.learners.shaping.goal_distances`). None: not known (the number of
    states is used)."""
    determinisation: str | None = None
    """The determinisation the planner and the prior read a PPDDL problem by
    (``"all-outcomes"``, ``"most-likely"``); None where there is no choice (STRIPS, the
    office)."""
    successors_grow: bool = False
    """The true model's next states of a pair are more than any capacity could list (a
    problem with factored actions, explored online: :attr:`max_successors` is a start):
    the model-based learners double a pair's slots when it meets one more. False: a
    transition past :attr:`max_successors` is an error."""

    @property
    def n_env_actions(self) -> int:
        """The env's number of actions (its ``action_space.n``)."""
        return self.n_actions if self.n_ground_actions is None else self.n_ground_actions

    @property
    def n_states(self) -> int:
        """Number of learner states (observations)."""
        return len(self.goal)

    @property
    def n_actions(self) -> int:
        """Columns of a state's row in the learner's tables (the number of learner
        actions where :attr:`columns` is None): the plans' width, or while they are not
        made, the columns' or the prior's."""
        if not BuiltWhenRead.built(self, "plans"):
            for given in (self.columns, getattr(self.prior, "next_state", None)):
                if isinstance(given, np.ndarray) and given.ndim == 2:
                    return int(given.shape[1])
        return int(getattr(self.plans.first_actions, "shape", (0, 0))[1])

    @property
    def live(self) -> np.ndarray:
        """bool[n_states, n_actions]: the columns that are actions (not padding)."""
        if self.columns is None:
            return np.ones((self.n_states, self.n_actions), dtype=np.bool_)
        return self.columns >= 0

    def action_of(self, s: int, column: int) -> int:
        """The env action of ``column`` in learner state ``s``."""
        return column if self.columns is None else int(self.columns[s, column])

    def column_of(self, s: int, action: int) -> int:
        """The column of env action ``action`` in learner state ``s`` (-1: not offered)."""
        if self.columns is None:
            return action
        hits = np.flatnonzero(self.columns[s] == action)
        return int(hits[0]) if len(hits) else -1


def row_context(context: TaskContext, rows: np.ndarray) -> TaskContext:
    """``context`` restricted to the states ``rows`` (in that order): what the learners'
    mask hooks read, so a problem explored online remakes only the rows it changed."""
    def plans(name: str) -> PlanTable | None:
        table = getattr(context, name)
        return None if table is None else PlanTable(table.first_actions[rows],
                                                    table.length[rows], table.plans)

    prior = context.prior
    return replace(
        context, s0=0, goal=context.goal[rows], plans=partial(plans, "plans"),
        darling_plans=partial(plans, "darling_plans"),
        prior=None if prior is None else prior.rows(rows),
        columns=None if context.columns is None else context.columns[rows],
        prior_reward=None if context.prior_reward is None else context.prior_reward[rows])


def empty_plan_table(n_states: int, n_actions: int) -> PlanTable:
    """A plan table with no plan at all (what a planner that finds nothing yields)."""
    return pack_plans(n_actions, [[] for _ in range(n_states)],
                      np.full(n_states, -1, dtype=np.int64), False)


MAX_TABLE_BYTES: int | None = None
"""A learner keeps arrays per (state, action) pair, with ``max_successors`` successor
slots each (:func:`gdq_pddl.learners.tables.table_bytes`, an upper bound: most of them are
never written); a task whose tables would exceed this many bytes is refused with a clear
message instead of exhausting memory. None (the default): the machine's memory
(:func:`~gdq_pddl.limits.physical_memory`), so a problem the state enumeration's budget
lets through is not stopped here by a fixed figure."""


def task_context(instance: Instance, planner: str = "graph", darling_tolerance: float = 0.3,
                 darling_kind: str = "all") -> TaskContext:
    """The :class:`TaskContext` of an instance of the one pipeline: plans by ``planner``
    (its shortest, and DARLING's within ``darling_tolerance``, built as ``darling_kind``
    says: :data:`~gdq_pddl.envs.office.TOLERANT_KINDS`), made when first read; the
    tolerance and kind are checked here, so a bad one is refused even by a run whose
    learners never read DARLING's plans."""
    check_real("darling_tolerance", darling_tolerance, 0.0, MAX_TOLERANCE)
    if darling_kind not in TOLERANT_KINDS:
        raise ConfigError(f"unknown plan table kind {darling_kind!r} (known: "
                          f"{', '.join(TOLERANT_KINDS)})")
    columns = getattr(instance, "columns", None)
    n_s, k = instance.n_states, instance.max_successors
    n_a = instance.n_actions if columns is None else columns.shape[1]
    limit = physical_memory() if MAX_TABLE_BYTES is None else MAX_TABLE_BYTES
    if table_bytes(n_s, n_a, k) > limit:
        raise PlanningError(f"{instance.source}: {n_s} reachable states x {n_a} actions "
                            f"(up to {k} successors each): the learners' tables "
                            f"would need {human_bytes(table_bytes(n_s, n_a, k))}, more than "
                            f"{human_bytes(limit)} (this machine's memory, or "
                            "gdq_pddl.learners.context.MAX_TABLE_BYTES); make the problem "
                            "smaller")
    return TaskContext(
        s0=instance.learner_start, goal=instance.learner_goal,
        plans=partial(instance.plan_table, planner, 0.0), r_max=instance.r_max,
        darling_plans=partial(instance.plan_table, planner, darling_tolerance, darling_kind),
        darling_tolerance=float(darling_tolerance), name=instance.name, max_successors=k,
        successors_grow=bool(getattr(instance, "successors_grow", False)),
        prior=instance.prior, columns=columns,
        n_ground_actions=None if columns is None else instance.n_actions,
        exact_knowledge=bool(getattr(instance, "ppddl", False)),
        identity=getattr(instance, "identity", None),
        horizon=_horizon(instance), determinisation=_determinisation(instance),
        **({"own_scale": True, "step_limit": int(instance.model.step_limit),
            "prior_reward": own_prior_rewards(instance)}
           if getattr(instance, "reward_scale", "goal") == "problem" else {}))


def _horizon(instance: Instance) -> int | None:
    """The env's step limit of ``instance`` (its dynamics', or its world's), or None."""
    for owner in ("dynamics", "world"):
        limit = getattr(getattr(instance, owner, None), "step_limit", None)
        if isinstance(limit, int | np.integer) and limit > 0:
            return int(limit)
    return None


def _determinisation(instance: Instance) -> str | None:
    """The determinisation of a PPDDL instance's knowledge, or None."""
    if not getattr(instance, "ppddl", False):
        return None
    found = getattr(instance, "determinisation", None)
    return found if isinstance(found, str) else None


def own_prior_rewards(instance: Instance) -> np.ndarray:
    """:attr:`TaskContext.prior_reward` of an instance on its problem's own reward scale:
    its own (a problem explored online fills them in as it finds states), else from its
    true model (:func:`file_prior_rewards`)."""
    own = getattr(instance, "prior_reward", None)
    return own if own is not None else file_prior_rewards(instance.model, instance.prior)


def file_prior_rewards(model: ModelArrays, prior: PriorModel) -> np.ndarray:
    """:attr:`TaskContext.prior_reward` of a PDDL problem on its own reward scale, from
    its true model (whose full states are the learner's states and whose columns are the
    prior's)."""
    n_states, width = prior.next_state.shape
    if not np.array_equal(model.obs_of, np.arange(n_states)) or \
            model.acts.shape != (n_states, width):
        raise PlanningError("the file's rewards reach GDQ's prior only where the learner's "
                            "states and columns are the true model's (a PDDL problem)")
    live = model.acts >= 0
    pair_cost = np.where(live, expected_costs(model)[np.where(live, model.acts, 0)], 0.0)
    gain = model.gain if len(model.gain) == len(model.prob) else np.zeros(len(model.prob))
    return prior_rewards(model.ptr, model.stuck, gain, pair_cost)


pddl_task_context = task_context
"""The name examples and tests use for a PDDL problem's context."""


def office_task_context(world: World, task: Task | str, planner: str = "graph",
                        darling_tolerance: float = 0.3, darling_kind: str = "all") -> TaskContext:
    """:func:`task_context` of ``task`` (a Task or a task name) of an office world."""
    if not isinstance(task, Task):
        task = world.task(task)  # a name; anything else is refused there
    return task_context(OfficeInstance(world, task), planner, darling_tolerance, darling_kind)
