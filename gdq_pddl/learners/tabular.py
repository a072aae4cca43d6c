"""The base of every learner, :class:`TabularLearner`: the arrays of
:class:`~gdq_pddl.learners.tables.Tables` and the compiled rules behind the small interface
the episode loop needs (:class:`Learner`). Its methods check their arguments
(:mod:`gdq_pddl.learners.guards`) and call the rules (:mod:`gdq_pddl.learners.rules` says
which). The learners on it: the baselines in :mod:`gdq_pddl.learners.agents`, GDQ in
:mod:`gdq_pddl.learners.gdq_learner`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from gdq_pddl.abstraction import PlanTable
from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import guards, learned_model, rules
from gdq_pddl.learners.config import LearnerConfig
from gdq_pddl.learners.context import TaskContext, row_context
from gdq_pddl.learners.tables import (
    BACKUP_EXPECTED,
    KIND_DYNAQ,
    KIND_GDQ,
    KIND_GDQ_PLANS,
    KIND_QLEARNING,
    NO_OWN,
    Params,
    Plans,
    Prior,
    QTable,
    Queue,
    Tables,
    greedy,
    recompute_all_v,
)
from gdq_pddl.limits import check_count

MODEL_BASED = (KIND_DYNAQ, KIND_GDQ_PLANS, KIND_GDQ)
"""The learner kinds that record transitions in a learned model."""

_I0 = np.zeros(0, dtype=np.int64)
NO_REWARD = np.zeros((0, 0))
"""An empty ``Prior.reward``: the prior charges a flat step cost (or there is no prior)."""
NO_DEAD = np.zeros((0, 0))
"""An empty ``Prior.dead``: the knowledge has no dead end (or there is no prior)."""
NO_PRIOR = (Prior(np.zeros((0, 0), dtype=np.int64), _I0, _I0, _I0, _I0, _I0,
                  np.zeros(1, dtype=np.int64), NO_REWARD, NO_DEAD),
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
    config_type: type[LearnerConfig] = LearnerConfig
    """The config class the constructor takes."""
    reads_knowledge: bool = True
    """Whether the rule reads the planner's knowledge (the prior, the plans); a problem
    explored online estimates no state for a learner that does not."""
    estimate_weight: float = 1.0
    """On a problem explored online, a state not reached yet stands ``ceil(w h)`` actions
    from the goal for this learner, ``h`` its estimate
    (:class:`~gdq_pddl.envs.online.OnlineInstance`)."""

    @classmethod
    def kind_of(cls, config: LearnerConfig) -> int:
        """The ``kind`` a learner of this class with ``config`` has."""
        return cls.kind

    loop_rules: type | None = None
    """A learner of this package whose rules are not its kind's: its rules class (a
    NamedTuple without fields whose ``act`` and ``observe`` are :attr:`act_rule` and
    :attr:`observe_rule`, as :mod:`gdq_pddl.learners.rules` has them), so numba caches its
    compiled episode loop; None: its kind's."""

    @classmethod
    def rules_for(cls, config: LearnerConfig) -> tuple:
        """``(act_rule, observe_rule)`` of a learner of this class with ``config``, without
        making one (what the compiled loop is compiled for)."""
        own = rules.KIND_RULES[cls.kind_of(config)]
        given = cls.act_rule, cls.observe_rule  # a plugin's own, or the kind's (properties)
        return tuple(o if isinstance(g, property) else g for g, o in zip(
            given, (own.act, own.observe), strict=True))

    @classmethod
    def loop_marker(cls, config: LearnerConfig) -> type | None:
        """The rules class the compiled episode loop of a learner of this class with
        ``config`` is compiled for (:attr:`loop_rules`, else its kind's), or None when its
        rules are neither (a learner of another package with rules of its own: the loop
        is a copy calling them, :func:`gdq_pddl.learners.episodes._loop_of`)."""
        marker = cls.loop_rules or rules.KIND_RULES[cls.kind_of(config)]
        return marker if (marker.act, marker.observe) == cls.rules_for(config) else None

    @property
    def act_rule(self):
        """The compiled acting rule, ``(table, visits, prior, params, s, rng) -> column``:
        epsilon-greedy, the default GDQ's own (:func:`gdq_pddl.learners.gdq.act`: its
        exploring rules), :func:`~gdq_pddl.learners.tables.act_plain` for the others.
        :meth:`act` and the compiled episode loop call it. A learner from another package
        may give its own numba function as a class attribute
        (``docs/howto-add-learner.md``)."""
        return rules.KIND_RULES[self.kind].act

    @property
    def observe_rule(self):
        """The compiled rule after a real step, ``(table, model, plans, prior, queue, own,
        params, s, a, r, s2, terminated, truncated, rng) -> bool`` (``own``: the learner's
        own arrays, :attr:`~gdq_pddl.learners.tables.Tables.own`): its kind's
        (:data:`gdq_pddl.learners.rules.KIND_RULES`). :meth:`observe` calls it, and the
        compiled episode loop."""
        return rules.KIND_RULES[self.kind].observe
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

    def _plans(self, context: TaskContext) -> PlanTable | None:
        """H: the plans whose pairs the rules may read (``Plans``: OptInit's ``opt_r``, the
        plans the paper's GDQ walks); None for a learner that reads no knowledge
        (:attr:`reads_knowledge`), for which the context's plans are never made."""
        return context.plans if self.reads_knowledge else None

    def _init_task(self) -> None:
        """What happens when a task starts (after the tables are rebuilt)."""

    def _prior_arrays(self, context: TaskContext) -> tuple[Prior, Queue]:
        """The :class:`Tables` groups only the default GDQ uses (empty here)."""
        return NO_PRIOR

    def _own_arrays(self, context: TaskContext) -> tuple:
        """The learner's own group of :class:`Tables` (:data:`NO_OWN`: none)."""
        return NO_OWN

    def _extra_params(self) -> dict[str, float]:
        """:class:`Params` fields beyond the shared ones (their defaults here)."""
        return {"backup": BACKUP_EXPECTED}

    # -- interface ---------------------------------------------------------------------
    def _build(self, context: TaskContext) -> tuple[Tables, Params]:
        """The tables and params for ``context`` (checked by the caller)."""
        allowed = np.ascontiguousarray(self._allowed(context), dtype=np.bool_)
        guide = np.ascontiguousarray(self._guide(context, allowed), dtype=np.bool_)
        plans = self._plans(context)
        opt_r = np.zeros(allowed.shape, dtype=np.bool_) if plans is None else \
            plans.start_pairs(context.s0)
        walked = (plans.plan_ptr, plans.pair_ptr, plans.pair_state, plans.pair_action) \
            if self.kind == KIND_GDQ_PLANS else (  # only the paper's GDQs walk plans
                np.zeros(len(allowed) + 1, dtype=np.int64), np.zeros(1, dtype=np.int64), _I0, _I0)
        table = QTable(self.q, np.zeros(len(self.q)), allowed, guide,
                       guide.sum(axis=1).astype(np.int64),
                       np.ascontiguousarray(context.goal, dtype=np.bool_),
                       context.live.sum(axis=1).astype(np.int64))
        plan_arrays = (np.ascontiguousarray(x, dtype=np.int64) for x in walked)
        tables = Tables(table, self._model, Plans(opt_r, *plan_arrays),
                        *self._prior_arrays(context), self._own_arrays(context))
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

    # -- a problem explored online (gdq_pddl.learners.online) ---------------------------
    def resize(self, context: TaskContext) -> None:
        """Take ``context``, the same task over more states or wider rows (a problem
        explored online outgrew its arrays): the tables are padded, what was learned is
        kept, and the task starts again on them (OptInit for GDQ)."""
        guards.check_context(context)
        n_s, n_a = context.n_states, context.n_actions
        old_s, old_a = self.q.shape
        if n_s < old_s or n_a < old_a:
            raise ConfigError(f"resize: the task has {n_s} x {n_a} states x actions, fewer "
                              f"than the learner's {old_s} x {old_a}")
        q = np.zeros((n_s, n_a))
        q[:old_s, :old_a] = self._q if hasattr(self, "_q") else self.q
        self.q = q
        self._model = learned_model.resized(self._model, n_s, n_a)
        self._set_task(context)

    def update_rows(self, rows: np.ndarray) -> None:
        """The context's rows ``rows`` were made in place (a problem explored online: rows
        for the states an episode reached, and for estimates): their allowed and guide
        masks are made from the context, their values from their untried pairs."""
        rows = np.asarray(rows, dtype=np.int64)
        part = row_context(self.context, rows)
        allowed = self._allowed(part)
        guide = self._guide(part, allowed)
        t = self.tables.table
        live = part.live
        t.allowed[rows] = allowed
        t.guide[rows] = guide
        t.n_guide[rows] = guide.sum(axis=1)
        t.n_live[rows] = live.sum(axis=1)
        t.q[rows] = 0.0
        self._revalue_rows(rows)

    def prior_changed(self, rows: np.ndarray) -> None:
        """The prior successors of some pairs of ``rows`` changed (a problem explored
        online: the state an estimate stood for now has a row); only GDQ reads them."""

    def _revalue_rows(self, rows: np.ndarray) -> None:
        """Values of rows whose masks were just set (their Q rows are zero)."""
        t = self.tables.table
        best = np.where(t.allowed[rows], t.q[rows], -np.inf).max(axis=1)
        t.v[rows] = np.where(t.goal[rows], 0.0, best)

    def act(self, state: int, rng: np.random.Generator) -> int:
        """The epsilon-greedy action (the env's index) to take in learner state ``state``,
        drawing from ``rng`` (:attr:`act_rule`)."""
        s = guards.check_state("state", state, len(self.q))
        guards.check_generator(rng)
        t = self.tables
        column = int(self.act_rule(t.table, t.model.visits, t.prior, self.params, s, rng))
        return self.context.action_of(s, column)

    def observe(self, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
                rng: np.random.Generator) -> None:
        """Learn from one real step ``(s, a, r, s2)`` as Gymnasium's step gave it (``a``:
        the env's action index); backups draw from ``rng``
        (:attr:`observe_rule`)."""
        n_s, n_a = self.q.shape
        s, s2 = guards.check_state("s", s, n_s), guards.check_state("s2", s2, n_s)
        a = self._column("a", s, a)
        r = guards.check_reward(r)
        guards.check_generator(rng)
        self._room_for(s, a, s2)
        if not self.observe_rule(*self.tables, self.params, s, a, r, s2, bool(terminated),
                             bool(truncated), rng):
            raise ValueError(learned_model.OVERFLOW)

    def _room_for(self, s: int, a: int, s2: int) -> None:
        """Twice the successor slots where column ``a`` of ``s`` has none free for a new
        ``s2``, where the context says the slots are a start
        (:attr:`TaskContext.successors_grow <gdq_pddl.learners.context.TaskContext.
        successors_grow>`: a problem explored online whose factored actions have more
        outcomes than any capacity could list); elsewhere the capacity bounds the true
        model's successors, and a step past it is an error."""
        slots = self._model.slots
        k = slots.shape[2]
        if self.context.successors_grow and self.kind in MODEL_BASED and 0 < k < len(self.q) \
                and slots[s, a, k - 1] != 0 \
                and not learned_model.has_successor(slots, s, a, s2):
            self.reserve_successors(min(2 * k, len(self.q)))

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
