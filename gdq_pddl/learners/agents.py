"""The learners behind one small interface (:class:`Learner`): :class:`QLearning`,
:class:`DynaQ`, :class:`Darling` and :class:`GDQ`, and :func:`make_learner` by the names
the command line takes. The methods check their arguments (:mod:`gdq_pddl.learners.guards`)
and call the compiled rules (:mod:`gdq_pddl.learners.rules` says which).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from gdq_pddl.abstraction import PlanTable
from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import gdq, gdq_paper, guards, learned_model, rules
from gdq_pddl.learners.config import (
    EXPLORE_ALL,
    DarlingConfig,
    DynaQConfig,
    GDQConfig,
    LearnerConfig,
    QLearningConfig,
)
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.tables import (
    BACKUP_EXPECTED,
    BACKUP_SAMPLE,
    KIND_DARLING,
    KIND_DYNAQ,
    KIND_GDQ,
    KIND_GDQ_PLANS,
    KIND_QLEARNING,
    Params,
    Plans,
    Prior,
    QTable,
    Queue,
    Tables,
    act,
    greedy,
    recompute_all_v,
)
from gdq_pddl.limits import check_count

MODEL_BASED = (KIND_DYNAQ, KIND_GDQ_PLANS, KIND_GDQ)
"""The learner kinds that record transitions in a learned model."""

_I0 = np.zeros(0, dtype=np.int64)
_F00 = np.zeros((0, 0))
_NO_PRIOR = (Prior(np.zeros((0, 0), dtype=np.int64), _I0, _I0, _I0, _I0, _I0,
                   np.zeros(1, dtype=np.int64), _F00),
             Queue(_I0, _I0, np.zeros(0), np.zeros(1, dtype=np.int64)))
"""The default GDQ's prior and queue, for the other learners (never read or written)."""

MAX_DENSE_COUNTS = 50_000_000
"""The most entries :attr:`TabularLearner.counts` builds a dense array of (400 MB)."""


def _capacity(context: TaskContext) -> int:
    """Successor slots per pair for ``context``: its ``max_successors``, or every state."""
    k = context.max_successors
    if k is None:
        return context.n_states
    check_count("TaskContext.max_successors", k)
    return min(max(1, int(k)), context.n_states)  # more than every state is never needed


@runtime_checkable
class Learner(Protocol):
    """What the episode loop needs from a learner."""

    q: np.ndarray
    """The Q table, float64[n_states, n_actions], in the env's reward units (``q[s, j]``:
    the value of the action of column ``j``, ``TaskContext.action_of(s, j)``)."""

    def act(self, state: int, rng: np.random.Generator) -> int:
        """The action index to take in learner state ``state``, drawing from ``rng``."""

    def observe(self, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
                rng: np.random.Generator) -> None:
        """Learn from one real step: ``a`` in ``s`` gave reward ``r`` and led to ``s2``."""

    def start_task(self, context: TaskContext) -> None:
        """Switch to the task ``context``, keeping what was learned."""

    def greedy_policy(self) -> np.ndarray:
        """int64[n_states]: the greedy action of each state."""


