"""A learner's arrays, its Q table, and how it acts: the part every learner shares.

Every learner is the same data, :class:`Tables` (five groups, one per concern; a compiled
function takes the groups it touches), plus scalar :class:`Params` whose ``kind`` says
which rules run after a real step (:data:`gdq_pddl.learners.rules.KIND_RULES`).

``allowed`` is what the max ranges over (the update's target and the greedy choice);
``guide`` is what exploration draws from. They differ for DARLING-code (a greedy action
outside ``guide`` is replaced by a draw from it) and the default GDQ with
``explore="plans"`` or ``"applicable"``; with ``"values"`` (its default) it draws among the
allowed actions near the best instead (``Params.explore_band``), and ``guide`` is every
action, unread.

A state's actions are the columns of its row: every learner action in the office; for a
PDDL problem the ground actions applicable in the state (``TaskContext.columns``), left-
packed, with padding columns (never in ``allowed`` or ``guide``) up to the longest row.
``n_live[s]`` counts the columns of state ``s`` that are not padding.

The compiled functions trust their arguments (:mod:`gdq_pddl.learners.guards` checks
them); why the small ones are ``inline="always"``: ``docs/learners.md``, "Speed".
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

KIND_QLEARNING, KIND_DYNAQ, KIND_DARLING, KIND_GDQ_PLANS, KIND_GDQ = 0, 1, 2, 3, 4
"""Which rules run after a real step. ``KIND_GDQ``: the default GDQ (the knowledge as a
prior, :mod:`gdq_pddl.learners.gdq`); ``KIND_GDQ_PLANS``: the paper's readings,
GDQ-literal and GDQ-code (backups along plans, :mod:`gdq_pddl.learners.gdq_paper`)."""
BACKUP_EXPECTED, BACKUP_SAMPLE = 0, 1


class Params(NamedTuple):
    """Scalar settings of a learner for the current task."""

    kind: int
    alpha: float
    gamma: float
    epsilon: float
    r_max: float
    n_backups: int
    m: int
    backup: int
    """BACKUP_EXPECTED (assign the expected value) or BACKUP_SAMPLE (TD on a sample)."""
    s0: int
    """The task's start learner state (target of the optimistic transitions)."""
    opt_continue: float = 1.0
    """1: an optimistic transition leads to s0 (the paper); 0: it ends the episode."""
    explore_all: float = 0.0
    """Share of exploring steps that draw from every action instead of ``guide``."""
    explore_all_last: float = 1.0
    """0: no such draw where the knowledge reaches the goal in one action (``KIND_GDQ``)."""
    prior_cost: float = 1.0
    """Step cost of a pair still on the prior (``KIND_GDQ``; besides ``Prior.reward``
    where that is not empty)."""
    sweep_threshold: float = 0.0
    """Smallest change of a state value that prioritised sweeping propagates."""
    prior_weight: float = 0.0
    """Pseudo-observations of the prior in a known pair's model (``KIND_GDQ``)."""
    own_scale: float = 0.0
    """1: the problem's own reward scale (an IPPC file's rewards): the learned model charges
    a trial that ended stuck the pair's mean step cost, not -r_max, and a step that
    reached the goal its mean cost besides r_max, as the env pays them."""
    explore_band: float = -1.0
    """``KIND_GDQ``: at least 0, an exploring step (but for the ``explore_all`` share) draws
    among the allowed actions whose Q is within this tolerance of the state's value,
    ``q >= v - explore_band * max(0, r_max - v)``; below 0, from ``guide``."""
    explore_loops: float = 1.0
    """``KIND_GDQ`` with ``explore_band``: 0, such a draw leaves out a move that a greedy
    step from where the prior says it leads would undo (:func:`_undone`)."""


class QTable(NamedTuple):
    """The Q table of the current task and what acting reads (this module)."""

    q: np.ndarray  # float64[S, A]
    v: np.ndarray  # float64[S], max of q over allowed actions
    allowed: np.ndarray  # bool[S, A], what the max (v, greedy) ranges over
    guide: np.ndarray  # bool[S, A], what exploration draws from (module doc)
    n_guide: np.ndarray  # int64[S], the count of guide[s], at least 1
    goal: np.ndarray  # bool[S], goal learner states of the current task
    n_live: np.ndarray  # int64[S], the columns of state s that are actions (module doc)


