"""The learning rules, each written once as a numba-compiled function over numpy arrays.

Every learner (Q-learning, Dyna-Q, DARLING, GDQ) is the same data, :class:`Tables`, plus
scalar :class:`Params` whose ``kind`` selects which rules run after a real step:

- :func:`act`: epsilon-greedy with random tie-breaking (over the allowed actions; see
  ``guide`` below for the one learner that acts differently);
- :func:`observe`: the TD update on the real transition, then (model-based learners)
  :func:`record` in the model and N :func:`model_backup` calls;
- :func:`expected_value`: the expected Bellman backup of one pair with the model;
- :func:`policy_iteration`: OptInit's planning on the (optimistic) model.

The Python learner methods and the fast episode loop of :mod:`gdq_pddl.learners.runner`
call these same functions, so each rule has a single definition.

The model (goal-independent, so it survives a task switch)
-------------------------------------------------------------
Per pair ``(s, a)``: ``visits[s, a]`` all trials; ``stuck[s, a]`` trials that failed by
getting stuck; ``cost_sum / cost_n`` the mean step cost over steps with no goal, stuck or
timeout event (pairs never seen in such a step use the mean over all pairs, or 0 before
any); and the transitions to learner states ``s'`` (goal, timeout and ordinary steps
alike), sparse:

- ``slots[s, a, j]``, ``j < K``: ``s' << 32 | count`` (int64, one load per slot;
  :func:`slot_successor`, :func:`slot_count`); 0 is an empty slot. The occupied slots
  come first, sorted by successor (:func:`record` inserts in order), so every loop over
  them meets the successors in increasing ``s'`` exactly as a loop over a dense
  ``counts[s, a, :]`` did: the same sums in the same order, the same sampled outcomes.
- ``K`` is a capacity, the most distinct successors any pair can have
  (:attr:`gdq_pddl.learners.context.TaskContext.max_successors`, from the world's true
  model; the runners raise it to what the env they run in needs). Memory is
  ``S x A x K`` slots instead of ``S x A x S`` counts, and ``np.zeros`` leaves the pages
  of untried pairs unwritten. The model-free learners get ``K = 0``: their
  :func:`observe` returns before the model.
- A transition that finds no free slot is not recorded at all: :func:`record` and
  :func:`observe` return False and their callers (the learners' ``observe``, the
  compiled episode loop) raise ValueError(:data:`OVERFLOW`). Not a raise in here: see
  :func:`add_successor`.

The expected backup for the current goal states G is::

    Q(s,a) = sum_s' T(s,a,s') * (R_max if s' in G else -cost(s,a) + gamma * V(s'))
             + P_stuck(s,a) * (-R_max)

with ``T(s,a,s') = count / visits`` over the slots of ``(s, a)`` and
``P_stuck = stuck / visits``. A step-limit timeout is not part of this Markov model (its
transition is counted, its -R_max is not). No backup bootstraps through a terminal
transition: reaching G or getting stuck ends the sum.

A pair is *known* when ``visits > m``. In expected backups (GDQ-literal) unknown
pairs use the optimistic model of OptInit instead: ``T(s,a,s0) = 1`` and ``R = R_max``
on OptInit's plan pairs (``opt_r``), 0 elsewhere, i.e. ``Q(s,a) = R + gamma * V(s0)``.
Sample-based backups (the authors' code) only replay recorded outcomes of pairs tried
at least once and leave untried pairs alone.

``v[s]`` is kept equal to ``max`` of ``q[s, a]`` over the allowed actions of ``s`` by
:func:`set_q`, the only writer of single Q entries.

``allowed`` is what the max ranges over (the update's target and the greedy choice);
``guide`` is what exploration draws uniformly from. They are the same array for every
learner except two. DARLING as the GDQ authors' code runs it: its max ranges over all
actions while it may only execute plan actions, so a greedy action outside ``guide`` is
replaced by a draw from it (DARLING only). GDQ's default: ``allowed`` holds the
knowledge-applicable and the known pairs, ``guide`` the first actions of the plans
(section "Planning on the prior"); its greedy action is never replaced.

Randomness comes only from the ``np.random.Generator`` passed in.

Speed. A call of a compiled function that is not inlined and takes :class:`Tables` costs
a reference-count update per array the tuple holds; the small rules called in inner loops
(``set_q``, ``td_update``, ``record``, the backups' value functions) are therefore
``inline="always"`` (Task C, env steps/s: Q-learning 531k -> 1.05M, Dyna-Q 165k -> 260k,
GDQ 182k -> 215k, ``benchmarks/learners.py speed``, same run), while ``act`` and
``observe`` stay calls: inlining ``observe`` into the episode loop made numba 0.68
compile a loop whose results differ from the Python path's (caught by the fast == Python
tests), and inlining more tripled the compile time.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

KIND_QLEARNING, KIND_DYNAQ, KIND_DARLING, KIND_GDQ, KIND_PRIOR = 0, 1, 2, 3, 4
"""``KIND_GDQ``: GDQ's ``literal`` and ``code`` variants (backups along plans);
``KIND_PRIOR``: GDQ's default, planning on the knowledge's prior model (section below)."""
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
    """0: no such draw in a state from which the knowledge reaches the goal in one action
    (``KIND_PRIOR``)."""
    prior_cost: float = 1.0
    """Step cost of a pair still on the prior model (``KIND_PRIOR``)."""
    sweep_threshold: float = 0.0
    """Smallest change of a state value that prioritised sweeping propagates."""
    prior_weight: float = 0.0
    """Pseudo-observations of the prior in a known pair's model (``KIND_PRIOR``)."""


