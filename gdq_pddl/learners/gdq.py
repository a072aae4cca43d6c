"""The default GDQ's update rule: the knowledge as a prior, a hybrid backup, a sweep.

Read in this order: :func:`after_step` (what GDQ does after each real step),
:func:`hybrid_backup` (what a pair is worth), :func:`sweep` (which pairs are recomputed),
:func:`value_iteration` (OptInit, at the start of each task, warm-started by
:func:`gdq_pddl.learners.warm_start.prior_values`).

- **The prior**: ``prior_next[s, a]``, where the knowledge says a pair leads (-1: "no
  change"; :mod:`gdq_pddl.abstraction.prior`), deterministically at cost ``prior_cost``
  (on a problem's own scale besides the most the file pays for a trial of the action,
  ``Prior.reward``); reaching a goal pays R_max; with the knowledge's chance of a dead end
  (``Prior.dead``), that share of the backup is a dead end's value
  (:func:`~gdq_pddl.learners.warm_start.prior_backup`).
- **Known pairs** (:func:`is_known`): an applicable pair after more than m trials, one
  the knowledge says does nothing after its first.
- **The hybrid backup**: an unknown pair is worth its prior backup, a known one
  ``(n * learned + w * prior) / (n + w)`` after n trials (``w = prior_weight``, learned:
  :func:`gdq_pddl.learners.learned_model.learned_value`). There is no TD update.
- **The sweep**: states whose value changed wait in a max-heap by the size of the change;
  popping one recomputes the pairs that can lead to it (unknown pairs by their prior
  successor, ``pp_*``; known pairs through the reverse index ``rev_*``) until
  ``n_backups`` are done; the heap carries the rest to the next step.
- ``allowed`` (what v and the greedy choice range over) holds the applicable and the
  known pairs (every action where nothing is applicable). Exploring steps draw among
  the allowed actions whose value is near the state's (``explore_band``) but for a move
  the next greedy step would undo (``explore_loops``), a share
  ``explore_all`` of them an untried action instead where the knowledge may lack
  actions (:func:`act`, the acting rule of this learner alone).

``docs/learners.md`` explains the rule, ``docs/decisions.md`` measures its settings.
"""

from __future__ import annotations

import numba
import numpy as np

from gdq_pddl.learners.learned_model import (
    has_successor,
    learned_value,
    record,
    slot_successor,
)
from gdq_pddl.learners.tables import (
    Model,
    Params,
    Prior,
    QTable,
    Queue,
    draw_guided,
    greedy_draw,
    set_q_arrays,
)
from gdq_pddl.learners.warm_start import prior_backup, prior_successor, prior_values

# --- the rule --------------------------------------------------------------------------------


@numba.njit(cache=True)
def after_step(table: QTable, model: Model, prior: Prior, queue: Queue, p: Params, s: int,
               a: int, r: float, s2: int, terminated: bool, truncated: bool) -> bool:
    """The default GDQ after one real step: record it in the learned model, index what
    became known, then :func:`sweep`. False when the model had no slot for the step or
    the reverse index is full (the callers keep room: :func:`reverse_room`)."""
    # a successor not indexed yet (stuck and goal steps end the episode: never indexed;
    # the prior successor is indexed from the start when the prior has weight)
    new = not terminated and not has_successor(model.slots, s, a, s2) and not (
        p.prior_weight > 0.0 and s2 == prior_successor(prior.next_state, s, a))
    if not record(model, table.goal, p, s, a, r, s2, terminated, truncated):
        return False
    if is_known(model.visits, prior.next_state, p.m, s, a):
        if model.visits[s, a] == (p.m if prior.next_state[s, a] >= 0 else 0) + 1:  # just known
            table.allowed[s, a] = True
            if not _index_known_pair(model, table.goal, prior, p, s, a):
                return False
        elif new and not _index_add(prior, s2, s * table.q.shape[1] + a):
            return False
    sweep(table, model, prior, queue, p, s, a)
    return True


@numba.njit(cache=True, inline="always", error_model="numpy")
def hybrid_backup(table: QTable, model: Model, prior_next: np.ndarray,
                  prior_reward: np.ndarray, prior_dead: np.ndarray, p: Params, s: int,
                  a: int) -> float:
    """The backup of ``(s, a)`` under the hybrid model, with the current ``v``: its
    :func:`~gdq_pddl.learners.warm_start.prior_backup` while unknown,
    ``(n * learned + w * prior) / (n + w)`` once known."""
    return _hybrid(table.v, table.goal, prior_next, prior_reward, prior_dead, model.slots,
                   model.stuck, model.visits, model.cost_sum, model.cost_n, model.cost_all,
                   p, s, a)


