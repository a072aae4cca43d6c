"""The default GDQ's prior alone: what it says a pair is worth (:func:`prior_backup`, also
the hybrid backup of a pair not yet known) and the state values it gives
(:func:`prior_values`), OptInit's warm start: :func:`gdq_pddl.learners.gdq.value_iteration`
starts from them, so that a first task takes one sweep however large the world. With a
flat step cost they have a closed form by goal distance; with a problem's own rewards
(``Prior.reward``) or the knowledge's chances of dead ends (``Prior.dead``), policy
iteration on the prior's deterministic model gives them."""

from __future__ import annotations

import numba
import numpy as np

from gdq_pddl.learners.tables import Params, Prior, QTable


@numba.njit(cache=True, inline="always")
def prior_successor(prior_next: np.ndarray, s: int, a: int) -> int:
    """Where the prior says ``(s, a)`` leads (``s`` itself where it says "no change")."""
    x = prior_next[s, a]
    return s if x < 0 else x


@numba.njit(cache=True, inline="always")
def dead_end_value(p: Params) -> float:
    """What the prior says a dead end is worth: its step cost forever,
    ``-prior_cost / (1 - gamma)`` (as :func:`prior_values` values a state that cannot
    reach the goal)."""
    return -p.prior_cost / (1.0 - p.gamma)


@numba.njit(cache=True, inline="always")
def prior_backup(v: np.ndarray, goal: np.ndarray, prior_next: np.ndarray,
                 prior_reward: np.ndarray, prior_dead: np.ndarray, p: Params, s: int,
                 a: int) -> float:
    """The backup of ``(s, a)`` under the prior alone, with the state values ``v``: R_max
    if its prior successor is a goal, else ``-prior_cost + gamma * v[prior successor]``;
    where ``prior_reward`` is given (a problem's own scale, ``Prior.reward``), the file's
    reward too: with ``r = prior_reward[s, a] - prior_cost``, ``r + R_max`` or
    ``r + gamma * v[prior successor]``. Where ``prior_dead`` is given (``Prior.dead``),
    the pair's chance ``d`` of a dead end is a step into one: ``(1 - d)`` times the above
    plus ``d`` times ``r + gamma * D`` (:func:`dead_end_value` ``D``; ``D`` itself with a
    flat step cost)."""
    s2 = prior_successor(prior_next, s, a)
    if prior_reward.shape[0] == 0:
        out = p.r_max if goal[s2] else -p.prior_cost + p.gamma * v[s2]
        r = -p.prior_cost
    else:
        r = prior_reward[s, a] - p.prior_cost
        out = r + p.r_max if goal[s2] else r + p.gamma * v[s2]
    if prior_dead.shape[0] == 0:
        return out
    d = prior_dead[s, a]
    return (1.0 - d) * out + d * (r + p.gamma * dead_end_value(p))


@numba.njit(cache=True)
def prior_values(table: QTable, prior: Prior, p: Params) -> np.ndarray:
    """The state values of the prior alone. With a flat step cost: a state ``d`` prior
    steps from the goal is worth R_max for d = 1 and ``-prior_cost + gamma * V_{d-1}``
    beyond (backward breadth-first search over the prior's edges); one that cannot reach
    it ``-prior_cost / (1 - gamma)``; a goal 0. With the file's rewards or chances of
    dead ends (``Prior.reward``, ``Prior.dead`` not empty): :func:`_policy_values`."""
    dist = _prior_distances(table, prior)
    if prior.reward.shape[0] or prior.dead.shape[0]:
        return _policy_values(table, prior, p, dist)
    n_states = len(dist)
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
def _prior_distances(table: QTable, prior: Prior) -> np.ndarray:
    """Prior steps from each state to the goal (backward breadth-first search over the
    prior's edges); -1 where the prior cannot reach it."""
    n_states, n_actions = table.q.shape
    goal, pp_ptr, pp_pair = table.goal, prior.pp_ptr, prior.pp_pair
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
    return dist


