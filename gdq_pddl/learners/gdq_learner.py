"""Guided Dyna-Q's two learners, the default :class:`GDQ` and the paper's :class:`PaperGDQ`
(GDQ-literal and GDQ-code), and what they derive from the task context: the prior's step
cost and rewards, the plans within a tolerance. Their rules are
:mod:`gdq_pddl.learners.gdq` (the default's acting and update) and
:mod:`gdq_pddl.learners.gdq_paper` (the paper's two readings).
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.abstraction import PlanTable
from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import gdq, gdq_paper
from gdq_pddl.learners.config import EXPLORE_ALL, GDQConfig
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.tables import (
    BACKUP_EXPECTED,
    BACKUP_SAMPLE,
    KIND_GDQ,
    KIND_GDQ_PLANS,
    Prior,
    Queue,
)
from gdq_pddl.learners.tabular import NO_DEAD, NO_REWARD, TabularLearner
from gdq_pddl.limits import check_count


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
    return NO_REWARD


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
    """Guided Dyna-Q, the default (``variant="prior"``): it takes the action knowledge as an
    optimistic prior over every (state, action) pair and plans on it.

    Its rules are one module, :mod:`gdq_pddl.learners.gdq`: its acting,
    :func:`~gdq_pddl.learners.gdq.act` (its exploring rules), and its update. After each
    real step, :func:`~gdq_pddl.learners.gdq.after_step` records the step in the learned
    model and calls :func:`~gdq_pddl.learners.gdq.sweep` (prioritised sweeping), which sets
    each pair it revisits to :func:`~gdq_pddl.learners.gdq.hybrid_backup`: the pair's
    :func:`~gdq_pddl.learners.warm_start.prior_backup` until tried more than ``m`` times, then
    the learned model's backup with the prior as ``prior_weight`` pseudo-trials. OptInit
    is :func:`~gdq_pddl.learners.gdq.value_iteration` on the same hybrid model.

    The paper's two readings, ``variant="literal"`` (GDQ-literal) and ``"code"``
    (GDQ-code), are another learner, :class:`PaperGDQ`; a ``GDQ(context, config)`` with
    one of those variants makes one (``docs/learners.md`` compares them).
    """

    kind = KIND_GDQ
    config: GDQConfig
    config_type = GDQConfig
    estimate_weight = 1.25
    """Online, GDQ's prior counts a state not reached yet ``ceil(1.25 h)`` actions from
    the goal: h_add runs short where goals interact, and each new state valued by it drew
    GDQ on (``docs/decisions.md``, "GDQ reads the estimates x1.25")."""

    def __new__(cls, context: TaskContext | None = None, config: GDQConfig | None = None):
        if cls is GDQ and isinstance(config, GDQConfig) and config.variant != "prior":
            learner = object.__new__(PaperGDQ)  # the paper's readings are their own learner
            learner.__init__(context, config)
            return learner
        return super().__new__(cls)

    def __init__(self, context: TaskContext, config: GDQConfig | None = None) -> None:
        if isinstance(config, GDQConfig) and config.variant != "prior":  # a subclass's
            raise ConfigError(f"{type(self).__name__} is the default GDQ (variant 'prior'); "
                              f"variant {config.variant!r} is the paper's, PaperGDQ")
        super().__init__(context, config)

    @classmethod
    def kind_of(cls, config: GDQConfig) -> int:  # type: ignore[override]
        """``KIND_GDQ`` for the default, ``KIND_GDQ_PLANS`` for the paper's readings (what
        ``GDQ(context, config)`` makes for them, :class:`PaperGDQ`)."""
        return KIND_GDQ if config.variant == "prior" else KIND_GDQ_PLANS

    @property
    def q(self) -> np.ndarray:
        """The Q table, float64[n_states, n_actions]. An untried action the knowledge says
        does nothing is worth its prior backup, one step that changes nothing
        (``-prior_cost + gamma * v[s]``); the sweeps never read those entries, so they are
        filled in here, when the table is read."""
        if hasattr(self, "tables"):
            gdq.fill_untried(self.tables.table, self.tables.prior.reward, self.params)
        return self._q

    @q.setter
    def q(self, value: np.ndarray) -> None:
        self._q = value

    def _extra_params(self) -> dict[str, float]:
        c = self.config
        explore_all = c.explore_all
        if explore_all is None:
            explore_all = 0.0 if self.context.exact_knowledge else EXPLORE_ALL
        return {"backup": BACKUP_EXPECTED,
                "opt_continue": 1.0 if c.optimistic_successor == "start" else 0.0,
                "explore_all": float(explore_all),
                "explore_all_last": float(c.explore_all_last_step),
                "prior_cost": prior_step_cost(c.prior_cost, self.context),
                "sweep_threshold": float(c.sweep_threshold),
                "prior_weight": float(c.prior_weight),
                "explore_band": float(c.plan_tolerance) if c.explore == "values" else -1.0,
                "explore_loops": float(c.explore_loops)}

    def _allowed(self, context: TaskContext) -> np.ndarray:
        return self._prior(context).applicable  # OptInit adds the known pairs

    def _guide(self, context: TaskContext, allowed: np.ndarray) -> np.ndarray:
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
                      rev_n=np.zeros(1, dtype=np.int64), reward=prior_reward(context),
                      dead=NO_DEAD if prior.dead is None else
                      np.ascontiguousarray(prior.dead, dtype=np.float64)),
                Queue(np.zeros(n_s, dtype=np.int64), np.full(n_s, -1, dtype=np.int64),
                      np.zeros(n_s), np.zeros(1, dtype=np.int64)))

    def _revalue_rows(self, rows: np.ndarray) -> None:
        t = self.tables
        none = ~t.table.allowed[rows].any(axis=1)  # nothing applicable: every action
        t.table.allowed[rows[none]] = self.context.live[rows[none]]
        gdq.revalue_rows(t.table, t.model, t.prior, t.queue, self.params, rows)

    def prior_changed(self, rows: np.ndarray) -> None:
        t = self.tables
        gdq.revalue_rows(t.table, t.model, t.prior, t.queue, self.params,
                         np.asarray(rows, dtype=np.int64))

    def refresh_predecessors(self) -> None:
        """Index the prior's pairs by successor again (a problem explored online added
        pairs since the task started: until this, sweeps do not reach them)."""
        pp_ptr, pp_pair = self._prior(self.context).predecessors()
        self.tables = self.tables._replace(
            prior=self.tables.prior._replace(pp_ptr=pp_ptr, pp_pair=pp_pair))

    def reserve_reverse(self, entries: int) -> None:
        """Make room for ``entries`` more reverse-index entries."""
        check_count("entries", entries)
        prior = self.tables.prior
        used = int(prior.rev_n[0])
        if len(prior.rev_pair) - used >= entries:
            return
        grow = (0, max(len(prior.rev_pair), used + entries - len(prior.rev_pair)))
        self.tables = self.tables._replace(prior=prior._replace(
            rev_next=np.pad(prior.rev_next, grow, constant_values=-1),
            rev_pair=np.pad(prior.rev_pair, grow)))

    def observe(self, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
                rng: np.random.Generator) -> None:
        """:meth:`TabularLearner.observe` (its rule records the step, then sweeps), with
        room in the reverse index first (where the slots are a start, for one successor
        more than they hold: the model may make room for it, ``_room_for``)."""
        self.reserve_reverse(gdq.reverse_room(self.max_successors
                                              + int(self.context.successors_grow)))
        super().observe(s, a, r, s2, terminated, truncated, rng)

    def _init_task(self) -> None:
        """OptInit: value iteration on the hybrid model."""
        self._q[:, :] = 0.0  # not self.q, whose getter first fills every untried pair
        t = self.tables
        tol = 1e-9 * max(1.0, self.params.r_max)
        if gdq.value_iteration(t.table, t.model, t.prior, t.queue, self.params, tol,
                               1_000_000) < 0:
            raise AssertionError("reverse index sized too small")  # _prior_arrays

    def _plans(self, context: TaskContext) -> None:
        """None: the default plans on the prior (its ``explore="plans"`` reads the plans
        for its guide alone)."""
        return None

    @property
    def optimistic_pairs(self) -> np.ndarray:
        """bool[S, A]: OptInit's plan pairs of the paper's readings (:class:`PaperGDQ`);
        none here: the default plans on the prior, whose optimism is in its values."""
        return self.tables.plans.opt_r


class PaperGDQ(TabularLearner):
    """The paper's GDQ, read two ways (:mod:`gdq_pddl.learners.gdq_paper`): Q-learning, the
    learned model and N backups per real step along the plans H from the current state.
    ``variant="literal"`` (GDQ-literal: Algorithms 1-3 read literally; OptInit is policy
    iteration on an optimistic plan model, backups assign the expected value) or
    ``"code"`` (GDQ-code: the authors' released code; OptInit seeds the plan pairs with
    R_max, backups are TD updates on replayed outcomes). Plain epsilon-greedy acting."""

    kind = KIND_GDQ_PLANS
    config: GDQConfig
    config_type = GDQConfig
    estimate_weight = GDQ.estimate_weight
    """Online, the same reading of the estimates as :class:`GDQ`'s."""

    def __init__(self, context: TaskContext, config: GDQConfig | None = None) -> None:
        config = GDQConfig(variant="code") if config is None else config
        if isinstance(config, GDQConfig) and config.variant == "prior":
            raise ConfigError("the paper's GDQ is variant 'literal' or 'code'; variant "
                              "'prior' is the default GDQ (GDQ)")
        super().__init__(context, config)

    @classmethod
    def kind_of(cls, config: GDQConfig) -> int:  # type: ignore[override]
        """``KIND_GDQ_PLANS``."""
        return KIND_GDQ_PLANS

    def _plans(self, context: TaskContext) -> PlanTable:
        return _tolerant_plans(context, self.config.plan_tolerance)

    def _extra_params(self) -> dict[str, float]:
        c = self.config
        return {"backup": BACKUP_SAMPLE if c.variant == "code" else BACKUP_EXPECTED,
                "opt_continue": 1.0 if c.optimistic_successor == "start" else 0.0}

    def _init_task(self) -> None:
        """OptInit: Algorithm 1 read literally (``literal``) or the authors' code's shortcut
        (``code``)."""
        self.q[:, :] = 0.0
        t = self.tables
        if self.config.variant == "literal":
            gdq_paper.policy_iteration(t.table, t.model, t.plans.opt_r, self.params)
        else:
            gdq_paper.seed_plan_pairs(t.table, t.plans.opt_r, self.params.r_max)

    @property
    def optimistic_pairs(self) -> np.ndarray:
        """bool[S, A]: OptInit's plan pairs (R = R_max in the optimistic model of the
        ``literal`` variant; Q = R_max in the ``code`` variant's OptInit)."""
        return self.tables.plans.opt_r