@numba.njit(cache=True, error_model="numpy")
def sweep(table: QTable, model: Model, prior: Prior, queue: Queue, p: Params, s: int,
          a: int) -> None:
    """Revalue the real step's pair ``(s, a)`` if it is known, then sweep: recompute the
    pairs leading to the most changed states until ``n_backups`` pairs are done (a popped
    state's pairs are all done) or none is queued."""
    # the arrays as locals, passed to _revalue one by one: a read of a group's field in
    # this loop would cost a reference count each time (GDQ ~20% fewer steps/s)
    q, v, allowed, goal = table.q, table.v, table.allowed, table.goal
    slots, stuck, visits = model.slots, model.stuck, model.visits
    cost_sum, cost_n, cost_all = model.cost_sum, model.cost_n, model.cost_all
    prior_next, pp_ptr, pp_pair = prior.next_state, prior.pp_ptr, prior.pp_pair
    prior_reward, prior_dead = prior.reward, prior.dead
    rev_head, rev_next, rev_pair = prior.rev_head, prior.rev_next, prior.rev_pair
    heap, pos, prio, heap_n = queue.heap, queue.pos, queue.prio, queue.n
    n_actions = q.shape[1]
    if is_known(visits, prior_next, p.m, s, a):
        _revalue(q, v, allowed, goal, prior_next, prior_reward, prior_dead, slots, stuck,
                 visits, cost_sum, cost_n, cost_all, heap, pos, prio, heap_n, p, s, a)
    budget = p.n_backups
    while budget > 0 and heap_n[0] > 0:
        x = _pop(queue)
        for k in range(pp_ptr[x], pp_ptr[x + 1]):  # unknown pairs the prior leads to x
            pair = pp_pair[k]
            ps, pa = pair // n_actions, pair % n_actions
            if goal[ps] or is_known(visits, prior_next, p.m, ps, pa):
                continue  # goal rows keep 0; known pairs are in the reverse index
            _revalue(q, v, allowed, goal, prior_next, prior_reward, prior_dead, slots, stuck,
                     visits, cost_sum, cost_n, cost_all, heap, pos, prio, heap_n, p, ps, pa)
            budget -= 1
        e = rev_head[x]
        while e >= 0:  # known pairs whose backup reads x
            pair = rev_pair[e]
            e = rev_next[e]
            ps, pa = pair // n_actions, pair % n_actions
            if goal[ps]:  # known before a task switch made its state a goal
                continue
            _revalue(q, v, allowed, goal, prior_next, prior_reward, prior_dead, slots, stuck,
                     visits, cost_sum, cost_n, cost_all, heap, pos, prio, heap_n, p, ps, pa)
            budget -= 1


# The sweep's inner loop on arrays (the groups' fields, one by one: see sweep).

@numba.njit(cache=True, inline="always", error_model="numpy")
def _revalue(q, v, allowed, goal, prior_next, prior_reward, prior_dead, slots, stuck, visits,
             cost_sum, cost_n, cost_all, heap, pos, prio, heap_n, p: Params, s: int,
             a: int) -> None:
    """``q[s, a] <-`` its hybrid backup; queue ``s`` if that moved its value by more than
    the sweep threshold. (The untried pairs the knowledge says do nothing are not allowed:
    nothing here reads their Q, which :func:`fill_untried` fills in when it is read.)"""
    old = v[s]
    set_q_arrays(q, v, allowed, s, a, _hybrid(v, goal, prior_next, prior_reward, prior_dead,
                                              slots, stuck, visits, cost_sum, cost_n,
                                              cost_all, p, s, a))
    change = abs(v[s] - old)
    if change > p.sweep_threshold:
        _push(heap, pos, prio, heap_n, s, change)


@numba.njit(cache=True, inline="always", error_model="numpy")
def _hybrid(v, goal, prior_next, prior_reward, prior_dead, slots, stuck, visits, cost_sum,
            cost_n, cost_all, p: Params, s: int, a: int) -> float:
    """:func:`hybrid_backup`: the prior backup, mixed with the learned model's once known."""
    prior = prior_backup(v, goal, prior_next, prior_reward, prior_dead, p, s, a)
    if is_known(visits, prior_next, p.m, s, a):
        n = visits[s, a]
        learned = learned_value(slots, stuck, visits, cost_sum, cost_n, cost_all, goal, v, p,
                                s, a)
        w = p.prior_weight
        return (n * learned + w * prior) / (n + w)
    return prior