class TabularLearner:
    """Shared implementation: arrays in :class:`~gdq_pddl.learners.tables.Tables`, rules in
    :mod:`gdq_pddl.learners.rules`; ``config`` None means :attr:`config_type`'s defaults."""

    kind: int = KIND_QLEARNING
    """Which compiled rule runs after a real step (:mod:`gdq_pddl.learners.rules`)."""
    name: str = "tabular"
    """The method's name in results and plots."""
    config_type: type[LearnerConfig] = LearnerConfig
    """The config class the constructor takes."""
    config: LearnerConfig
    """The learner's settings (frozen)."""
    context: TaskContext
    """The current task (:meth:`start_task` replaces it)."""
    q: np.ndarray
    """The Q table, float64[n_states, n_actions], in the env's reward units: ``q[s, j]`` is
    the value of the action of column ``j`` of state ``s`` (:attr:`TaskContext.columns
    <gdq_pddl.learners.context.TaskContext.columns>`; the action ``j`` in the office)."""

    def __init__(self, context: TaskContext, config: LearnerConfig | None = None) -> None:
        config = self.config_type() if config is None else config
        if not isinstance(config, self.config_type):
            raise ConfigError(f"{type(self).__name__} takes a {self.config_type.__name__}, "
                              f"got {type(config).__name__}")
        guards.check_context(context)
        self.config = config
        n_s, n_a = context.n_states, context.n_actions
        k = _capacity(context)  # checked for every learner; the model-free never record
        self._model = learned_model.new_model(n_s, n_a, k if self.kind in MODEL_BASED else 0)
        self.q = np.zeros((n_s, n_a), dtype=np.float64)
        self._set_task(context)

    # -- per-learner hooks -------------------------------------------------------------
    def _allowed(self, context: TaskContext) -> np.ndarray:
        """What the max in the update and the greedy choice range over, per state."""
        return context.live

    def _guide(self, context: TaskContext, allowed: np.ndarray) -> np.ndarray:
        """What the learner may execute, per state (:mod:`~gdq_pddl.learners.tables`)."""
        return allowed

    def _plans(self, context: TaskContext) -> PlanTable:
        """H: the plans this learner backs up (GDQ may ask for plans within a tolerance)."""
        return context.plans

    def _init_task(self) -> None:
        """What happens when a task starts (after the tables are rebuilt)."""

    def _prior_arrays(self, context: TaskContext) -> tuple[Prior, Queue]:
        """The :class:`Tables` groups only the default GDQ uses (empty here)."""
        return _NO_PRIOR

    def _extra_params(self) -> dict[str, float]:
        """:class:`Params` fields beyond the shared ones (their defaults here)."""
        return {"backup": BACKUP_EXPECTED}

    # -- interface ---------------------------------------------------------------------
    def _build(self, context: TaskContext) -> tuple[Tables, Params]:
        """The tables and params for ``context`` (checked by the caller)."""
        allowed = np.ascontiguousarray(self._allowed(context), dtype=np.bool_)
        guide = np.ascontiguousarray(self._guide(context, allowed), dtype=np.bool_)
        plans = self._plans(context)
        opt_r = plans.start_pairs(context.s0)
        walked = (plans.plan_ptr, plans.pair_ptr, plans.pair_state, plans.pair_action) \
            if self.kind == KIND_GDQ_PLANS else (  # only the paper's GDQs walk plans
                np.zeros(len(allowed) + 1, dtype=np.int64), np.zeros(1, dtype=np.int64), _I0, _I0)
        table = QTable(self.q, np.zeros(len(self.q)), allowed, guide,
                       guide.sum(axis=1).astype(np.int64),
                       np.ascontiguousarray(context.goal, dtype=np.bool_),
                       context.live.sum(axis=1).astype(np.int64))
        plan_arrays = (np.ascontiguousarray(x, dtype=np.int64) for x in walked)
        tables = Tables(table, self._model, Plans(opt_r, *plan_arrays),
                        *self._prior_arrays(context))
        c = self.config
        params = Params(
            kind=int(self.kind), alpha=float(c.alpha), gamma=float(c.gamma),
            epsilon=float(c.epsilon), r_max=float(context.r_max),
            n_backups=int(getattr(c, "n_backups", 0)), m=int(getattr(c, "m", 0)),
            s0=int(context.s0), own_scale=float(context.own_scale), **self._extra_params())
        guards.check_tables(tables, params)
        return tables, params

    def start_task(self, context: TaskContext) -> None:
        """Switch to a new task, keeping what the learner has learned (``docs/learners.md``:
        the baselines keep their Q table, every GDQ reruns OptInit on its learned model)."""
        guards.check_context(context, *self.q.shape)
        k = _capacity(context)
        if self.kind in MODEL_BASED:
            self._model = learned_model.with_successor_slots(self._model, k)
        self._set_task(context)

    def _set_task(self, context: TaskContext) -> None:
        """Build the tables for ``context``, then start the task (OptInit for the GDQs)."""
        self.context = context
        self.tables, self.params = self._build(context)
        recompute_all_v(self.tables.table)
        self._init_task()

    def act(self, state: int, rng: np.random.Generator) -> int:
        """The epsilon-greedy action (the env's index) to take in learner state ``state``,
        drawing from ``rng`` (:func:`~gdq_pddl.learners.tables.act`)."""
        s = guards.check_state("state", state, len(self.q))
        guards.check_generator(rng)
        t = self.tables
        column = int(act(t.table, t.model.visits, t.prior.next_state, self.params, s, rng))
        return self.context.action_of(s, column)

    def observe(self, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
                rng: np.random.Generator) -> None:
        """Learn from one real step ``(s, a, r, s2)`` as Gymnasium's step gave it (``a``:
        the env's action index); backups draw from ``rng``
        (:func:`~gdq_pddl.learners.rules.observe`)."""
        n_s, n_a = self.q.shape
        s, s2 = guards.check_state("s", s, n_s), guards.check_state("s2", s2, n_s)
        a = self._column("a", s, a)
        r = guards.check_reward(r)
        guards.check_generator(rng)
        if not rules.observe(*self.tables, self.params, s, a, r, s2, bool(terminated),
                             bool(truncated), rng):
            raise ValueError(learned_model.OVERFLOW)

    def _column(self, name: str, s: int, a: object) -> int:
        """The column of env action ``a`` in state ``s``; refused where ``s`` does not
        offer it (a PDDL state offers its applicable ground actions)."""
        columns = self.context.columns
        if columns is None:
            return guards.check_action(name, a, self.q.shape[1])
        j = self.context.column_of(s, guards.check_action(name, a, self.context.n_env_actions))
        if j < 0:
            offered = columns[s][columns[s] >= 0].tolist()
            raise ConfigError(f"{name} = {a} is not offered in state {s}, whose applicable "
                              f"ground actions are {offered}")
        return j

    def greedy_policy(self) -> np.ndarray:
        """int64[n_states]: per state, the env action of the lowest allowed column of
        maximal Q (the lowest-index allowed action of maximal Q in the office)."""
        policy = greedy(self.tables.table, self.params)
        columns = self.context.columns
        return policy if columns is None else columns[np.arange(len(policy)), policy]

    @property
    def v(self) -> np.ndarray:
        """max_a Q(s, a) over the allowed actions, per state."""
        return self.tables.table.v

    @property
    def visits(self) -> np.ndarray:
        """Trials per (s, a) recorded in the learned model (model-based learners only)."""
        return self.tables.model.visits

    @property
    def counts(self) -> np.ndarray:
        """The learned model's transition counts C[s, a, s'] as a new dense int64 array (all
        zero for the model-free learners); refused past :data:`MAX_DENSE_COUNTS` entries
        (use :meth:`successors`)."""
        n_s, n_a = self.q.shape
        if n_s * n_a * n_s > MAX_DENSE_COUNTS:
            raise ValueError(f"a dense C[s, a, s'] of {n_s} x {n_a} x {n_s} entries is too "
                             f"large; use successors(s, a)")
        return learned_model.dense_counts(self.tables.model.slots, n_s)

    def successors(self, s: int, a: int) -> dict[int, int]:
        """``{s': count}`` of the recorded transitions of ``(s, a)`` (``a``: the env's
        action), in increasing ``s'``."""
        s = guards.check_state("s", s, self.q.shape[0])
        a = self._column("a", s, a)
        slots = self.tables.model.slots[s, a]
        slots = slots[slots != 0]
        return dict(zip((slots >> learned_model.SLOT_SHIFT).tolist(),
                        (slots & learned_model.COUNT_MASK).tolist(), strict=True))

    @property
    def nbytes(self) -> int:
        """Bytes of the learner's arrays as allocated (each once: ``guide`` is usually
        ``allowed``), more than it uses where the pages of untried pairs are never written."""
        arrays = {id(x): x for group in self.tables for x in group}
        return sum(x.nbytes for x in arrays.values())

    @property
    def max_successors(self) -> int:
        """Successor slots per pair of the learned model (0 for the model-free learners)."""
        return int(self.tables.model.slots.shape[2])

    def reserve_successors(self, k: int) -> None:
        """Make room for ``k`` distinct successors per pair (model-based learners; at most
        the learner's states), keeping the recorded transitions."""
        check_count("k", k)
        k = min(int(k), len(self.q))
        if self.kind in MODEL_BASED and k > self.max_successors:
            self._model = learned_model.with_successor_slots(self._model, k)
            self.tables = self.tables._replace(model=self._model)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.config})"