class Tables(NamedTuple):
    """All arrays of a learner (see the module docstring)."""

    q: np.ndarray  # float64[S, A]
    v: np.ndarray  # float64[S], max of q over allowed actions
    allowed: np.ndarray  # bool[S, A], what the max (v, greedy) ranges over
    guide: np.ndarray  # bool[S, A], what may be executed (module doc); usually `allowed`
    n_guide: np.ndarray  # int64[S]
    goal: np.ndarray  # bool[S], goal learner states of the current task
    opt_r: np.ndarray  # bool[S, A], OptInit's plan pairs (R = R_max in the optimistic model)
    slots: np.ndarray  # int64[S, A, K]: s' << 32 | count, sorted, 0 = empty (module doc)
    stuck: np.ndarray  # int64[S, A]
    visits: np.ndarray  # int64[S, A]
    cost_sum: np.ndarray  # float64[S, A]
    cost_n: np.ndarray  # int64[S, A]
    cost_all: np.ndarray  # float64[2]: sum and number of all recorded step costs
    known: np.ndarray  # int64[S * A]: pairs s * A + a in the order they became known
    n_known: np.ndarray  # int64[1]
    plan_ptr: np.ndarray  # PlanTable (tolerance 0) arrays of the current task
    pair_ptr: np.ndarray
    pair_state: np.ndarray
    pair_action: np.ndarray
    # KIND_PRIOR only (empty arrays for the other kinds; see "Planning on the prior")
    prior_next: np.ndarray  # int64[S, A]: the knowledge's successor, -1 = no change
    pp_ptr: np.ndarray  # int64[S + 1]: applicable pairs by prior successor (CSR) ...
    pp_pair: np.ndarray  # int64[E]: ... as s * A + a
    rev_head: np.ndarray  # int64[S]: first reverse entry of a successor state, -1 none
    rev_next: np.ndarray  # int64[C]: next entry of the same successor, -1 none
    rev_pair: np.ndarray  # int64[C]: the known pair s * A + a of an entry
    rev_n: np.ndarray  # int64[1]: entries used
    heap: np.ndarray  # int64[S]: states whose value change awaits propagation (max-heap)
    heap_pos: np.ndarray  # int64[S]: a state's place in ``heap``, -1 when not queued
    heap_prio: np.ndarray  # float64[S]: a queued state's priority (size of its value change)
    heap_n: np.ndarray  # int64[1]


def new_model(n_states: int, n_actions: int, max_successors: int,
              transitions: bool = True) -> dict[str, np.ndarray]:
    """Fresh (empty) model arrays, the part of :class:`Tables` kept across tasks.

    ``max_successors`` slots per pair for the transitions, none (``K = 0``) when
    ``transitions`` is False (the model-free learners never record one).
    """
    k = int(max_successors) if transitions else 0
    return {
        "slots": np.zeros((n_states, n_actions, k), dtype=np.int64),
        "stuck": np.zeros((n_states, n_actions), dtype=np.int64),
        "visits": np.zeros((n_states, n_actions), dtype=np.int64),
        "cost_sum": np.zeros((n_states, n_actions), dtype=np.float64),
        "cost_n": np.zeros((n_states, n_actions), dtype=np.int64),
        "cost_all": np.zeros(2, dtype=np.float64),
        "known": np.zeros(n_states * n_actions, dtype=np.int64),
        "n_known": np.zeros(1, dtype=np.int64),
    }


def with_successor_slots(model: dict[str, np.ndarray],
                         max_successors: int) -> dict[str, np.ndarray]:
    """``model`` with at least ``max_successors`` slots per pair (a copy of the slot
    array when it had fewer, the recorded transitions kept; else ``model`` itself)."""
    slots = model["slots"]
    n_states, n_actions, k = slots.shape
    if max_successors <= k:
        return model
    wider = np.zeros((n_states, n_actions, max_successors), dtype=np.int64)
    wider[:, :, :k] = slots
    return {**model, "slots": wider}


SLOT_SHIFT = 32
COUNT_MASK = (1 << SLOT_SHIFT) - 1
"""A slot is ``successor << SLOT_SHIFT | count``: successors below 2**31, counts up to
2**32 - 1 per (pair, successor)."""


@numba.njit(cache=True)
def slot_successor(slot: int) -> int:
    return slot >> SLOT_SHIFT


@numba.njit(cache=True)
def slot_count(slot: int) -> int:
    return slot & COUNT_MASK


def dense_counts(slots: np.ndarray, n_states: int) -> np.ndarray:
    """The transition counts as a dense int64 ``[S, A, n_states]`` array."""
    out = np.zeros((*slots.shape[:2], n_states), dtype=np.int64)
    s, a, j = np.nonzero(slots)
    out[s, a, slots[s, a, j] >> SLOT_SHIFT] = slots[s, a, j] & COUNT_MASK
    return out


def table_bytes(n_states: int, n_actions: int, max_successors: int,
                transitions: bool = True, prior: bool = True) -> int:
    """Bytes of a learner's per-pair arrays at most: Q, the allowed, guide and optimistic
    masks, the model's visits, stuck, costs and known list, (``transitions``) the slots,
    and (``prior``, GDQ's default) the prior's successors and reverse edges and, when
    every pair is known, the reverse index (an entry of two int64 per successor)."""
    per_pair = 8 * 6 + 3 + (8 * max_successors if transitions else 0)  # int64 slots
    if prior:
        per_pair += 8 + 8 + 16 * (max_successors if transitions else 1)
    return n_states * n_actions * per_pair


# --- Q table and its maximum -------------------------------------------------------------

@numba.njit(cache=True, inline="always")
def recompute_v(t: Tables, s: int) -> None:
    """``v[s] <- max`` of ``q[s, a]`` over the allowed actions."""
    _recompute_v(t.q, t.v, t.allowed, s)