@numba.njit(cache=True, inline="always")
def is_known(visits: np.ndarray, prior_next: np.ndarray, m: int, s: int, a: int) -> bool:
    """Whether ``(s, a)`` is valued by the learned model: tried more than m times if the
    knowledge says it applies, at least once if it says it does nothing."""
    return visits[s, a] > (m if prior_next[s, a] >= 0 else 0)


# --- OptInit ---------------------------------------------------------------------------------

@numba.njit(cache=True)
def value_iteration(table: QTable, model: Model, prior: Prior, queue: Queue, p: Params,
                    tol: float, max_sweeps: int) -> int:
    """OptInit of the default GDQ: value iteration on the hybrid model (Gauss-Seidel sweeps
    over the allowed pairs until no state value moves by more than ``tol``), then every
    other pair's Q from the converged values, the reverse index rebuilt for the known
    pairs and the queue emptied. Goal rows are 0. The sweeps start from the prior's own
    values (:func:`prior_values`), exact when no pair is known yet (with the file's
    rewards too), so a first task takes one sweep however large the world. Returns the
    number of sweeps, or -1 when the reverse index is too small (the caller sizes it
    for the known pairs)."""
    q, v, allowed, goal = table.q, table.v, table.allowed, table.goal
    visits, prior_next = model.visits, prior.next_state
    n_states, n_actions = q.shape
    ptr = np.zeros(n_states + 1, dtype=np.int64)
    for s in range(n_states):
        n = 0
        for a in range(n_actions):
            ok = prior_next[s, a] >= 0 or is_known(visits, prior_next, p.m, s, a)
            allowed[s, a] = ok
            n += ok
        if n == 0:  # nothing applicable or known: every action (every live column)
            n = table.n_live[s]
            allowed[s, :n] = True
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
    v[:] = prior_values(table, prior, p)
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
                x = hybrid_backup(table, model, prior_next, prior.reward, prior.dead, p, s, a)
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
                q[s, a] = hybrid_backup(table, model, prior_next, prior.reward, prior.dead, p, s, a)
    prior.rev_head[:] = -1
    prior.rev_n[0] = 0
    for s in range(n_states):
        for a in range(n_actions):
            if is_known(visits, prior_next, p.m, s, a) and \
                    not _index_known_pair(model, goal, prior, p, s, a):
                return -1
    queue.pos[:] = -1
    queue.n[0] = 0
    return sweeps


@numba.njit(cache=True)
def fill_untried(table: QTable, prior_reward: np.ndarray, p: Params) -> None:
    """Q of every pair that is not allowed (untried, and the knowledge says it does
    nothing) <- its prior backup ``-prior_cost + gamma * v[s]``, below ``v[s]`` (on a
    problem's own scale plus ``prior_reward[s, a]``, 0 in a padding column); goal rows
    stay 0. The sweeps never read these entries, so
    they leave them to this."""
    q, v, allowed, goal = table.q, table.v, table.allowed, table.goal
    own = prior_reward.shape[0] > 0
    for s in range(q.shape[0]):
        if goal[s]:
            continue
        stay = -p.prior_cost + p.gamma * v[s]
        for a in range(q.shape[1]):
            if not allowed[s, a]:
                q[s, a] = prior_reward[s, a] + stay if own else stay


@numba.njit(cache=True)
def revalue_rows(table: QTable, model: Model, prior: Prior, queue: Queue, p: Params,
                 rows: np.ndarray) -> None:
    """A problem explored online changed ``rows`` (in order: a row's prior successors
    before it): each row's allowed pairs <- their hybrid backups, repeated until the row's
    value settles (a row whose pairs lead back to itself), and the row queued by the
    change, as a sweep does. Goal rows are 0."""
    q, v, allowed, goal = table.q, table.v, table.allowed, table.goal
    tol = 1e-9 * max(1.0, p.r_max)
    for s in rows:
        if goal[s]:
            q[s, :] = 0.0
            v[s] = 0.0
            continue
        old = v[s]
        for _ in range(100_000):
            best = -np.inf
            for a in range(q.shape[1]):
                if allowed[s, a]:
                    x = hybrid_backup(table, model, prior.next_state, prior.reward,
                                      prior.dead, p, s, a)
                    q[s, a] = x
                    best = max(best, x)
            settled = abs(best - v[s]) <= tol
            v[s] = best
            if settled:
                break
        if abs(v[s] - old) > p.sweep_threshold:
            _push(queue.heap, queue.pos, queue.prio, queue.n, s, abs(v[s] - old))


# --- the reverse index: which known pairs read a state -----------------------------------------