class Model(NamedTuple):
    """The learned model, kept across tasks (:mod:`gdq_pddl.learners.learned_model`)."""

    slots: np.ndarray  # int64[S, A, K]: s' << 32 | count, sorted, 0 = empty
    stuck: np.ndarray  # int64[S, A]
    visits: np.ndarray  # int64[S, A]
    cost_sum: np.ndarray  # float64[S, A]
    cost_n: np.ndarray  # int64[S, A]
    cost_all: np.ndarray  # float64[2]: sum and number of all recorded step costs
    known: np.ndarray  # int64[S * A]: pairs s * A + a in the order they became known
    n_known: np.ndarray  # int64[1]


class Plans(NamedTuple):
    """The plans of GDQ-literal and GDQ-code (:mod:`gdq_pddl.learners.gdq_paper`): a
    :class:`~gdq_pddl.abstraction.PlanTable` of the current task, and OptInit's pairs."""

    opt_r: np.ndarray  # bool[S, A], OptInit's plan pairs (R = R_max in the optimism)
    plan_ptr: np.ndarray  # int64[S + 1]: plans from state s ...
    pair_ptr: np.ndarray  # int64[P + 1]: ... the pairs of plan k ...
    pair_state: np.ndarray  # int64[N]: ... as states
    pair_action: np.ndarray  # int64[N]: ... and actions


class Prior(NamedTuple):
    """The default GDQ's prior and the index of what each state's value feeds
    (:mod:`gdq_pddl.learners.gdq`; empty arrays for the other learners)."""

    next_state: np.ndarray  # int64[S, A]: the knowledge's successor, -1 = no change
    pp_ptr: np.ndarray  # int64[S + 1]: applicable pairs by prior successor (CSR) ...
    pp_pair: np.ndarray  # int64[E]: ... as s * A + a
    rev_head: np.ndarray  # int64[S]: first reverse entry of a successor state, -1 none
    rev_next: np.ndarray  # int64[C]: next entry of the same successor, -1 none
    rev_pair: np.ndarray  # int64[C]: the known pair s * A + a of an entry
    rev_n: np.ndarray  # int64[1]: entries used
    reward: np.ndarray  # float64[S, A] on a problem's own scale, float64[0, 0] else: the
    # most the file pays for a trial of a pair (TaskContext.prior_reward), which a prior
    # step pays besides -Params.prior_cost
    dead: np.ndarray  # float64[S, A] where the knowledge has dead ends, float64[0, 0] else:
    # a pair's chance of one (PriorModel.dead), which the prior values as a dead end


class Queue(NamedTuple):
    """The default GDQ's sweep queue: states whose value change awaits propagation, a
    max-heap by the size of the change (empty arrays for the other learners)."""

    heap: np.ndarray  # int64[S]: the queued states, heap-ordered
    pos: np.ndarray  # int64[S]: a state's place in ``heap``, -1 when not queued
    prio: np.ndarray  # float64[S]: a queued state's priority (size of its value change)
    n: np.ndarray  # int64[1]: states queued


class NoOwn(NamedTuple):
    """The :attr:`Tables.own` group of a learner with no arrays of its own."""

    none: np.ndarray  # float64[0], never read
    SPEC = {"none": (np.dtype(np.float64), "0", None)}
    """Each field's ``(dtype, shape, values)`` as :data:`gdq_pddl.learners.guards.TABLES`
    writes them (a learner's own group says its own)."""


NO_OWN = NoOwn(np.zeros(0))
"""The own group of the learners that need none."""


class Tables(NamedTuple):
    """All arrays of a learner, S states x A actions, by concern. ``own``: a learner's own
    arrays (a NamedTuple of its type, e.g. a shaping potential; :data:`NO_OWN` for most),
    which its rules read; numba compiles the rules and the episode loop for each type,
    saving keeps it as ``own.FIELD``, and the guards check it against its class's
    ``SPEC``."""

    table: QTable
    model: Model
    plans: Plans
    prior: Prior
    queue: Queue
    own: NamedTuple = NO_OWN


def table_bytes(n_states: int, n_actions: int, max_successors: int) -> int:
    """Bytes of a learner's per-pair arrays at most (the default GDQ's): Q, the allowed,
    guide and optimistic masks, the model's visits, stuck, costs, known list and int64
    slots, the prior's successors and reverse edges and, when every pair is known, the
    reverse index (an entry of two int64 per successor)."""
    per_pair = 8 * 6 + 3 + 8 * max_successors + 8 + 8 + 16 * max_successors
    return n_states * n_actions * per_pair


