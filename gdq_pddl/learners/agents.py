"""The four learners behind one small interface.

Every learner has ``q`` (the Q table, float64[n_states, n_actions]), ``act(state, rng)``,
``observe(s, a, r, s2, terminated, truncated, rng)``, ``start_task(context)`` and
``greedy_policy()``. The methods only call the compiled rules of
:mod:`gdq_pddl.learners.core`, which the fast episode loop calls too.

- :class:`QLearning`: epsilon-greedy Q-learning.
- :class:`DynaQ`: Q-learning + the goal-independent model + N expected backups per real
  step on uniformly random pairs tried more than m times.
- :class:`Darling`: Q-learning restricted, at every state, to the actions that start a
  plan within the length tolerance (1.3 x shortest) from that state, both when acting
  (exploration included) and in the max of the update; all actions where no plan exists.
  ``variant="code"`` is DARLING as the GDQ authors' released agent runs it (read, not
  copied): the greedy choice and the update's max range over every action (untried ones
  at 0), and any action that does not start a plan, greedy or exploratory, is replaced
  by a uniformly random one that does. Untried actions keep Q = 0, so wherever the plan
  actions' values are still negative the greedy choice is a non-plan action, replaced by
  a random plan action: it walks at random among plan actions until the values along a
  route turn positive (and the zeros floor every state's value in the update). It
  learns much more slowly: on Task C, first 300 episodes, 100 runs, mean return 0.67
  against 7.54 for the paper variant, the 50-episode average of the mean curve turning
  positive at episode 170 against 58 (the issue's measurement of the released code:
  ~231). It is a baseline for reading the paper's curves, not part of the paper
  protocol (``gdq-pddl run --method DARLING-code``).
- :class:`GDQ`: Guided Dyna-Q, below.

GDQ's default: the action knowledge as an optimistic prior model (``variant="model"``)
-----------------------------------------------------------------------------------
SPEC section 4's decision; the rules are in :mod:`gdq_pddl.learners.core` ("Planning on
the prior"), the prior in :mod:`gdq_pddl.abstraction.prior`, the measurements behind its
settings in ``docs/decisions.md``. Every (state, action) pair is valued by a model: the
knowledge's (the planner's successor, or no change where its preconditions fail; one
step costs 1; reaching the goal pays R_max and ends the episode) until the pair has been
tried more than m times, then the learned one with the prior as ``prior_weight``
pseudo-trials. OptInit is value iteration on that hybrid model, so before the first step
the greedy policy follows a shortest plan; after every real step prioritised sweeping
recomputes pair values until at least ``n_backups`` are done (it finishes each state it
takes from the queue). Exploring steps draw from the first actions of the
plans within 1.3 x from the current state, a share ``explore_all`` of them from the
actions never tried there. An action the knowledge says does nothing is outside the max
until it has been tried.

The two readings of the paper it is compared with
-------------------------------------------------
``variant="literal"`` (GDQ-literal: Algorithms 1-3 read literally) and ``variant="code"``
(GDQ-code: the authors' released code), side by side (literal | code):

- H, the plans: every shortest plan (the paper: "a set of the shortest plans") | every
  loop-free plan up to 1.3 x the shortest (the authors' planner's factor; their
  planner's exact set differs, see ``docs/decisions.md``); ``plan_tolerance``.
- Optimistic model: T(s,a,s0) = 1 for every pair, R = R_max on every pair of every plan
  in H(s0), else 0 | none: the optimism is only in the initial Q.
- Q after OptInit: policy iteration on that model (known pairs: learned model) until pi
  is stable, and Q <- its Q for every (s, a) | Q <- 0, then Q(s,a) <- R_max on the plan
  pairs; no policy iteration.
- Real step: epsilon-greedy on Q, TD update with alpha, count in the model | the same.
- N backups per step, each on a random transition of a random plan from the current
  state: expected backup, assigned, ``Q(s,a) <- sum_s' T(s,a,s') (R or gamma V(s'))`` |
  a TD update with alpha on one ``(r, s')`` replayed from the pair's recorded outcomes;
  a pair never tried gets no backup.

Where the code column comes from. The SPEC describes the released code's OptInit and
its sample-based (alpha) backups, and that is what this variant implements; its backups
replay recorded outcomes of plan pairs from the current state, stuck trials (-R_max)
included. The authors' public GDQ agent (read, not copied) is more particular, and
differs from this variant in ways the SPEC does not mention: a backup there draws a
uniformly random experienced state and one of its tried actions, uses the pair's most
frequent successor at its mean step reward, updates only if that transition is a step
of a plan from some state it has planned from, and never holds a stuck step (its model
counts only steps that did not end the episode). That rule was implemented and
measured (commit b6c3c2a, reverted in the next commit): Task C, first 300 episodes,
100 runs, mean return 5.41 against 7.26 for this variant (paired difference -1.84,
s.e. 0.14), the gap coming almost entirely from not replaying stuck penalties. Which of
the two the package should call "code" is an open question (``docs/decisions.md``).
An earlier version of this package backed up untried plan pairs with the paper's
optimistic model (``R_max`` and a jump to s0); with the code's seeding that inflates
plan pairs towards ``R_max / (1 - gamma)`` as GDQ-literal's do, and it made
GDQ-code reach a positive 50-episode average on Task C at episode ~120 instead of ~60.

Policy iteration in GDQ-literal's OptInit (a decision). Algorithm 1, read literally, evaluates only
``Q(s, pi(s))`` and then takes ``argmax_a Q(s, a)`` over a table whose other entries
are still the initial zeros, so it can lock onto a non-plan action whose 0 beats a
negative estimate, and it never gives the learner Q values for the other actions. We
implement standard policy iteration instead: evaluate V^pi exactly (to 1e-10), compute
``Q(s,a) = R(s,a) + gamma * sum_s' T(s,a,s') V^pi(s')`` for every action, improve
keeping the current action on ties (else the lowest index) so it terminates, repeat
until pi is stable, and hand that final Q to the learner. The initial policy is
"action 0 everywhere" rather than random: the final Q is the optimistic model's Q*
whatever the start, so this changes nothing the learner uses and keeps OptInit free of
randomness.

A consequence worth knowing (it follows from the paper's model, not from this code):
optimistic pairs lead back to s0 without ending the episode, so under policy iteration
the plan pairs are worth ``R_max / (1 - gamma)`` (400 for the office) and every other
pair ``gamma`` times that (380), far above any achievable return (at most R_max = 20).
Real experience then has to pull these values down.

Other decisions where the paper is silent (GDQ-literal and GDQ-code):

- H is re-planned from the state the action was taken in (Alg. 2 line 12 uses the
  ``s`` of line 1), by a lookup in the task's :class:`PlanTable`.
- When the current state has no plan (a planner that finds nothing), GDQ's N backups go
  to uniformly random known pairs, as in Dyna-Q, so it still plans with what it learned.
- ``start_task``: every GDQ keeps its model (counts) and reruns OptInit for the new goal
  (known pairs with the learned model, unknown with the optimistic one; Q <- 0 first).
  The baselines keep their Q table (they are not told the task changed other than
  through the goal states their backups use); DARLING recomputes its allowed sets.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from gdq_pddl.abstraction import PlanTable
from gdq_pddl.learners import core
from gdq_pddl.learners.config import (
    DarlingConfig,
    DynaQConfig,
    GDQConfig,
    LearnerConfig,
    QLearningConfig,
)
from gdq_pddl.learners.context import TaskContext

MODEL_BASED = (core.KIND_DYNAQ, core.KIND_GDQ, core.KIND_PRIOR)
"""The learner kinds that record transitions (the others get no successor slots)."""

_I0 = np.zeros(0, dtype=np.int64)
_NO_PRIOR: dict[str, np.ndarray] = {
    "prior_next": np.zeros((0, 0), dtype=np.int64), "pp_ptr": _I0, "pp_pair": _I0,
    "rev_head": _I0, "rev_next": _I0, "rev_pair": _I0, "rev_n": np.zeros(1, dtype=np.int64),
    "heap": _I0, "heap_pos": _I0, "heap_prio": np.zeros(0), "heap_n": np.zeros(1, np.int64)}
"""The :class:`core.Tables` fields of GDQ's default variant, for the other learners (never
read by them; the two counters are never written either)."""

MAX_DENSE_COUNTS = 50_000_000
"""The most entries :attr:`TabularLearner.counts` builds a dense array of (400 MB)."""


def _capacity(context: TaskContext) -> int:
    """Successor slots per pair for ``context``: its ``max_successors``, or every state."""
    k = context.max_successors
    return context.n_states if k is None else max(1, int(k))


@runtime_checkable
class Learner(Protocol):
    """What the episode runner needs from a learner."""

    q: np.ndarray

    def act(self, state: int, rng: np.random.Generator) -> int: ...

    def observe(self, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
                rng: np.random.Generator) -> None: ...

    def start_task(self, context: TaskContext) -> None: ...

    def greedy_policy(self) -> np.ndarray: ...


class TabularLearner:
    """Shared implementation: arrays in :class:`core.Tables`, rules in :mod:`core`."""

    kind: int = core.KIND_QLEARNING
    name: str = "tabular"

    def __init__(self, context: TaskContext, config: LearnerConfig) -> None:
        self.config = config
        n_s, n_a = context.n_states, context.n_actions
        self._model = core.new_model(n_s, n_a, _capacity(context),
                                     transitions=self.kind in MODEL_BASED)
        self.q = np.zeros((n_s, n_a), dtype=np.float64)
        self.context = context
        self.tables, self.params = self._build(context)
        core.recompute_all_v(self.tables)
        self._init_task()

    # -- per-learner hooks -------------------------------------------------------------
    def _allowed(self, context: TaskContext) -> np.ndarray:
        """What the max in the update and the greedy choice range over, per state."""
        return np.ones((context.n_states, context.n_actions), dtype=np.bool_)

    def _guide(self, context: TaskContext, allowed: np.ndarray) -> np.ndarray:
        """What the learner may execute, per state (:mod:`~gdq_pddl.learners.core`)."""
        return allowed

    def _plans(self, context: TaskContext) -> PlanTable:
        """H: the plans this learner backs up (GDQ may ask for plans within a tolerance)."""
        return context.plans

    def _init_task(self) -> None:
        """What happens when a task starts (after the tables are rebuilt)."""

    def _n_backups(self) -> int:
        return 0

    def _m(self) -> int:
        return 0

    def _backup_mode(self) -> int:
        return core.BACKUP_EXPECTED

    def _opt_continue(self) -> float:
        return 1.0

    def _prior_arrays(self, context: TaskContext) -> dict[str, np.ndarray]:
        """The :class:`core.Tables` fields only GDQ's default variant uses (empty here)."""
        return _NO_PRIOR

    def _extra_params(self) -> dict[str, float]:
        """:class:`core.Params` fields beyond the shared ones (their defaults here)."""
        return {}

    # -- interface ---------------------------------------------------------------------
    def _build(self, context: TaskContext) -> tuple[core.Tables, core.Params]:
        if (context.n_states, context.n_actions) != self.q.shape:
            raise ValueError(f"task has {context.n_states} states x {context.n_actions} "
                             f"actions, the learner {self.q.shape}")
        allowed = np.ascontiguousarray(self._allowed(context), dtype=np.bool_)
        guide = np.ascontiguousarray(self._guide(context, allowed), dtype=np.bool_)
        plans = self._plans(context)
        opt_r = np.zeros_like(allowed)
        for k in range(plans.plan_ptr[context.s0], plans.plan_ptr[context.s0 + 1]):
            lo, hi = plans.pair_ptr[k], plans.pair_ptr[k + 1]
            opt_r[plans.pair_state[lo:hi], plans.pair_action[lo:hi]] = True
        tables = core.Tables(
            q=self.q, v=np.zeros(len(self.q)), allowed=allowed, guide=guide,
            n_guide=guide.sum(axis=1).astype(np.int64),
            goal=np.ascontiguousarray(context.goal, dtype=np.bool_), opt_r=opt_r,
            **self._model,
            plan_ptr=np.ascontiguousarray(plans.plan_ptr, dtype=np.int64),
            pair_ptr=np.ascontiguousarray(plans.pair_ptr, dtype=np.int64),
            pair_state=np.ascontiguousarray(plans.pair_state, dtype=np.int64),
            pair_action=np.ascontiguousarray(plans.pair_action, dtype=np.int64),
            **self._prior_arrays(context))
        c = self.config
        params = core.Params(
            kind=int(self.kind), alpha=float(c.alpha), gamma=float(c.gamma),
            epsilon=float(c.epsilon), r_max=float(context.r_max),
            n_backups=int(self._n_backups()), m=int(self._m()),
            backup=int(self._backup_mode()), s0=int(context.s0),
            opt_continue=float(self._opt_continue()), **self._extra_params())
        return tables, params

    def start_task(self, context: TaskContext) -> None:
        """Switch to a new task, keeping what the learner has learned (see module doc)."""
        self.context = context
        self._model = self._slots(_capacity(context))
        self.tables, self.params = self._build(context)
        core.recompute_all_v(self.tables)
        self._init_task()

    def act(self, state: int, rng: np.random.Generator) -> int:
        return int(core.act(self.tables, self.params, int(state), rng))

    def observe(self, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
                rng: np.random.Generator) -> None:
        if not core.observe(self.tables, self.params, int(s), int(a), float(r), int(s2),
                            bool(terminated), bool(truncated), rng):
            raise ValueError(core.OVERFLOW)

    def greedy_policy(self) -> np.ndarray:
        """Per state, the lowest-index allowed action of maximal Q."""
        return core.greedy(self.tables, self.params)

    @property
    def v(self) -> np.ndarray:
        """max_a Q(s, a) over the allowed actions, per state."""
        return self.tables.v

    @property
    def visits(self) -> np.ndarray:
        """Trials per (s, a) recorded in the model (model-based learners only)."""
        return self.tables.visits

    @property
    def counts(self) -> np.ndarray:
        """Model transition counts C[s, a, s'] as a new dense int64 array (all zero for the
        model-free learners); refused past :data:`MAX_DENSE_COUNTS` entries (use
        :meth:`successors`)."""
        n_s, n_a = self.q.shape
        if n_s * n_a * n_s > MAX_DENSE_COUNTS:
            raise ValueError(f"a dense C[s, a, s'] of {n_s} x {n_a} x {n_s} entries is too "
                             f"large; use successors(s, a)")
        return core.dense_counts(self.tables.slots, n_s)

    def successors(self, s: int, a: int) -> dict[int, int]:
        """``{s': count}`` of the recorded transitions of ``(s, a)``, in increasing ``s'``."""
        slots = self.tables.slots[s, a]
        slots = slots[slots != 0]
        return dict(zip((slots >> core.SLOT_SHIFT).tolist(),
                        (slots & core.COUNT_MASK).tolist(), strict=True))

    @property
    def nbytes(self) -> int:
        """Bytes of the learner's arrays (allocated; the pages of pairs never tried are
        never written, so the memory actually used can be much less)."""
        # guide is usually the allowed array itself: count each array once
        arrays = {id(x): x for x in self.tables if isinstance(x, np.ndarray)}
        return sum(x.nbytes for x in arrays.values())

    @property
    def max_successors(self) -> int:
        """Successor slots per pair of the model (0 for the model-free learners)."""
        return int(self.tables.slots.shape[2])

    def reserve_successors(self, k: int) -> None:
        """Make room for ``k`` distinct successors per pair (model-based learners; the
        recorded transitions are kept). The runners call it with what their env needs."""
        if self.kind in MODEL_BASED and k > self.max_successors:
            self._model = self._slots(k)
            self.tables = self.tables._replace(slots=self._model["slots"])

    def _slots(self, k: int) -> dict[str, np.ndarray]:
        if self.kind not in MODEL_BASED:
            return self._model
        return core.with_successor_slots(self._model, k)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.config})"


