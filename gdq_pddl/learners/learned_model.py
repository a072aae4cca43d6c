"""The learned model (what "model" means in the learners) and Dyna-Q's backups on it.

The model counts the real steps a learner took; it is goal-independent, so it survives a
task switch. Per pair ``(s, a)``: ``visits`` (all trials), ``stuck`` (trials that got
stuck), ``cost_sum / cost_n`` (the mean step cost over steps with no goal, stuck or
timeout event; else the mean over all pairs, or 0: :func:`mean_cost`), and the
transitions to learner states ``s'``, sparse: ``slots[s, a, j]`` is ``s' << 32 | count``
(0: empty), the occupied slots first and sorted by successor, so every loop meets the
successors in increasing ``s'`` as a loop over dense counts would. ``K``, the slots per
pair, is a capacity (:attr:`gdq_pddl.learners.context.TaskContext.max_successors`; the
model-free learners get 0); a transition finding no free slot is not recorded and its
callers raise ValueError(:data:`OVERFLOW`).

The expected backup of a pair, for the current goal states G (:func:`learned_value`)::

    Q(s,a) = sum_s' T(s,a,s') * (R_max if s' in G else -cost(s,a) + gamma * V(s'))
             + P_stuck(s,a) * (-R_max)

with ``T = count / visits`` and ``P_stuck = stuck / visits``; a step-limit timeout is
counted as a transition, its -R_max is not. A pair is *known* when ``visits > m``:
Dyna-Q backs up known pairs only (:func:`backup_known`); GDQ-literal gives an unknown pair
OptInit's optimism (:func:`expected_value`); GDQ-code replays recorded outcomes of tried
pairs (:func:`sample_outcome`).
"""

from __future__ import annotations

import numba
import numpy as np

from gdq_pddl.learners.tables import (
    BACKUP_EXPECTED,
    Model,
    Params,
    QTable,
    set_q,
    td_update,
)

SLOT_SHIFT = 32
COUNT_MASK = (1 << SLOT_SHIFT) - 1
"""A slot is ``successor << SLOT_SHIFT | count``: successors below 2**31, counts up to
2**32 - 1 per (pair, successor)."""

OVERFLOW = ("a (state, action) pair has more distinct successors than the learner's model "
            "has slots (TaskContext.max_successors); give it more with reserve_successors")
"""Why :func:`record` or a learner's ``observe_rule`` returned False."""


def new_model(n_states: int, n_actions: int, max_successors: int) -> Model:
    """A fresh (empty) learned model, ``max_successors`` slots per pair."""
    pair = (n_states, n_actions)
    return Model(slots=np.zeros((*pair, int(max_successors)), dtype=np.int64),
                 stuck=np.zeros(pair, dtype=np.int64), visits=np.zeros(pair, dtype=np.int64),
                 cost_sum=np.zeros(pair), cost_n=np.zeros(pair, dtype=np.int64),
                 cost_all=np.zeros(2), known=np.zeros(n_states * n_actions, dtype=np.int64),
                 n_known=np.zeros(1, dtype=np.int64))


def with_successor_slots(model: Model, max_successors: int) -> Model:
    """``model`` with at least ``max_successors`` slots per pair, the transitions kept."""
    n_states, n_actions, k = model.slots.shape
    if max_successors <= k:
        return model
    wider = np.zeros((n_states, n_actions, max_successors), dtype=np.int64)
    wider[:, :, :k] = model.slots
    return model._replace(slots=wider)


def resized(model: Model, n_states: int, n_actions: int) -> Model:
    """``model`` over ``n_states x n_actions`` (at least its own), the transitions kept:
    a problem explored online found more states, or a state with more actions."""
    old_s, old_a, k = model.slots.shape
    if (n_states, n_actions) == (old_s, old_a):
        return model
    out = new_model(n_states, n_actions, k)
    for name in ("slots", "stuck", "visits", "cost_sum", "cost_n"):
        getattr(out, name)[:old_s, :old_a] = getattr(model, name)
    out.cost_all[:] = model.cost_all
    n = int(model.n_known[0])
    pairs = model.known[:n]
    out.known[:n] = pairs // old_a * n_actions + pairs % old_a  # pair s * A + a, new A
    out.n_known[0] = n
    return out