class QLearning(TabularLearner):
    """Epsilon-greedy Q-learning: the TD update on each real step, nothing else."""

    kind = KIND_QLEARNING
    name = "Q-learning"
    config_type = QLearningConfig


class DynaQ(TabularLearner):
    """Q-learning + the learned model + N expected backups per real step on uniformly
    random pairs tried more than m times (:mod:`gdq_pddl.learners.learned_model`)."""

    kind = KIND_DYNAQ
    name = "Dyna-Q"
    config_type = DynaQConfig


class Darling(TabularLearner):
    """Q-learning restricted, at every state, to the actions that start a plan within the
    length tolerance from it (every action where none does), when acting and in the max
    of the update. ``variant="code"``: as the GDQ authors' agent runs it (``docs/learners.md``)."""

    kind = KIND_DARLING
    name = "DARLING"
    config: DarlingConfig
    config_type = DarlingConfig

    def _plan_actions(self, context: TaskContext) -> np.ndarray:
        """Per state, the actions that start a plan within the tolerance (all actions
        where there is no plan)."""
        table = context.darling_plans
        if table is None:
            raise ConfigError("DARLING needs a task context with darling_plans")
        if context.darling_tolerance is not None and not np.isclose(
                context.darling_tolerance, self.config.tolerance):
            raise ConfigError(f"the context's DARLING plans use tolerance "
                              f"{context.darling_tolerance}, the config "
                              f"{self.config.tolerance}")
        return table.allowed_actions(context.live)

    def _allowed(self, context: TaskContext) -> np.ndarray:
        code = self.config.variant == "code"  # the max ranges over every action
        return super()._allowed(context) if code else self._plan_actions(context)

    def _guide(self, context: TaskContext, allowed: np.ndarray) -> np.ndarray:
        return self._plan_actions(context) if self.config.variant == "code" else allowed