class QLearning(TabularLearner):
    kind = core.KIND_QLEARNING
    name = "Q-learning"

    def __init__(self, context: TaskContext, config: QLearningConfig | None = None) -> None:
        super().__init__(context, config or QLearningConfig())


class DynaQ(TabularLearner):
    kind = core.KIND_DYNAQ
    name = "Dyna-Q"
    config: DynaQConfig

    def __init__(self, context: TaskContext, config: DynaQConfig | None = None) -> None:
        super().__init__(context, config or DynaQConfig())

    def _n_backups(self) -> int:
        return self.config.n_backups

    def _m(self) -> int:
        return self.config.m


class Darling(TabularLearner):
    kind = core.KIND_DARLING
    name = "DARLING"
    config: DarlingConfig

    def __init__(self, context: TaskContext, config: DarlingConfig | None = None) -> None:
        super().__init__(context, config or DarlingConfig())

    def _plan_actions(self, context: TaskContext) -> np.ndarray:
        """Per state, the actions that start a plan within the tolerance (all actions
        where there is no plan)."""
        table = context.darling_plans
        if table is None:
            raise ValueError("DARLING needs a task context with darling_plans")
        if context.darling_tolerance is not None and not np.isclose(
                context.darling_tolerance, self.config.tolerance):
            raise ValueError(f"the context's DARLING plans use tolerance "
                             f"{context.darling_tolerance}, the config {self.config.tolerance}")
        return table.allowed_actions()

    def _allowed(self, context: TaskContext) -> np.ndarray:
        if self.config.variant == "code":  # the max ranges over every action
            return super()._allowed(context)
        return self._plan_actions(context)

    def _guide(self, context: TaskContext, allowed: np.ndarray) -> np.ndarray:
        if self.config.variant == "code":
            return self._plan_actions(context)
        return allowed