# --- the Q table and its maximum ---------------------------------------------------------

@numba.njit(cache=True, inline="always")
def _best(q: np.ndarray, allowed: np.ndarray, s: int) -> float:
    best = -np.inf
    for a in range(q.shape[1]):
        if allowed[s, a] and q[s, a] > best:
            best = q[s, a]
    return best


@numba.njit(cache=True)
def recompute_all_v(table: QTable) -> None:
    """``v[s] <- max`` of ``q[s, a]`` over the allowed actions, every ``s``."""
    q, v, allowed = table.q, table.v, table.allowed
    for s in range(q.shape[0]):
        v[s] = _best(q, allowed, s)


@numba.njit(cache=True, inline="always")
def set_q(table: QTable, s: int, a: int, value: float) -> None:
    """``q[s, a] <- value``, keeping ``v`` exact."""
    set_q_arrays(table.q, table.v, table.allowed, s, a, value)


@numba.njit(cache=True, inline="always")
def set_q_arrays(q: np.ndarray, v: np.ndarray, allowed: np.ndarray, s: int, a: int,
                 value: float) -> None:
    """:func:`set_q` on the arrays, for the sweep's inner loop (no tuple field reads)."""
    old = q[s, a]
    q[s, a] = value
    if not allowed[s, a]:
        return
    if value >= v[s]:
        v[s] = value
    elif old >= v[s]:
        v[s] = _best(q, allowed, s)


@numba.njit(cache=True, inline="always")
def td_update(table: QTable, s: int, a: int, target: float, alpha: float) -> None:
    """``Q(s,a) += alpha (target - Q(s,a))``: real and sample-based simulated experience."""
    q = table.q
    set_q(table, s, a, q[s, a] + alpha * (target - q[s, a]))


# --- acting --------------------------------------------------------------------------------

@numba.njit(cache=True, inline="always")
def draw_guided(table: QTable, s: int, rng: np.random.Generator) -> int:
    """A uniformly random action of ``guide[s]``."""
    k = rng.integers(0, table.n_guide[s])
    guide = table.guide
    for a in range(guide.shape[1]):
        if guide[s, a]:
            if k == 0:
                return a
            k -= 1
    return 0  # unreachable: n_guide[s] counts guide[s]


@numba.njit(cache=True)
def act_plain(table: QTable, visits: np.ndarray, prior: Prior, p: Params, s: int,
              rng: np.random.Generator) -> int:
    """Epsilon-greedy, ties broken uniformly at random: with probability epsilon a uniform
    action of ``guide[s]``, else a uniform maximiser of Q over ``allowed[s]``, which
    DARLING replaces by a uniform action of ``guide[s]`` if it is not in it
    (:func:`greedy_draw`). The acting rule of every built-in learner but the default GDQ,
    whose exploring rules are its own (:func:`gdq_pddl.learners.gdq.act`); ``visits`` and
    ``prior`` are unread (every acting rule takes the same arguments)."""
    if rng.random() < p.epsilon:
        return draw_guided(table, s, rng)
    return greedy_draw(table, p, s, rng)


@numba.njit(cache=True, inline="always")
def greedy_draw(table: QTable, p: Params, s: int, rng: np.random.Generator) -> int:
    """A uniform maximiser of Q over ``allowed[s]``, which DARLING replaces by a uniform
    action of ``guide[s]`` if it is not in it."""
    q, allowed = table.q, table.allowed
    n_actions = q.shape[1]
    best = table.v[s]
    ties = 0
    last = 0
    for a in range(n_actions):
        if allowed[s, a] and q[s, a] == best:
            ties += 1
            last = a
    if ties > 1:
        k = rng.integers(0, ties)
        for a in range(n_actions):
            if allowed[s, a] and q[s, a] == best:
                if k == 0:
                    last = a
                    break
                k -= 1
    if p.kind == KIND_DARLING and not table.guide[s, last]:
        return draw_guided(table, s, rng)
    return last


def greedy(table: QTable, p: Params) -> np.ndarray:
    """The greedy policy: per state, the lowest-index action of maximal Q among the allowed
    ones (DARLING: ``guide``, which differs from ``allowed`` for DARLING-code); 0 where
    none is allowed. Plain numpy: called once per run, not worth a compile."""
    mask = table.guide if p.kind == KIND_DARLING else table.allowed
    return np.where(mask, table.q, -np.inf).argmax(axis=1).astype(np.int64)