def reverse_room(max_successors: int, steps: int = 1) -> int:
    """Reverse-index entries ``steps`` real steps can add at most: per step, one per recorded
    successor and one prior successor for a pair becoming known, else one."""
    return steps * (max_successors + 1)


@numba.njit(cache=True, inline="always")
def _index_add(prior: Prior, x: int, pair: int) -> bool:
    """Record that known ``pair`` has reached state ``x``; False when the index is full."""
    rev_n = prior.rev_n
    e = rev_n[0]
    if e >= prior.rev_pair.shape[0]:
        return False
    prior.rev_pair[e] = pair
    prior.rev_next[e] = prior.rev_head[x]
    prior.rev_head[x] = e
    rev_n[0] = e + 1
    return True


@numba.njit(cache=True)
def _index_known_pair(model: Model, goal: np.ndarray, prior: Prior, p: Params, s: int,
                      a: int) -> bool:
    """Index the states the newly known pair ``(s, a)``'s backup reads: its recorded
    non-goal successors and, with ``prior_weight > 0``, its prior successor."""
    slots = model.slots
    pair = s * slots.shape[1] + a
    for j in range(slots.shape[2]):
        here = slots[s, a, j]
        if here == 0:
            break
        x = slot_successor(here)
        if not goal[x] and not _index_add(prior, x, pair):
            return False
    x = prior_successor(prior.next_state, s, a)
    if p.prior_weight > 0.0 and not goal[x] and not has_successor(slots, s, a, x):
        return _index_add(prior, x, pair)
    return True


# --- the queue of changed states (a max-heap by the size of the change) -------------------------

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
def _pop(queue: Queue) -> int:
    """The queued state of highest priority, removed from the queue."""
    heap, pos = queue.heap, queue.pos
    x = heap[0]
    n = queue.n[0] - 1
    queue.n[0] = n
    pos[x] = -1
    if n > 0:
        heap[0] = heap[n]
        _sift_down(heap, pos, queue.prio, n, 0)
    return x


# --- acting: GDQ's exploring rules ------------------------------------------------------------

@numba.njit(cache=True)
def act(table: QTable, visits: np.ndarray, prior: Prior, p: Params, s: int,
        rng: np.random.Generator) -> int:
    """The default GDQ's acting rule: epsilon-greedy as every learner
    (:func:`~gdq_pddl.learners.tables.act_plain`), but an exploring step draws, for a share
    ``explore_all`` of them, an untried action (unless ``explore_all_last`` is 0 and the
    knowledge reaches the goal from ``s`` in one action), else, with ``explore_band`` at
    least 0, among the actions near the best (:func:`_draw_near_best`), else from
    ``guide[s]``. :func:`act_reference` is the same rule in plain Python."""
    if rng.random() < p.epsilon:
        if p.explore_all > 0.0 and rng.random() < p.explore_all and (
                p.explore_all_last > 0.0
                or not _one_step_from_goal(table.goal, prior.next_state, s)):
            return _draw_untried(visits, table.n_live, s, rng)
        if p.explore_band >= 0.0:
            return _draw_near_best(table, prior, p, s, rng)
        return draw_guided(table, s, rng)
    return greedy_draw(table, p, s, rng)


@numba.njit(cache=True)
def _draw_near_best(table: QTable, prior: Prior, p: Params, s: int,
                    rng: np.random.Generator) -> int:
    """A uniformly random allowed action whose Q is within ``explore_band`` of ``v[s]``:
    DARLING's length tolerance carried to values (a plan ``1 + band`` times as long falls
    short of ``r_max`` by ``1 + band`` times as much, undiscounted at a unit step cost),
    and, unless ``explore_loops``, loop-free as DARLING's plans are (:func:`_undone`),
    and never a move the knowledge says ends in a dead end for certain
    (``prior.dead`` 1: DARLING's plans never do either). The state's greedy actions
    always qualify."""
    floor = table.v[s] - p.explore_band * max(0.0, p.r_max - table.v[s])
    n = 0
    for a in range(table.n_live[s]):
        n += _near_best(table, prior, p, s, a, floor)
    k = rng.integers(0, n)
    for a in range(table.n_live[s]):
        if _near_best(table, prior, p, s, a, floor):
            if k == 0:
                return a
            k -= 1
    return 0  # unreachable: the greedy actions are counted


@numba.njit(cache=True, inline="always")
def _near_best(table: QTable, prior: Prior, p: Params, s: int, a: int, floor: float
               ) -> bool:
    """Whether :func:`_draw_near_best` may draw ``a`` in ``s``."""
    q, v = table.q[s, a], table.v[s]
    if not table.allowed[s, a] or q < floor:
        return False
    if q >= v:  # a greedy action
        return True
    if prior.dead.shape[0] and prior.dead[s, a] >= 1.0:
        return False
    return p.explore_loops > 0.0 or not _undone(table, prior, s, a)