# The rules that run in inner loops take arrays, not Tables: a call that takes the tuple
# costs a reference count update per array it holds (measured: GDQ's default variant's
# backup took 650 ns through Tables, 60 ns on arrays).
@numba.njit(cache=True, inline="always")
def _recompute_v(q: np.ndarray, v: np.ndarray, allowed: np.ndarray, s: int) -> None:
    best = -np.inf
    for a in range(q.shape[1]):
        if allowed[s, a] and q[s, a] > best:
            best = q[s, a]
    v[s] = best


@numba.njit(cache=True)
def recompute_all_v(t: Tables) -> None:
    for s in range(t.q.shape[0]):
        recompute_v(t, s)


@numba.njit(cache=True, inline="always")
def set_q(t: Tables, s: int, a: int, value: float) -> None:
    """``q[s, a] <- value``, keeping ``v`` exact."""
    _set_q(t.q, t.v, t.allowed, s, a, value)


@numba.njit(cache=True, inline="always")
def _set_q(q: np.ndarray, v: np.ndarray, allowed: np.ndarray, s: int, a: int,
           value: float) -> None:
    old = q[s, a]
    q[s, a] = value
    if not allowed[s, a]:
        return
    if value >= v[s]:
        v[s] = value
    elif old >= v[s]:
        _recompute_v(q, v, allowed, s)


@numba.njit(cache=True, inline="always")
def td_update(t: Tables, s: int, a: int, target: float, alpha: float) -> None:
    """``Q(s,a) += alpha (target - Q(s,a))``: real and sample-based simulated experience."""
    set_q(t, s, a, t.q[s, a] + alpha * (target - t.q[s, a]))


# --- acting --------------------------------------------------------------------------------

@numba.njit(cache=True, inline="always")
def _draw_guided(t: Tables, s: int, rng: np.random.Generator) -> int:
    """A uniformly random action of ``guide[s]``."""
    k = rng.integers(0, t.n_guide[s])
    for a in range(t.q.shape[1]):
        if t.guide[s, a]:
            if k == 0:
                return a
            k -= 1
    return 0  # unreachable: n_guide[s] counts guide[s]


@numba.njit(cache=True)
def _draw_untried(visits: np.ndarray, s: int, rng: np.random.Generator) -> int:
    """A uniformly random action never tried in ``s``; any action once all were."""
    n_actions = visits.shape[1]
    n = 0
    for a in range(n_actions):
        n += visits[s, a] == 0
    if n == 0:
        return rng.integers(0, n_actions)
    k = rng.integers(0, n)
    for a in range(n_actions):
        if visits[s, a] == 0:
            if k == 0:
                return a
            k -= 1
    return 0


@numba.njit(cache=True, inline="always")
def _one_step_from_goal(t: Tables, p: Params, s: int) -> bool:
    """Whether the knowledge reaches the goal from ``s`` in one action (``KIND_PRIOR``)."""
    if p.kind != KIND_PRIOR:
        return False
    for a in range(t.prior_next.shape[1]):
        s2 = t.prior_next[s, a]
        if s2 >= 0 and t.goal[s2]:
            return True
    return False


@numba.njit(cache=True)
def act(t: Tables, p: Params, s: int, rng: np.random.Generator) -> int:
    """Epsilon-greedy, ties broken uniformly at random (module doc: allowed and guide).

    With probability epsilon a uniform action of ``guide[s]`` (or, for a share
    ``explore_all`` of those steps, of every action, unless ``explore_all_last`` is 0 and
    the knowledge reaches the goal from ``s`` in one action); else a uniformly chosen maximiser
    of Q over ``allowed[s]``, which DARLING replaces by a uniform action of ``guide[s]``
    if it is not in it (never, when ``guide`` is ``allowed``). Draws one uniform, one more
    when exploring with ``explore_all > 0``, then one integer when exploring or when
    several actions tie, and one more for a replacement.
    """
    n_actions = t.q.shape[1]
    if rng.random() < p.epsilon:
        if p.explore_all > 0.0 and rng.random() < p.explore_all and (
                p.explore_all_last > 0.0 or not _one_step_from_goal(t, p, s)):
            return _draw_untried(t.visits, s, rng)
        return _draw_guided(t, s, rng)
    best = t.v[s]
    ties = 0
    last = 0
    for a in range(n_actions):
        if t.allowed[s, a] and t.q[s, a] == best:
            ties += 1
            last = a
    if ties > 1:
        k = rng.integers(0, ties)
        for a in range(n_actions):
            if t.allowed[s, a] and t.q[s, a] == best:
                if k == 0:
                    last = a
                    break
                k -= 1
    if p.kind == KIND_DARLING and not t.guide[s, last]:
        return _draw_guided(t, s, rng)
    return last


@numba.njit(cache=True)
def greedy(t: Tables, p: Params) -> np.ndarray:
    """The greedy policy: per state, the lowest-index action of maximal Q among those it
    may execute: the allowed ones (DARLING: ``guide``, which is ``allowed`` but for
    DARLING-code)."""
    n_states, n_actions = t.q.shape
    mask = t.guide if p.kind == KIND_DARLING else t.allowed
    out = np.zeros(n_states, dtype=np.int64)
    for s in range(n_states):
        best = -np.inf
        for a in range(n_actions):
            if mask[s, a] and t.q[s, a] > best:
                best = t.q[s, a]
                out[s] = a
    return out


# --- the model -----------------------------------------------------------------------------

OVERFLOW = ("a (state, action) pair has more distinct successors than the learner's model "
            "has slots (TaskContext.max_successors); give it more with reserve_successors")
"""Why :func:`record` or :func:`observe` returned False (raised by their callers)."""