def prior_step_cost(prior_cost: float, context: TaskContext) -> float:
    """The flat step cost GDQ's prior charges: ``prior_cost``, and on a problem's own
    reward scale at most ``r_max / step_limit`` (besides the file's rewards there,
    :func:`prior_reward`). There a step may cost nothing (an IPPC goal reward of 1, free
    actions): a prior that charged 1 a step would value every plan of more than one
    action below a loop of free steps, and GDQ would learn to do nothing; why it charges
    the capped cost at all: ``docs/decisions.md``, "the prior's step cost cap"."""
    if context.own_scale and context.step_limit:
        return float(min(prior_cost, context.r_max / context.step_limit))
    return float(prior_cost)


def prior_reward(context: TaskContext) -> np.ndarray:
    """``Prior.reward`` for ``context``: its :attr:`~TaskContext.prior_reward` on a
    problem's own scale, else an empty array (the prior charges a flat step cost)."""
    if context.own_scale and context.prior_reward is not None:
        return np.ascontiguousarray(context.prior_reward, dtype=np.float64)
    return _F00


def _tolerant_plans(context: TaskContext, tolerance: float) -> PlanTable:
    """The context's plans within ``tolerance`` (its shortest plans for 0)."""
    if not tolerance:
        return context.plans
    if context.darling_plans is None or context.darling_tolerance is None or \
            not np.isclose(context.darling_tolerance, tolerance):
        raise ConfigError(f"GDQ with plan_tolerance {tolerance} needs a task context whose "
                          f"tolerant plan table was built with that tolerance (it has "
                          f"{context.darling_tolerance})")
    return context.darling_plans