@numba.njit(cache=True, error_model="numpy")
def _policy_values(table: QTable, prior: Prior, p: Params, dist: np.ndarray) -> np.ndarray:
    """The state values of the prior with the file's rewards or chances of dead ends:
    policy iteration on the prior's deterministic model over the pairs OptInit first
    allows (the applicable ones; every live column where none is), each policy evaluated
    exactly along its one successor per state (a path to the goal, or into a cycle, whose
    value is its discounted rewards over ``1 - gamma^length``; a chance ``d`` of a dead end
    makes a step pay ``d * gamma * D`` more and discount by ``(1 - d) * gamma``, as
    :func:`prior_backup` reads it). It starts from the policy that moves
    closest to the goal (``dist``), so where the file's rewards agree with shortest plans
    one evaluation and one improvement step suffice; a few more elsewhere, each O(pairs),
    where Gauss-Seidel sweeps would take ~log(tol) / log(gamma) sweeps around a loop that
    pays. A switch needs a gain above 1e-12 x R_max, so it ends; past 1000 policies the
    values are returned as they are (OptInit's sweeps finish the job)."""
    goal, n_live = table.goal, table.n_live
    nxt = prior.next_state
    n_states, n_actions = nxt.shape
    # a step to a state that is not a goal is worth rew + keep * v[successor]
    rew = (prior.reward if prior.reward.shape[0] else np.zeros(nxt.shape)) - p.prior_cost
    keep = np.full(nxt.shape, p.gamma)
    if prior.dead.shape[0]:
        rew += prior.dead * (p.gamma * dead_end_value(p))
        keep -= prior.dead * p.gamma
    r_max = p.r_max
    eps = 1e-12 * max(1.0, r_max)
    far = n_states + 1
    policy = np.zeros(n_states, dtype=np.int64)
    for s in range(n_states):  # first policy: closest to the goal, then the best reward
        if goal[s]:
            continue
        best_d, best_r = far + 1, -np.inf
        for a in range(n_actions):
            x = nxt[s, a]
            if x < 0:
                continue
            d = dist[x] if dist[x] >= 0 else far
            if d < best_d or (d == best_d and rew[s, a] > best_r):
                best_d, best_r, policy[s] = d, rew[s, a], a
        if best_d > far:  # nothing applicable: the best-paying live column
            for a in range(n_live[s]):
                if rew[s, a] > best_r:
                    best_r, policy[s] = rew[s, a], a
    v = np.zeros(n_states)
    mark = np.zeros(n_states, dtype=np.int8)  # 0 new, 1 on the walk, 2 valued
    at = np.zeros(n_states, dtype=np.int64)  # a walked state's place on the stack
    stack = np.empty(n_states, dtype=np.int64)
    for _ in range(1000):
        for s in range(n_states):
            mark[s] = 2 if goal[s] else 0
            if goal[s]:
                v[s] = 0.0
        for s0 in range(n_states):  # evaluate: walk each policy path until valued
            if mark[s0]:
                continue
            top, x = 0, s0
            while True:
                mark[x], at[x], stack[top] = 1, top, x
                top += 1
                y = prior_successor(nxt, x, policy[x])
                if goal[y]:
                    v[x] = prior_backup(v, goal, nxt, prior.reward, prior.dead, p, x,
                                        policy[x])
                    mark[x] = 2
                    top -= 1
                    break
                if mark[y] == 2:
                    break
                if mark[y] == 1:  # a cycle from y to x: value y, then the rest
                    j = at[y]
                    total, g = 0.0, 1.0
                    for k in range(j, top):
                        z = stack[k]
                        total += g * rew[z, policy[z]]
                        g *= keep[z, policy[z]]
                    v[y] = total / (1.0 - g)
                    mark[y] = 2
                    for k in range(top - 1, j, -1):
                        z = stack[k]
                        a = policy[z]
                        v[z] = rew[z, a] + keep[z, a] * v[prior_successor(nxt, z, a)]
                        mark[z] = 2
                    top = j
                    break
                x = y
            for k in range(top - 1, -1, -1):  # the walk back from where it was valued
                z = stack[k]
                a = policy[z]
                v[z] = rew[z, a] + keep[z, a] * v[prior_successor(nxt, z, a)]
                mark[z] = 2
        changed = False
        for s in range(n_states):  # improve
            if goal[s]:
                continue
            applicable = False
            for a in range(n_actions):
                applicable = applicable or nxt[s, a] >= 0
            best, best_a = v[s], policy[s]
            for a in range(n_live[s] if not applicable else n_actions):
                if applicable and nxt[s, a] < 0:
                    continue
                value = prior_backup(v, goal, nxt, prior.reward, prior.dead, p, s, a)
                if value > best + eps:
                    best, best_a = value, a
            if best_a != policy[s]:
                policy[s] = best_a
                changed = True
        if not changed:
            break
    return v