@numba.njit(cache=True)
def _undone(table: QTable, prior: Prior, s: int, a: int) -> bool:
    """Whether the next greedy step would undo the move ``a`` in ``s``: the prior leads it
    to ``x`` and a greedy action of ``x`` leads straight back to ``s`` (the pairs the
    prior leads to ``s`` are ``prior.pp_*``'s, a handful). Far from the goal the band is
    wide enough for such a two-step loop (put a block down, pick it up again), which
    makes no way and, where moves are risky, adds the risk of two. A move into a goal is
    none: the episode ends there. Called only for the few actions in the band."""
    x = prior.next_state[s, a]
    if x < 0 or x == s or table.goal[x]:
        return False
    q, v, allowed = table.q, table.v, table.allowed
    n_actions = q.shape[1]
    for k in range(prior.pp_ptr[s], prior.pp_ptr[s + 1]):
        b = prior.pp_pair[k] - x * n_actions
        if 0 <= b < n_actions and allowed[x, b] and q[x, b] >= v[x]:
            return True
    return False


@numba.njit(cache=True)
def _draw_untried(visits: np.ndarray, n_live: np.ndarray, s: int,
                  rng: np.random.Generator) -> int:
    """A uniformly random action never tried in ``s``; any action once all were."""
    n_actions = n_live[s]
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
def _one_step_from_goal(goal: np.ndarray, prior_next: np.ndarray, s: int) -> bool:
    """Whether the knowledge reaches the goal from ``s`` in one action."""
    for a in range(prior_next.shape[1]):
        s2 = prior_next[s, a]
        if s2 >= 0 and goal[s2]:
            return True
    return False


# --- the acting rule in plain Python (the reference the tests hold the compiled one to) ----

def act_reference(table: QTable, visits: np.ndarray, prior: Prior, p: Params, s: int,
                  rng: np.random.Generator) -> int:
    """:func:`act` written out in plain Python and numpy, drawing from ``rng`` in the same
    order: the rule to read, and what ``tests/learners/test_gdq_exploring.py`` holds the
    compiled one to, draw for draw."""
    q, v, allowed = table.q[s], table.v[s], table.allowed[s]
    if rng.random() >= p.epsilon:  # greedy: a uniform maximiser of Q over allowed
        best = np.flatnonzero(allowed & (q == v))
        if len(best) < 2:
            return int(best[0]) if len(best) else 0
        return int(best[rng.integers(0, len(best))])
    ends_next = bool(np.any(table.goal[prior.next_state[s][prior.next_state[s] >= 0]]))
    if p.explore_all > 0.0 and rng.random() < p.explore_all and (
            p.explore_all_last > 0.0 or not ends_next):  # explore_all, last-step sparing
        live = np.arange(table.n_live[s])
        untried = live[visits[s, live] == 0]
        pool = untried if len(untried) else live
        return int(pool[rng.integers(0, len(pool))])
    if p.explore_band < 0.0:  # the guide's actions
        guide = np.flatnonzero(table.guide[s])
        return int(guide[rng.integers(0, len(guide))])
    floor = v - p.explore_band * max(0.0, p.r_max - v)  # the band
    band = [a for a in range(table.n_live[s]) if allowed[a] and q[a] >= floor and (
        q[a] >= v or not _ends_for_certain(prior, s, a) and (
            p.explore_loops > 0.0 or not _undone_reference(table, prior, s, a)))]
    return band[rng.integers(0, len(band))]


def _ends_for_certain(prior: Prior, s: int, a: int) -> bool:
    """Whether the knowledge says ``a`` in ``s`` ends in a dead end for certain."""
    return bool(prior.dead.shape[0]) and prior.dead[s, a] >= 1.0


def _undone_reference(table: QTable, prior: Prior, s: int, a: int) -> bool:
    """:func:`_undone` in plain Python: a greedy action of the prior's successor ``x`` of
    ``(s, a)`` leads straight back to ``s`` (a goal ``x`` ends the episode: never)."""
    x = prior.next_state[s, a]
    if x < 0 or x == s or table.goal[x]:
        return False
    n_actions = table.q.shape[1]
    back = prior.pp_pair[prior.pp_ptr[s]:prior.pp_ptr[s + 1]] - x * n_actions
    back = back[(back >= 0) & (back < n_actions)]
    return bool(np.any(table.allowed[x, back] & (table.q[x, back] >= table.v[x])))