class GDQ(TabularLearner):
    """Guided Dyna-Q. The default (``variant="prior"``) takes the action knowledge as an
    optimistic prior over every (state, action) pair and plans on it.

    Its update rule is one module, :mod:`gdq_pddl.learners.gdq`. After each real step,
    :func:`~gdq_pddl.learners.gdq.after_step` records the step in the learned model and
    calls :func:`~gdq_pddl.learners.gdq.sweep` (prioritised sweeping), which sets each
    pair it revisits to :func:`~gdq_pddl.learners.gdq.hybrid_backup`: the pair's
    :func:`~gdq_pddl.learners.gdq.prior_backup` until tried more than ``m`` times, then
    the learned model's backup with the prior as ``prior_weight`` pseudo-trials. OptInit
    is :func:`~gdq_pddl.learners.gdq.value_iteration` on the same hybrid model.

    ``variant="literal"`` (GDQ-literal) and ``"code"`` (GDQ-code) are the paper's two
    readings, in :mod:`gdq_pddl.learners.gdq_paper`; ``docs/learners.md`` compares them.
    """

    kind = KIND_GDQ
    name = "GDQ"
    config: GDQConfig
    config_type = GDQConfig

    def __init__(self, context: TaskContext, config: GDQConfig | None = None) -> None:
        if isinstance(config, GDQConfig) and config.variant != "prior":
            self.kind = KIND_GDQ_PLANS
        super().__init__(context, config)

    @property
    def q(self) -> np.ndarray:
        """The Q table, float64[n_states, n_actions]. In the default variant an untried
        action the knowledge says does nothing is worth its prior backup, one step that
        changes nothing (``-prior_cost + gamma * v[s]``); the sweeps never read those
        entries, so they are filled in here, when the table is read."""
        if self.kind == KIND_GDQ and hasattr(self, "tables"):
            gdq.fill_untried(self.tables.table, self.tables.prior.reward, self.params)
        return self._q

    @q.setter
    def q(self, value: np.ndarray) -> None:
        self._q = value

    def _plans(self, context: TaskContext) -> PlanTable:
        if self.config.variant == "prior":
            return context.plans
        return _tolerant_plans(context, self.config.plan_tolerance)

    def _extra_params(self) -> dict[str, float]:
        c = self.config
        shared = {"backup": BACKUP_SAMPLE if c.variant == "code" else BACKUP_EXPECTED,
                  "opt_continue": 1.0 if c.optimistic_successor == "start" else 0.0}
        if self.kind != KIND_GDQ:
            return shared
        explore_all = c.explore_all
        if explore_all is None:
            explore_all = 0.0 if self.context.exact_knowledge else EXPLORE_ALL
        return {**shared, "explore_all": float(explore_all),
                "explore_all_last": float(c.explore_all_last_step),
                "prior_cost": prior_step_cost(c.prior_cost, self.context),
                "sweep_threshold": float(c.sweep_threshold),
                "prior_weight": float(c.prior_weight),
                "explore_band": float(c.plan_tolerance) if c.explore == "values" else -1.0}

    def _allowed(self, context: TaskContext) -> np.ndarray:
        if self.kind != KIND_GDQ:
            return super()._allowed(context)
        return self._prior(context).applicable  # OptInit adds the known pairs

    def _guide(self, context: TaskContext, allowed: np.ndarray) -> np.ndarray:
        if self.kind != KIND_GDQ:
            return allowed
        if self.config.explore == "values":  # draws near the best of allowed, not guide:
            return context.live  # no plan mask is built for nothing (every row has one)
        if self.config.explore == "plans":
            return _tolerant_plans(context, self.config.plan_tolerance).allowed_actions(
                context.live)
        guide = self._prior(context).applicable
        none = ~guide.any(axis=1)  # nothing applicable: explore every action
        guide[none] = context.live[none]
        return guide

    @staticmethod
    def _prior(context: TaskContext):
        if context.prior is None:
            raise ConfigError("the default GDQ plans on the knowledge's prior, and this task "
                              "context has none (build it with office_task_context or "
                              "pddl_task_context, or pass prior=...)")
        return context.prior  # its shape and values: guards.check_context

    def _prior_arrays(self, context: TaskContext) -> tuple[Prior, Queue]:
        if self.kind != KIND_GDQ:
            return _NO_PRIOR
        prior = self._prior(context)
        n_s = context.n_states
        pp_ptr, pp_pair = prior.predecessors()
        # the reverse index: room for the known pairs (the recorded successors of every pair
        # tried, and a prior successor each) and 64 steps more; a task switch keeps its room
        tried = self._model.visits > 0
        capacity = int(np.count_nonzero(self._model.slots[tried])) + int(
            np.count_nonzero(tried)) + gdq.reverse_room(self._model.slots.shape[2], 64)
        if hasattr(self, "tables"):
            capacity = max(capacity, len(self.tables.prior.rev_pair))
        return (Prior(np.ascontiguousarray(prior.next_state, dtype=np.int64), pp_ptr, pp_pair,
                      rev_head=np.full(n_s, -1, dtype=np.int64),
                      rev_next=np.full(capacity, -1, dtype=np.int64),
                      rev_pair=np.zeros(capacity, dtype=np.int64),
                      rev_n=np.zeros(1, dtype=np.int64), reward=prior_reward(context)),
                Queue(np.zeros(n_s, dtype=np.int64), np.full(n_s, -1, dtype=np.int64),
                      np.zeros(n_s), np.zeros(1, dtype=np.int64)))

    def reserve_reverse(self, entries: int) -> None:
        """Make room for ``entries`` more reverse-index entries (the default GDQ)."""
        check_count("entries", entries)
        prior = self.tables.prior
        used = int(prior.rev_n[0])
        if self.kind != KIND_GDQ or len(prior.rev_pair) - used >= entries:
            return
        grow = (0, max(len(prior.rev_pair), used + entries - len(prior.rev_pair)))
        self.tables = self.tables._replace(prior=prior._replace(
            rev_next=np.pad(prior.rev_next, grow, constant_values=-1),
            rev_pair=np.pad(prior.rev_pair, grow)))

    def observe(self, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
                rng: np.random.Generator) -> None:
        """:meth:`TabularLearner.observe`, then a sweep (the default variant) or N backups
        along plans (``literal``, ``code``)."""
        if self.kind == KIND_GDQ:
            self.reserve_reverse(gdq.reverse_room(self.max_successors))
        super().observe(s, a, r, s2, terminated, truncated, rng)

    def _init_task(self) -> None:
        """OptInit: value iteration on the hybrid model (``prior``), Algorithm 1 read
        literally (``literal``) or the authors' code's shortcut (``code``)."""
        self.q[:, :] = 0.0
        t = self.tables
        if self.kind == KIND_GDQ:
            tol = 1e-9 * max(1.0, self.params.r_max)
            if gdq.value_iteration(t.table, t.model, t.prior, t.queue, self.params, tol,
                                   1_000_000) < 0:
                raise AssertionError("reverse index sized too small")  # _prior_arrays
        elif self.config.variant == "literal":
            gdq_paper.policy_iteration(t.table, t.model, t.plans.opt_r, self.params)
        else:
            gdq_paper.seed_plan_pairs(t.table, t.plans.opt_r, self.params.r_max)

    @property
    def optimistic_pairs(self) -> np.ndarray:
        """bool[S, A]: OptInit's plan pairs (R = R_max in the optimistic model of the
        ``literal`` variant; Q = R_max in the ``code`` variant's OptInit)."""
        return self.tables.plans.opt_r