def dense_counts(slots: np.ndarray, n_states: int) -> np.ndarray:
    """The transition counts as a dense int64 ``[S, A, n_states]`` array."""
    out = np.zeros((*slots.shape[:2], n_states), dtype=np.int64)
    s, a, j = np.nonzero(slots)
    out[s, a, slots[s, a, j] >> SLOT_SHIFT] = slots[s, a, j] & COUNT_MASK
    return out


@numba.njit(cache=True)
def slot_successor(slot: int) -> int:
    return slot >> SLOT_SHIFT


@numba.njit(cache=True)
def slot_count(slot: int) -> int:
    return slot & COUNT_MASK


# --- recording a real step -------------------------------------------------------------------

@numba.njit(cache=True)
def add_successor(slots: np.ndarray, s: int, a: int, s2: int) -> bool:
    """Count one transition ``(s, a) -> s2`` in the slots of ``(s, a)``, keeping them
    sorted by successor. False (nothing changed) when ``s2`` is new and every slot is
    taken. (The slot array and a status, not the tuple and a raise: docs/learners.md.)"""
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
def has_successor(slots: np.ndarray, s: int, a: int, s2: int) -> bool:
    """Whether ``(s, a) -> s2`` has been recorded."""
    for j in range(slots.shape[2]):
        here = slots[s, a, j]
        if here == 0:
            return False
        if slot_successor(here) == s2:
            return True
    return False


@numba.njit(cache=True, inline="always")
def record(model: Model, goal: np.ndarray, p: Params, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool) -> bool:
    """Count one real transition in the model; False (nothing recorded) if no slot is free.
    A step's cost is what it paid; on the problem's own scale an ending step's too (the
    goal step: what it paid besides ``r_max``), since there it can differ from the
    ordinary steps' (a delivery that earns more than the goal reward)."""
    if terminated and not goal[s2]:
        model.stuck[s, a] += 1
    elif not add_successor(model.slots, s, a, s2):
        return False
    if p.own_scale > 0.0 or not (terminated or truncated):
        cost = p.r_max - r if terminated and goal[s2] else -r
        model.cost_sum[s, a] += cost
        model.cost_n[s, a] += 1
        model.cost_all[0] += cost
        model.cost_all[1] += 1.0
    visits = model.visits
    visits[s, a] += 1
    if visits[s, a] == p.m + 1:
        model.known[model.n_known[0]] = s * visits.shape[1] + a
        model.n_known[0] += 1
    return True


# --- what the model says a pair is worth -------------------------------------------------------

@numba.njit(cache=True, inline="always", error_model="numpy")
def mean_cost(cost_sum: np.ndarray, cost_n: np.ndarray, cost_all: np.ndarray, s: int,
              a: int) -> float:
    """The mean step cost of ``(s, a)``; of every pair where it has none; else 0."""
    if cost_n[s, a] > 0:
        return cost_sum[s, a] / cost_n[s, a]
    if cost_all[1] > 0:
        return cost_all[0] / cost_all[1]
    return 0.0


@numba.njit(cache=True, inline="always", error_model="numpy")
def learned_value(slots: np.ndarray, stuck: np.ndarray, visits: np.ndarray,
                  cost_sum: np.ndarray, cost_n: np.ndarray, cost_all: np.ndarray,
                  goal: np.ndarray, v: np.ndarray, p: Params, s: int, a: int) -> float:
    """The expected Bellman backup of a tried ``(s, a)`` under the learned model, with ``v``."""
    r_max, gamma = p.r_max, p.gamma
    c = mean_cost(cost_sum, cost_n, cost_all, s, a)
    own = p.own_scale > 0.0  # an ending step pays its cost too, and stuck no penalty
    total = stuck[s, a] * -c if own else stuck[s, a] * -r_max
    for j in range(slots.shape[2]):  # successors in increasing order
        here = slots[s, a, j]
        if here == 0:
            break
        k = slot_count(here)
        s2 = slot_successor(here)
        if goal[s2]:
            total += k * (r_max - c) if own else k * r_max
        else:
            total += k * (gamma * v[s2] - c)
    return total / visits[s, a]