@numba.njit(cache=True)
def add_successor(slots: np.ndarray, s: int, a: int, s2: int) -> bool:
    """Count one transition ``(s, a) -> s2`` in the slots of ``(s, a)``, keeping them
    sorted by successor. False (nothing changed) when ``s2`` is new and every slot is
    taken.

    Takes the slot array, not :class:`Tables`, and returns a status instead of raising
    (both measured): reading tuple fields inside a loop cost a reference count update
    per read (the loop 4 x slower), and a callee that can raise makes every caller that
    holds the tuple update the counts of all its arrays on each call.
    """
    key = np.int64(s2) << SLOT_SHIFT
    n_slots = slots.shape[2]
    for j in range(n_slots):
        here = slots[s, a, j]
        if here == 0:  # the first empty slot: s2 is new and larger than all before
            slots[s, a, j] = key + 1
            return True
        if slot_successor(here) == s2:
            slots[s, a, j] = here + 1
            return True
        if here > key:  # a larger successor: insert s2 here, shifting the rest up
            if slots[s, a, n_slots - 1] != 0:
                return False
            for jj in range(n_slots - 1, j, -1):
                slots[s, a, jj] = slots[s, a, jj - 1]
            slots[s, a, j] = key + 1
            return True
    return False


@numba.njit(cache=True, inline="always")
def record(t: Tables, p: Params, s: int, a: int, r: float, s2: int, terminated: bool,
           truncated: bool) -> bool:
    """Count one real transition in the goal-independent model; False, and nothing
    recorded, when its successor finds no free slot (:data:`OVERFLOW`)."""
    if terminated and not t.goal[s2]:
        t.stuck[s, a] += 1
    elif not add_successor(t.slots, s, a, s2):
        return False
    if not terminated and not truncated:
        t.cost_sum[s, a] -= r
        t.cost_n[s, a] += 1
        t.cost_all[0] -= r
        t.cost_all[1] += 1.0
    t.visits[s, a] += 1
    if t.visits[s, a] == p.m + 1:
        t.known[t.n_known[0]] = s * t.q.shape[1] + a
        t.n_known[0] += 1
    return True


@numba.njit(cache=True, inline="always")
def mean_cost(t: Tables, s: int, a: int) -> float:
    return _mean_cost(t.cost_sum, t.cost_n, t.cost_all, s, a)


@numba.njit(cache=True, inline="always", error_model="numpy")
def _mean_cost(cost_sum: np.ndarray, cost_n: np.ndarray, cost_all: np.ndarray, s: int,
               a: int) -> float:
    """The mean step cost of ``(s, a)``; of every pair where it has none; else 0."""
    if cost_n[s, a] > 0:
        return cost_sum[s, a] / cost_n[s, a]
    if cost_all[1] > 0:
        return cost_all[0] / cost_all[1]
    return 0.0


@numba.njit(cache=True, inline="always")
def expected_value(t: Tables, p: Params, s: int, a: int, v: np.ndarray) -> float:
    """The expected Bellman backup of ``(s, a)`` under the model, with state values ``v``.

    Known pairs (``visits > m``) use the learned model, unknown ones the optimistic one.
    """
    if t.visits[s, a] > p.m:
        return learned_value(t, p, s, a, v)
    r = p.r_max if t.opt_r[s, a] else 0.0
    return r + p.opt_continue * p.gamma * v[p.s0]


@numba.njit(cache=True, inline="always")
def learned_value(t: Tables, p: Params, s: int, a: int, v: np.ndarray) -> float:
    """The expected Bellman backup of ``(s, a)`` under the learned model (``visits > 0``),
    with state values ``v``."""
    return _learned(t.slots, t.stuck, t.visits, t.cost_sum, t.cost_n, t.cost_all, t.goal, v,
                    s, a, p.r_max, p.gamma)


@numba.njit(cache=True, inline="always", error_model="numpy")
def _learned(slots: np.ndarray, stuck: np.ndarray, visits: np.ndarray, cost_sum: np.ndarray,
             cost_n: np.ndarray, cost_all: np.ndarray, goal: np.ndarray, v: np.ndarray,
             s: int, a: int, r_max: float, gamma: float) -> float:
    c = _mean_cost(cost_sum, cost_n, cost_all, s, a)
    total = stuck[s, a] * -r_max
    for j in range(slots.shape[2]):  # successors in increasing order
        here = slots[s, a, j]
        if here == 0:
            break
        k = slot_count(here)
        s2 = slot_successor(here)
        if goal[s2]:
            total += k * r_max
        else:
            total += k * (gamma * v[s2] - c)
    return total / visits[s, a]


@numba.njit(cache=True, inline="always")
def sample_outcome(t: Tables, p: Params, s: int, a: int,
                   rng: np.random.Generator) -> tuple[float, int, bool]:
    """One ``(reward, next state, terminal)`` drawn from the experience of ``(s, a)``.

    The pair must have been tried (``visits > 0``): the draw replays a recorded outcome
    (stuck, goal, or an ordinary step at the pair's mean cost), never the optimistic model.
    """
    k = rng.integers(0, t.visits[s, a])
    if k < t.stuck[s, a]:
        return -p.r_max, s, True
    k -= t.stuck[s, a]
    slots = t.slots  # a local: a tuple field read in a loop costs more
    for j in range(slots.shape[2]):  # successors in increasing order
        k -= slot_count(slots[s, a, j])
        if k < 0:
            s2 = slot_successor(slots[s, a, j])
            if t.goal[s2]:
                return p.r_max, s2, True
            return -mean_cost(t, s, a), s2, False
    return -mean_cost(t, s, a), s, False  # unreachable: counts + stuck == visits