def _tolerant_plans(context: TaskContext, tolerance: float) -> PlanTable:
    """The context's plans within ``tolerance`` (its shortest plans for 0)."""
    if not tolerance:
        return context.plans
    if context.darling_plans is None or context.darling_tolerance is None or \
            not np.isclose(context.darling_tolerance, tolerance):
        raise ValueError(f"GDQ with plan_tolerance {tolerance} needs a task context whose "
                         f"tolerant plan table was built with that tolerance (it has "
                         f"{context.darling_tolerance})")
    return context.darling_plans


class GDQ(TabularLearner):
    kind = core.KIND_PRIOR
    name = "GDQ"
    config: GDQConfig

    def __init__(self, context: TaskContext, config: GDQConfig | None = None) -> None:
        config = config or GDQConfig()
        self.kind = core.KIND_PRIOR if config.variant == "model" else core.KIND_GDQ
        self._rev_capacity = 0
        super().__init__(context, config)

    @property
    def q(self) -> np.ndarray:
        """The Q table, float64[n_states, n_actions]. In the default variant an untried
        action the knowledge says does nothing is worth its prior backup, one step that
        changes nothing (``-prior_cost + gamma * v[s]``); the sweeps never read those
        entries, so they are filled in here, when the table is read."""
        if self.kind == core.KIND_PRIOR and hasattr(self, "tables"):
            core.prior_fill_untried(self.tables, self.params)
        return self._q

    @q.setter
    def q(self, value: np.ndarray) -> None:
        self._q = value

    def _n_backups(self) -> int:
        return self.config.n_backups

    def _m(self) -> int:
        return self.config.m

    def _backup_mode(self) -> int:
        return core.BACKUP_SAMPLE if self.config.variant == "code" else core.BACKUP_EXPECTED

    def _plans(self, context: TaskContext) -> PlanTable:
        if self.config.variant == "model":
            return context.plans
        return _tolerant_plans(context, self.config.plan_tolerance)

    def _opt_continue(self) -> float:
        return 1.0 if self.config.optimistic_successor == "start" else 0.0

    def _extra_params(self) -> dict[str, float]:
        if self.kind != core.KIND_PRIOR:
            return {}
        c = self.config
        return {"explore_all": float(c.explore_all),
                "explore_all_last": float(c.explore_all_last_step),
                "prior_cost": float(c.prior_cost),
                "sweep_threshold": float(c.sweep_threshold),
                "prior_weight": float(c.prior_weight)}

    def _allowed(self, context: TaskContext) -> np.ndarray:
        if self.kind != core.KIND_PRIOR:
            return super()._allowed(context)
        return self._prior(context).applicable  # OptInit adds the known pairs

    def _guide(self, context: TaskContext, allowed: np.ndarray) -> np.ndarray:
        if self.kind != core.KIND_PRIOR:
            return allowed
        if self.config.explore == "plans":
            return _tolerant_plans(context, self.config.plan_tolerance).allowed_actions()
        guide = self._prior(context).applicable
        guide[~guide.any(axis=1)] = True  # nothing applicable: explore every action
        return guide

    @staticmethod
    def _prior(context: TaskContext):
        if context.prior is None:
            raise ValueError("GDQ's default variant plans on the knowledge's prior model, and "
                             "this task context has none (build it with office_task_context "
                             "or pddl_task_context, or pass prior=...)")
        if context.prior.next_state.shape != (context.n_states, context.n_actions):
            raise ValueError(f"the context's prior model is {context.prior.next_state.shape},"
                             f" its task {context.n_states} states x {context.n_actions} "
                             "actions")
        return context.prior

    def _prior_arrays(self, context: TaskContext) -> dict[str, np.ndarray]:
        if self.kind != core.KIND_PRIOR:
            return _NO_PRIOR
        prior = self._prior(context)
        n_s = context.n_states
        pp_ptr, pp_pair = prior.predecessors()
        capacity = max(self._rev_capacity,
                       self._rev_needed() + core.rev_room(self._model["slots"].shape[2], 64))
        self._rev_capacity = capacity
        return {"prior_next": np.ascontiguousarray(prior.next_state, dtype=np.int64),
                "pp_ptr": pp_ptr, "pp_pair": pp_pair,
                "rev_head": np.full(n_s, -1, dtype=np.int64),
                "rev_next": np.full(capacity, -1, dtype=np.int64),
                "rev_pair": np.zeros(capacity, dtype=np.int64),
                "rev_n": np.zeros(1, dtype=np.int64),
                "heap": np.zeros(n_s, dtype=np.int64),
                "heap_pos": np.full(n_s, -1, dtype=np.int64),
                "heap_prio": np.zeros(n_s), "heap_n": np.zeros(1, dtype=np.int64)}

    def _rev_needed(self) -> int:
        """At least the reverse-index entries the known pairs need: the recorded successors
        of every pair tried, and one prior successor each."""
        slots, visits = self._model["slots"], self._model["visits"]
        tried = visits > 0
        return int(np.count_nonzero(slots[tried])) + int(np.count_nonzero(tried))

    def reserve_reverse(self, entries: int) -> None:
        """Make room for ``entries`` more reverse-index entries (GDQ's default variant;
        the runners call it with what the coming steps can add)."""
        t = self.tables
        if self.kind != core.KIND_PRIOR or len(t.rev_pair) - int(t.rev_n[0]) >= entries:
            return
        capacity = max(2 * len(t.rev_pair), int(t.rev_n[0]) + entries)
        rev_next = np.full(capacity, -1, dtype=np.int64)
        rev_pair = np.zeros(capacity, dtype=np.int64)
        rev_next[:len(t.rev_next)] = t.rev_next
        rev_pair[:len(t.rev_pair)] = t.rev_pair
        self._rev_capacity = capacity
        self.tables = t._replace(rev_next=rev_next, rev_pair=rev_pair)

    def observe(self, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
                rng: np.random.Generator) -> None:
        if self.kind == core.KIND_PRIOR:
            self.reserve_reverse(core.rev_room(self.max_successors))
        super().observe(s, a, r, s2, terminated, truncated, rng)

    def _init_task(self) -> None:
        """OptInit: value iteration on the hybrid model (``model``), Algorithm 1 read
        literally (``literal``) or the authors' code's shortcut (``code``)."""
        self.q[:, :] = 0.0
        if self.kind == core.KIND_PRIOR:
            tol = 1e-9 * max(1.0, self.params.r_max)
            if core.prior_optinit(self.tables, self.params, tol, 1_000_000) < 0:
                raise AssertionError("reverse index sized too small")  # _prior_arrays
        elif self.config.variant == "literal":
            self.policy = core.policy_iteration(self.tables, self.params)
            return
        else:
            core.seed_plan_pairs(self.tables, self.params.r_max)
        self.policy = core.greedy(self.tables, self.params)

    @property
    def optimistic_pairs(self) -> np.ndarray:
        """bool[S, A]: OptInit's plan pairs (R = R_max in the optimistic model of the
        ``literal`` variant; Q = R_max in the ``code`` variant's OptInit)."""
        return self.tables.opt_r

    @property
    def applicable(self) -> np.ndarray:
        """bool[S, A]: what the knowledge says can do something (``model``; the max ranges
        over it and the known pairs, exploration draws from it with ``explore=
        "applicable"``), a view of the prior."""
        return self._prior(self.context).applicable


METHODS: dict[str, tuple[type[TabularLearner], type[LearnerConfig]]] = {
    "qlearning": (QLearning, QLearningConfig),
    "dynaq": (DynaQ, DynaQConfig),
    "darling": (Darling, DarlingConfig),
    "gdq": (GDQ, GDQConfig),
}


def make_learner(method: str, context: TaskContext, **config: object) -> TabularLearner:
    """A learner by name (``qlearning``, ``dynaq``, ``darling``, ``gdq``) with config
    overrides, e.g. ``make_learner("gdq", ctx, variant="code")``."""
    key = method.lower().replace("-", "").replace("_", "")
    if key not in METHODS:
        raise ValueError(f"unknown method {method!r} (known: {', '.join(METHODS)})")
    cls, cfg = METHODS[key]
    return cls(context, cfg(**config))  # type: ignore[arg-type]