METHODS: dict[str, tuple[type[TabularLearner], type[LearnerConfig], str | None]] = {
    "GDQ": (GDQ, GDQConfig, None),
    "GDQ-literal": (GDQ, GDQConfig, "literal"),
    "GDQ-code": (GDQ, GDQConfig, "code"),
    "DARLING": (Darling, DarlingConfig, None),
    "DARLING-code": (Darling, DarlingConfig, "code"),
    "Dyna-Q": (DynaQ, DynaQConfig, None),
    "Q-learning": (QLearning, QLearningConfig, None),
}
"""Every learner by the name the command line takes (``--method``): its class, its config
class and the variant the name stands for (None: the config's default)."""

_BY_KEY = {name.lower().replace("-", ""): name for name in METHODS}


def make_learner(method: str, context: TaskContext, **config: object) -> TabularLearner:
    """A fresh learner by name for ``context``, with config overrides, e.g.
    ``make_learner("GDQ-code", ctx, alpha=0.2)``. ``method``: a name of :data:`METHODS`, in
    any case, with or without hyphens and underscores (``gdq``, ``dynaq``, ``q_learning``);
    a name without a variant takes ``variant=...`` among the overrides."""
    key = method.lower().replace("-", "").replace("_", "") if isinstance(method, str) else ""
    if key not in _BY_KEY:
        raise ConfigError(f"unknown method {method!r} (known: {', '.join(METHODS)})")
    cls, config_type, variant = METHODS[_BY_KEY[key]]
    if variant is not None and config.setdefault("variant", variant) != variant:
        raise ConfigError(f"method {method!r} is variant {variant!r}, and the overrides "
                          f"say variant={config['variant']!r}")
    try:
        settings = config_type(**config)  # type: ignore[arg-type]
    except TypeError as e:
        raise ConfigError(f"{method}: {e}".replace("__init__() ", "")) from None
    return cls(context, settings)