@numba.njit(cache=True, inline="always")
def expected_value(model: Model, goal: np.ndarray, opt_r: np.ndarray, p: Params, s: int,
                   a: int, v: np.ndarray) -> float:
    """The expected Bellman backup of ``(s, a)``, with state values ``v``: the learned
    model's for a known pair (``visits > m``), else the optimism of GDQ-literal (R_max on
    OptInit's plan pairs ``opt_r``)."""
    if model.visits[s, a] > p.m:
        return learned_value(model.slots, model.stuck, model.visits, model.cost_sum,
                             model.cost_n, model.cost_all, goal, v, p, s, a)
    r = p.r_max if opt_r[s, a] else 0.0
    return r + p.opt_continue * p.gamma * v[p.s0]


@numba.njit(cache=True, inline="always")
def sample_outcome(model: Model, goal: np.ndarray, p: Params, s: int, a: int,
                   rng: np.random.Generator) -> tuple[float, int, bool]:
    """One ``(reward, next state, terminal)`` replayed from the recorded outcomes of a
    tried pair ``(s, a)`` (stuck, goal, or an ordinary step at the pair's mean cost)."""
    k = rng.integers(0, model.visits[s, a])
    own = p.own_scale > 0.0  # as learned_value
    if k < model.stuck[s, a]:
        if own:
            return -mean_cost(model.cost_sum, model.cost_n, model.cost_all, s, a), s, True
        return -p.r_max, s, True
    k -= model.stuck[s, a]
    slots = model.slots  # a local: a tuple field read in a loop costs more
    for j in range(slots.shape[2]):  # successors in increasing order
        k -= slot_count(slots[s, a, j])
        if k < 0:
            s2 = slot_successor(slots[s, a, j])
            if goal[s2]:
                if own:
                    c = mean_cost(model.cost_sum, model.cost_n, model.cost_all, s, a)
                    return p.r_max - c, s2, True
                return p.r_max, s2, True
            return -mean_cost(model.cost_sum, model.cost_n, model.cost_all, s, a), s2, False
    return -mean_cost(model.cost_sum, model.cost_n, model.cost_all, s, a), s, False


# --- Dyna-Q's planning ---------------------------------------------------------------------------

@numba.njit(cache=True)
def model_backup(table: QTable, model: Model, opt_r: np.ndarray, p: Params, s: int, a: int,
                 rng: np.random.Generator) -> None:
    """One simulated update of ``(s, a)``: assign :func:`expected_value`
    (``BACKUP_EXPECTED``), or a TD update on a :func:`sample_outcome` (``BACKUP_SAMPLE``,
    GDQ-code; a pair never tried is left alone)."""
    if p.backup == BACKUP_EXPECTED:
        set_q(table, s, a, expected_value(model, table.goal, opt_r, p, s, a, table.v))
    elif model.visits[s, a] > 0:
        r, s2, terminal = sample_outcome(model, table.goal, p, s, a, rng)
        target = r if terminal else r + p.gamma * table.v[s2]
        td_update(table, s, a, target, p.alpha)


@numba.njit(cache=True)
def backup_known(table: QTable, model: Model, opt_r: np.ndarray, p: Params,
                 rng: np.random.Generator) -> None:
    """Dyna-Q planning: N backups of uniformly random known pairs."""
    nk = model.n_known[0]
    if nk == 0:
        return
    n_actions = model.visits.shape[1]
    for _ in range(p.n_backups):
        i = model.known[rng.integers(0, nk)]
        model_backup(table, model, opt_r, p, i // n_actions, i % n_actions, rng)