@numba.njit(cache=True)
def model_backup(t: Tables, p: Params, s: int, a: int, rng: np.random.Generator) -> None:
    """One simulated update of ``(s, a)``.

    ``BACKUP_EXPECTED``: assign the expected backup under the model (learned for known
    pairs, optimistic otherwise). ``BACKUP_SAMPLE`` (the authors' code): a TD update on an
    outcome replayed from experience; a pair never tried is left alone.
    """
    if p.backup == BACKUP_EXPECTED:
        set_q(t, s, a, expected_value(t, p, s, a, t.v))
    elif t.visits[s, a] > 0:
        r, s2, terminal = sample_outcome(t, p, s, a, rng)
        target = r if terminal else r + p.gamma * t.v[s2]
        td_update(t, s, a, target, p.alpha)


@numba.njit(cache=True)
def backup_known(t: Tables, p: Params, rng: np.random.Generator) -> None:
    """Dyna-Q planning: N backups of uniformly random known pairs."""
    nk = t.n_known[0]
    if nk == 0:
        return
    n_actions = t.q.shape[1]
    for _ in range(p.n_backups):
        i = t.known[rng.integers(0, nk)]
        model_backup(t, p, i // n_actions, i % n_actions, rng)


@numba.njit(cache=True)
def backup_plans(t: Tables, p: Params, s: int, rng: np.random.Generator) -> bool:
    """GDQ planning: N backups of a random transition of a random plan from ``s``.

    Returns False (and does nothing) when ``s`` has no plan.
    """
    lo, hi = t.plan_ptr[s], t.plan_ptr[s + 1]
    if hi <= lo:
        return False
    for _ in range(p.n_backups):
        k = lo + rng.integers(0, hi - lo)
        j = t.pair_ptr[k] + rng.integers(0, t.pair_ptr[k + 1] - t.pair_ptr[k])
        model_backup(t, p, t.pair_state[j], t.pair_action[j], rng)
    return True


@numba.njit(cache=True)
def observe(t: Tables, p: Params, s: int, a: int, r: float, s2: int, terminated: bool,
            truncated: bool, rng: np.random.Generator) -> bool:
    """Everything a learner does after one real step ``(s, a, r, s2)``.

    TD update (a terminated or truncated step's target is ``r`` alone); then, for the
    model-based learners, count the transition and run the N model backups. False when
    the model had no slot for the transition (:func:`record`; no backups then): the
    callers raise ValueError(:data:`OVERFLOW`).
    """
    if p.kind == KIND_PRIOR:
        return prior_observe(t, p, s, a, r, s2, terminated, truncated)
    target = r if (terminated or truncated) else r + p.gamma * t.v[s2]
    td_update(t, s, a, target, p.alpha)
    if p.kind == KIND_QLEARNING or p.kind == KIND_DARLING:
        return True
    if not record(t, p, s, a, r, s2, terminated, truncated):
        return False
    if p.kind == KIND_GDQ and backup_plans(t, p, s, rng):
        return True
    backup_known(t, p, rng)
    return True


# --- OptInit -------------------------------------------------------------------------------

@numba.njit(cache=True)
def policy_iteration(t: Tables, p: Params, eval_tol: float = 1e-10,
                     improve_tol: float = 1e-6, max_iter: int = 10_000) -> np.ndarray:
    """Policy iteration on the model (learned for known pairs, optimistic otherwise).

    Starts from the policy "action 0 everywhere", evaluates V^pi (in-place sweeps to
    ``eval_tol``), computes Q(s, a) for every action and improves, keeping the current
    action on ties (within ``improve_tol``) and else taking the lowest index, until the
    policy is stable. Writes that final Q into ``t.q`` (goal rows 0) and returns pi.
    """
    n_states, n_actions = t.q.shape
    pi = np.zeros(n_states, dtype=np.int64)
    v = np.zeros(n_states)
    qq = np.zeros((n_states, n_actions))
    for _ in range(max_iter):
        for _sweep in range(1_000_000):
            delta = 0.0
            for s in range(n_states):
                if t.goal[s]:
                    continue
                x = expected_value(t, p, s, pi[s], v)
                delta = max(delta, abs(x - v[s]))
                v[s] = x
            if delta < eval_tol:
                break
        stable = True
        for s in range(n_states):
            if t.goal[s]:
                continue
            best = -np.inf
            for a in range(n_actions):
                qq[s, a] = expected_value(t, p, s, a, v)
                best = max(best, qq[s, a])
            if qq[s, pi[s]] < best - improve_tol:
                stable = False
                for a in range(n_actions):
                    if qq[s, a] >= best - improve_tol:
                        pi[s] = a
                        break
        if stable:
            break
    t.q[:, :] = qq
    recompute_all_v(t)
    return pi


@numba.njit(cache=True)
def seed_plan_pairs(t: Tables, value: float) -> None:
    """The authors' code's OptInit: Q <- 0, then Q(s, a) <- ``value`` on OptInit's pairs."""
    t.q[:, :] = 0.0
    for s in range(t.q.shape[0]):
        for a in range(t.q.shape[1]):
            if t.opt_r[s, a]:
                t.q[s, a] = value
    recompute_all_v(t)


# --- Planning on the prior (GDQ's default variant, KIND_PRIOR) ------------------------------
#
# Every pair has a value from the *hybrid model*. A pair on the prior (``prior_next``)
# succeeds deterministically, or changes nothing where the knowledge says the action does
# nothing, at cost ``prior_cost``; reaching a goal pays R_max and ends the episode. A
# knowledge-applicable pair is *known* after more than m trials (the prior's optimism
# lasts that long), a knowledge-inapplicable one after its first trial (its prior, "no
# change", is no optimism worth keeping, and a single trial that does something is news
# the learner should plan with at once). A known pair's model is the posterior mean with
# the prior as ``prior_weight`` pseudo-observations: its backup is
# ``(n * learned + w * prior) / (n + w)`` after n trials.
#
# ``allowed`` (what v and the greedy choice range over) holds the knowledge-applicable
# pairs and the known ones, so an action the knowledge says does nothing is never valued
# above an applicable one before it has been tried; a state where nothing is applicable
# allows every action. ``guide`` (what exploration draws from) holds the first actions of
# the plans from each state (or the applicable ones); a share ``explore_all`` of the
# exploring steps draws an action never tried in the state instead (:func:`act`).
#
# OptInit is value iteration on the hybrid model (:func:`prior_optinit`). After a real step
# the learner records it, recomputes the stepped pair if it is known, and runs prioritised
# sweeping: states whose value changed wait in a max-heap by the size of the change;
# popping one recomputes every pair that can lead to it, i.e. the unknown applicable pairs
# whose prior successor it is (``pp_ptr``/``pp_pair``, static) and the known pairs that
# have reached it (the reverse index ``rev_*``, grown as pairs become known), until
# ``n_backups`` pairs have been recomputed. The heap carries what is left to the next step.
# There is no TD update: a pair's value is always its hybrid backup.


@numba.njit(cache=True, inline="always")
def _is_known(visits: np.ndarray, prior_next: np.ndarray, m: int, s: int, a: int) -> bool:
    return visits[s, a] > (m if prior_next[s, a] >= 0 else 0)


@numba.njit(cache=True)
def prior_known(t: Tables, p: Params, s: int, a: int) -> bool:
    """Whether ``(s, a)`` is valued by the learned model (see the section comment)."""
    return _is_known(t.visits, t.prior_next, p.m, s, a)


@numba.njit(cache=True, inline="always", error_model="numpy")
def _hybrid(slots: np.ndarray, stuck: np.ndarray, visits: np.ndarray, cost_sum: np.ndarray,
            cost_n: np.ndarray, cost_all: np.ndarray, goal: np.ndarray, v: np.ndarray,
            prior_next: np.ndarray, p: Params, s: int, a: int) -> float:
    s2 = prior_next[s, a]
    if s2 < 0:
        s2 = s
    prior = p.r_max if goal[s2] else -p.prior_cost + p.gamma * v[s2]
    if _is_known(visits, prior_next, p.m, s, a):
        n = visits[s, a]
        learned = _learned(slots, stuck, visits, cost_sum, cost_n, cost_all, goal, v, s, a,
                           p.r_max, p.gamma)
        w = p.prior_weight
        return (n * learned + w * prior) / (n + w)
    return prior


@numba.njit(cache=True)
def hybrid_value(t: Tables, p: Params, s: int, a: int) -> float:
    """The backup of ``(s, a)`` under the hybrid model, with the current ``v``."""
    return _hybrid(t.slots, t.stuck, t.visits, t.cost_sum, t.cost_n, t.cost_all, t.goal, t.v,
                   t.prior_next, p, s, a)


@numba.njit(cache=True, inline="always")
def _sift_up(heap: np.ndarray, pos: np.ndarray, prio: np.ndarray, i: int) -> None:
    x = heap[i]
    while i > 0:
        parent = (i - 1) // 2
        y = heap[parent]
        if prio[y] >= prio[x]:
            break
        heap[i] = y
        pos[y] = i
        i = parent
    heap[i] = x
    pos[x] = i


@numba.njit(cache=True, inline="always")
def _sift_down(heap: np.ndarray, pos: np.ndarray, prio: np.ndarray, n: int, i: int) -> None:
    x = heap[i]
    while True:
        c = 2 * i + 1
        if c >= n:
            break
        if c + 1 < n and prio[heap[c + 1]] > prio[heap[c]]:
            c += 1
        y = heap[c]
        if prio[y] <= prio[x]:
            break
        heap[i] = y
        pos[y] = i
        i = c
    heap[i] = x
    pos[x] = i


@numba.njit(cache=True, inline="always")
def _push(heap: np.ndarray, pos: np.ndarray, prio: np.ndarray, heap_n: np.ndarray, x: int,
          change: float) -> None:
    """Queue state ``x`` with priority ``change`` (raised to it if already queued)."""
    if pos[x] >= 0:
        if change > prio[x]:
            prio[x] = change
            _sift_up(heap, pos, prio, pos[x])
        return
    n = heap_n[0]
    heap[n] = x
    prio[x] = change
    heap_n[0] = n + 1
    _sift_up(heap, pos, prio, n)


@numba.njit(cache=True, inline="always")
def _pop(heap: np.ndarray, pos: np.ndarray, prio: np.ndarray, heap_n: np.ndarray) -> int:
    """The queued state of highest priority, removed from the queue."""
    x = heap[0]
    n = heap_n[0] - 1
    heap_n[0] = n
    pos[x] = -1
    if n > 0:
        heap[0] = heap[n]
        _sift_down(heap, pos, prio, n, 0)
    return x


@numba.njit(cache=True, inline="always", error_model="numpy")
def _update(q: np.ndarray, v: np.ndarray, allowed: np.ndarray, slots: np.ndarray,
            stuck: np.ndarray, visits: np.ndarray, cost_sum: np.ndarray, cost_n: np.ndarray,
            cost_all: np.ndarray, goal: np.ndarray, prior_next: np.ndarray, heap: np.ndarray,
            heap_pos: np.ndarray, heap_prio: np.ndarray, heap_n: np.ndarray, p: Params,
            s: int, a: int) -> None:
    """Recompute ``q[s, a]``; queue ``s`` if that moved its value by more than the sweep
    threshold. (The untried pairs the knowledge says do nothing are not allowed: nothing
    here reads their Q, which :func:`prior_fill_untried` fills in when it is read.)"""
    old = v[s]
    _set_q(q, v, allowed, s, a, _hybrid(slots, stuck, visits, cost_sum, cost_n, cost_all,
                                        goal, v, prior_next, p, s, a))
    change = abs(v[s] - old)
    if change > p.sweep_threshold:
        _push(heap, heap_pos, heap_prio, heap_n, s, change)


@numba.njit(cache=True, inline="always")
def _rev_add(rev_head: np.ndarray, rev_next: np.ndarray, rev_pair: np.ndarray,
             rev_n: np.ndarray, x: int, pair: int) -> bool:
    """Record that known ``pair`` has reached state ``x``; False when the index is full."""
    e = rev_n[0]
    if e >= rev_pair.shape[0]:
        return False
    rev_pair[e] = pair
    rev_next[e] = rev_head[x]
    rev_head[x] = e
    rev_n[0] = e + 1
    return True


@numba.njit(cache=True, inline="always")
def _prior_successor(prior_next: np.ndarray, s: int, a: int) -> int:
    """Where the prior says ``(s, a)`` leads (``s`` itself where it says "no change")."""
    x = prior_next[s, a]
    return s if x < 0 else x


@numba.njit(cache=True)
def _rev_add_pair(t: Tables, p: Params, s: int, a: int) -> bool:
    """Index the states the newly known pair ``(s, a)``'s backup reads: its recorded
    non-goal successors and, with ``prior_weight > 0``, its prior successor."""
    slots, goal = t.slots, t.goal
    rev_head, rev_next, rev_pair, rev_n = t.rev_head, t.rev_next, t.rev_pair, t.rev_n
    pair = s * t.q.shape[1] + a
    for j in range(slots.shape[2]):
        here = slots[s, a, j]
        if here == 0:
            break
        x = slot_successor(here)
        if not goal[x] and not _rev_add(rev_head, rev_next, rev_pair, rev_n, x, pair):
            return False
    x = _prior_successor(t.prior_next, s, a)
    if p.prior_weight > 0.0 and not goal[x] and not has_successor(slots, s, a, x):
        return _rev_add(rev_head, rev_next, rev_pair, rev_n, x, pair)
    return True


@numba.njit(cache=True, inline="always")
def has_successor(slots: np.ndarray, s: int, a: int, s2: int) -> bool:
    """Whether ``(s, a) -> s2`` has been recorded."""
    for j in range(slots.shape[2]):
        here = slots[s, a, j]
        if here == 0:
            return False
        if slot_successor(here) == s2:
            return True
    return False


@numba.njit(cache=True, error_model="numpy")
def prior_plan(t: Tables, p: Params, s: int, a: int) -> None:
    """Revalue the real step's pair ``(s, a)`` if it is known, then sweep: recompute the
    pairs leading to the most changed states until ``n_backups`` pairs are done (a popped
    state's pairs are all done) or none is queued."""
    q, v, allowed, goal = t.q, t.v, t.allowed, t.goal
    slots, stuck, visits = t.slots, t.stuck, t.visits
    cost_sum, cost_n, cost_all = t.cost_sum, t.cost_n, t.cost_all
    prior_next, pp_ptr, pp_pair = t.prior_next, t.pp_ptr, t.pp_pair
    rev_head, rev_next, rev_pair = t.rev_head, t.rev_next, t.rev_pair
    heap, heap_pos, heap_prio, heap_n = t.heap, t.heap_pos, t.heap_prio, t.heap_n
    n_actions = q.shape[1]
    if _is_known(visits, prior_next, p.m, s, a):
        _update(q, v, allowed, slots, stuck, visits, cost_sum, cost_n, cost_all, goal,
                prior_next, heap, heap_pos, heap_prio, heap_n, p, s, a)
    budget = p.n_backups
    while budget > 0 and heap_n[0] > 0:
        x = _pop(heap, heap_pos, heap_prio, heap_n)
        for k in range(pp_ptr[x], pp_ptr[x + 1]):
            pair = pp_pair[k]
            ps, pa = pair // n_actions, pair % n_actions
            if goal[ps] or _is_known(visits, prior_next, p.m, ps, pa):
                continue  # goal rows keep 0; known pairs are in the reverse index
            _update(q, v, allowed, slots, stuck, visits, cost_sum, cost_n, cost_all, goal,
                    prior_next, heap, heap_pos, heap_prio, heap_n, p, ps, pa)
            budget -= 1
        e = rev_head[x]
        while e >= 0:
            pair = rev_pair[e]
            e = rev_next[e]
            ps, pa = pair // n_actions, pair % n_actions
            if goal[ps]:  # known before a task switch made its state a goal
                continue
            _update(q, v, allowed, slots, stuck, visits, cost_sum, cost_n, cost_all, goal,
                    prior_next, heap, heap_pos, heap_prio, heap_n, p, ps, pa)
            budget -= 1


@numba.njit(cache=True)
def prior_observe(t: Tables, p: Params, s: int, a: int, r: float, s2: int, terminated: bool,
                  truncated: bool) -> bool:
    """GDQ's default after one real step: record it, index what became known, plan
    (:func:`prior_plan`). False when the model had no slot for the step or the reverse
    index is full (the callers keep room: :func:`rev_room`)."""
    # a successor not indexed yet (stuck and goal steps end the episode: never indexed;
    # the prior successor is indexed from the start when the prior has weight)
    new = not terminated and not has_successor(t.slots, s, a, s2) and not (
        p.prior_weight > 0.0 and s2 == _prior_successor(t.prior_next, s, a))
    if not record(t, p, s, a, r, s2, terminated, truncated):
        return False
    if _is_known(t.visits, t.prior_next, p.m, s, a):
        if t.visits[s, a] == (p.m if t.prior_next[s, a] >= 0 else 0) + 1:  # just known
            t.allowed[s, a] = True
            if not _rev_add_pair(t, p, s, a):
                return False
        elif new and not _rev_add(t.rev_head, t.rev_next, t.rev_pair, t.rev_n, s2,
                                  s * t.q.shape[1] + a):
            return False
    prior_plan(t, p, s, a)
    return True


def rev_room(max_successors: int, steps: int = 1) -> int:
    """Reverse-index entries ``steps`` real steps can add at most (a pair becoming known
    adds one per recorded successor and one for its prior successor, a known pair
    reaching a new state one)."""
    return steps * (max_successors + 1)


@numba.njit(cache=True)
def prior_fill_untried(t: Tables, p: Params) -> None:
    """Q of every pair that is not allowed (untried, and the knowledge says it does
    nothing) <- its prior backup ``-prior_cost + gamma * v[s]``, below ``v[s]``; goal rows
    stay 0. The sweeps never read these entries, so they leave them to this."""
    q, v, allowed, goal = t.q, t.v, t.allowed, t.goal
    for s in range(q.shape[0]):
        if goal[s]:
            continue
        stay = -p.prior_cost + p.gamma * v[s]
        for a in range(q.shape[1]):
            if not allowed[s, a]:
                q[s, a] = stay


@numba.njit(cache=True)
def prior_values(t: Tables, p: Params) -> np.ndarray:
    """The state values of the prior model alone: a state ``d`` prior steps from the goal
    is worth R_max for d = 1 and ``-prior_cost + gamma * V_{d-1}`` beyond (backward
    breadth-first search over the prior's edges); one that cannot reach it
    ``-prior_cost / (1 - gamma)``; a goal 0."""
    n_states, n_actions = t.q.shape
    goal, pp_ptr, pp_pair = t.goal, t.pp_ptr, t.pp_pair
    dist = np.full(n_states, -1, dtype=np.int64)
    queue = np.empty(n_states, dtype=np.int64)
    head, tail = 0, 0
    for s in range(n_states):
        if goal[s]:
            dist[s] = 0
            queue[tail] = s
            tail += 1
    while head < tail:
        x = queue[head]
        head += 1
        for k in range(pp_ptr[x], pp_ptr[x + 1]):
            ps = pp_pair[k] // n_actions
            if dist[ps] < 0:
                dist[ps] = dist[x] + 1
                queue[tail] = ps
                tail += 1
    longest = 0
    for s in range(n_states):
        longest = max(longest, dist[s])
    by_distance = np.zeros(longest + 1)
    for d in range(1, longest + 1):
        by_distance[d] = p.r_max if d == 1 else -p.prior_cost + p.gamma * by_distance[d - 1]
    out = np.empty(n_states)
    for s in range(n_states):
        out[s] = by_distance[dist[s]] if dist[s] >= 0 else -p.prior_cost / (1.0 - p.gamma)
    return out


@numba.njit(cache=True)
def prior_optinit(t: Tables, p: Params, tol: float, max_sweeps: int) -> int:
    """OptInit of GDQ's default: value iteration on the hybrid model (Gauss-Seidel sweeps
    over the allowed pairs until no state value moves by more than ``tol``), then every
    other pair's Q from the converged values, the reverse index rebuilt for the known
    pairs and the queue emptied. Goal rows are 0. The sweeps start from the prior's own
    values (:func:`prior_values`), exact when no pair is known yet, so a first task
    takes one sweep however large the world. Returns the number of sweeps, or -1 when
    the reverse index is too small (the caller sizes it for the known pairs)."""
    n_states, n_actions = t.q.shape
    q, v, allowed, goal, visits, prior_next = t.q, t.v, t.allowed, t.goal, t.visits, \
        t.prior_next
    ptr = np.zeros(n_states + 1, dtype=np.int64)
    for s in range(n_states):
        n = 0
        for a in range(n_actions):
            ok = prior_next[s, a] >= 0 or _is_known(visits, prior_next, p.m, s, a)
            allowed[s, a] = ok
            n += ok
        if n == 0:
            allowed[s, :] = True
            n = n_actions
        ptr[s + 1] = ptr[s] + (0 if goal[s] else n)
    pairs = np.empty(ptr[n_states], dtype=np.int64)
    for s in range(n_states):
        if goal[s]:
            continue
        k = ptr[s]
        for a in range(n_actions):
            if allowed[s, a]:
                pairs[k] = a
                k += 1
    q[:, :] = 0.0
    v[:] = prior_values(t, p)
    sweeps = 0
    while sweeps < max_sweeps:
        sweeps += 1
        delta = 0.0
        for s in range(n_states):
            if goal[s]:
                continue
            best = -np.inf
            for k in range(ptr[s], ptr[s + 1]):
                a = pairs[k]
                x = hybrid_value(t, p, s, a)
                q[s, a] = x
                if x > best:
                    best = x
            delta = max(delta, abs(best - v[s]))
            v[s] = best
        if delta <= tol:
            break
    for s in range(n_states):
        if goal[s]:
            continue
        for a in range(n_actions):
            if not allowed[s, a]:
                q[s, a] = hybrid_value(t, p, s, a)
    t.rev_head[:] = -1
    t.rev_n[0] = 0
    for s in range(n_states):
        for a in range(n_actions):
            if _is_known(visits, prior_next, p.m, s, a) and not _rev_add_pair(t, p, s, a):
                return -1
    t.heap_pos[:] = -1
    t.heap_n[0] = 0
    return sweeps
