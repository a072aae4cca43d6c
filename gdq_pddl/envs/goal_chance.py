"""How likely the goal is, on the true model: what V* (:func:`~gdq_pddl.envs.solve.solve`)
means in probabilities.

V* is an expected return within the step limit. Two problems of the same V* can differ in
what the goal is worth: the step limit can cut off most of the episodes that would reach
it. Beside V*, the report gives

- :func:`best_within_limit`: the most probability of reaching the goal within the step
  limit any policy has (finite-horizon value iteration on the probability of reaching
  the goal, the model's :func:`success` outcomes worth 1, stuck outcomes and the last
  step's others 0);
- :func:`best_without_limit`: the most probability of reaching the goal with no step
  limit (*MaxProb*: the least fixed point of the Bellman operator on that probability),
  as IPPC-2008's published goal probabilities count it. Value iteration from 0 only
  converges to it; the policy its values make (:func:`_attractor`: in each state an
  action of the best value that leads closer to the goal) is evaluated exactly (a sparse
  linear solve), and a policy's value that is also a fixed point of the Bellman operator
  is the optimum: the answer is then exact, to :data:`FIXED_POINT_TOLERANCE`; else the
  best value found is a lower bound, and said so.

A goal state itself counts as reached (a start at the goal: every episode ends there).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix, identity
from scipy.sparse.csgraph import breadth_first_order
from scipy.sparse.linalg import spsolve

from gdq_pddl.envs.step import ModelArrays, width_of

FIXED_POINT_TOLERANCE = 1e-9
"""A policy's goal probabilities count as a fixed point of the Bellman operator when no
action improves any state's by more than this."""

SWEEPS = 64
"""Value-iteration sweeps between two exact evaluations of :func:`best_without_limit`."""

EXACT_STATES = 1_000_000
"""The most states a policy is evaluated exactly on (one sparse LU factorisation, whose
fill-in grows faster than the states); past it, or out of memory, value iteration alone
gives a lower bound."""


@dataclass(frozen=True)
class Unlimited:
    """:func:`best_without_limit`'s answer: ``value[s]`` the most probability of reaching
    the goal from state ``s`` with no step limit; ``exact`` whether it is the optimum (to
    :data:`FIXED_POINT_TOLERANCE`), else a lower bound (the work budget ran out)."""

    value: np.ndarray
    exact: bool


class _Pairs:
    """The model's (state, column) pairs that have outcomes, and each outcome's kind."""

    def __init__(self, model: ModelArrays, goal_pos: int) -> None:
        self.n = model.obs_of.shape[0]
        self.width = width_of(model)
        counts = np.diff(model.ptr)
        self.live = counts > 0
        self.starts = model.ptr[:-1][self.live]
        self.pair_state = np.flatnonzero(self.live) // self.width
        at_goal = model.pos_of[model.next] == goal_pos
        self.success = (at_goal & ~model.stuck).astype(np.float64)
        self.goes_on = ~(at_goal | model.stuck)
        self.prob, self.next = model.prob, model.next
        self.goal_states = model.pos_of == goal_pos
        self.after = np.where(self.goes_on, model.next, self.n)  # n: worth nothing more
        self.first_pair = np.searchsorted(self.pair_state, np.arange(self.n))
        self.towards = self.prob * self.success  # the goal reached by the outcome

    def backup(self, value: np.ndarray, go_on: bool = True) -> np.ndarray:
        """float64[live pairs]: each pair's probability of the goal when the states after
        it are worth ``value`` (``go_on`` False: the last step, only the goal counts)."""
        if not go_on:
            return np.add.reduceat(self.towards, self.starts)
        return np.add.reduceat(self.towards + self.prob * np.append(value, 0.0)[self.after],
                               self.starts)

    def best(self, q: np.ndarray) -> np.ndarray:
        """float64[n]: each state's best pair value (1 at a goal state); every state has a
        pair (:func:`~gdq_pddl.envs.solve.solve` checks as much)."""
        out = np.maximum.reduceat(q, self.first_pair)
        out[self.goal_states] = 1.0
        return out


def best_within_limit(model: ModelArrays, goal_pos: int) -> np.ndarray:
    """float64[n_full]: the most probability of reaching the goal within
    ``model.step_limit`` actions from each state, over every policy."""
    pairs = _Pairs(model, goal_pos)
    value = np.zeros(pairs.n)
    for t in range(model.step_limit):
        value = pairs.best(pairs.backup(value, go_on=t > 0))
    return value


def best_without_limit(model: ModelArrays, goal_pos: int,
                       work: float = 1e8) -> Unlimited:
    """The most probability of reaching the goal with no step limit (module docstring),
    within about ``work`` outcome updates."""
    pairs = _Pairs(model, goal_pos)
    value = np.zeros(pairs.n)
    value[pairs.goal_states] = 1.0
    reach = _can_reach(pairs)
    sweeps_left = max(SWEEPS, int(work // max(1, len(pairs.prob))))
    since, every = 0, 1  # evaluate as soon as every state that can reach the goal is
    while sweeps_left > 0:  # valued above 0 (its policy is found), then every SWEEPS
        value = np.where(reach, pairs.best(pairs.backup(value)), 0.0)
        sweeps_left, since = sweeps_left - 1, since + 1
        if since < every or not (value[reach] > 0).all():
            continue
        since, every = 0, SWEEPS
        if int(reach.sum()) > EXACT_STATES:
            continue
        try:
            policy_value = _evaluate(pairs, _attractor(pairs, value))
        except MemoryError:  # the factorisation: value iteration alone, a lower bound
            every = sweeps_left + 1
            continue
        value = np.maximum(value, policy_value)
        improved = pairs.best(pairs.backup(policy_value)) - policy_value
        if improved.max(initial=0.0) <= FIXED_POINT_TOLERANCE:
            return Unlimited(policy_value, True)
    return Unlimited(value, False)


def _can_reach(pairs: _Pairs) -> np.ndarray:
    """bool[n]: the states from which some outcomes of positive probability lead to the
    goal (a goal state included); the goal is out of reach from every other state."""
    src = np.repeat(pairs.pair_state, np.diff(np.append(pairs.starts, len(pairs.prob))))
    keep = pairs.prob > 0
    goal_node = pairs.n  # one node for "the goal reached"
    dst = np.where(pairs.success > 0, goal_node, pairs.next)
    keep &= (pairs.success > 0) | pairs.goes_on
    back = csr_matrix((np.ones(int(keep.sum())), (dst[keep], src[keep])),
                      shape=(pairs.n + 1, pairs.n + 1))
    back = back + csr_matrix((np.ones(int(pairs.goal_states.sum())),
                              (np.full(int(pairs.goal_states.sum()), goal_node),
                               np.flatnonzero(pairs.goal_states))),
                             shape=(pairs.n + 1, pairs.n + 1))
    out = np.zeros(pairs.n + 1, dtype=np.bool_)
    out[breadth_first_order(back, goal_node, directed=True, return_predecessors=False)] = True
    return out[:-1]


def _attractor(pairs: _Pairs, value: np.ndarray) -> np.ndarray:
    """int64[n]: a live pair for each state (-1: none, the state is worth 0), of the best
    value under ``value``, chosen so that every chosen pair has an outcome to the goal or
    to a state chosen before it: the policy reaches the goal from every chosen state with
    positive probability, so its values solve one linear system."""
    q = pairs.backup(value)
    best = pairs.best(q)
    optimal = (q >= best[pairs.pair_state] - FIXED_POINT_TOLERANCE) & \
        (best[pairs.pair_state] > 0)
    chosen = np.full(pairs.n, -1, dtype=np.int64)
    done = pairs.goal_states.copy()
    towards = pairs.success * (pairs.prob > 0)  # outcomes that reach the goal
    while True:
        hit = np.add.reduceat(towards, pairs.starts) > 0
        new = optimal & hit & ~done[pairs.pair_state]
        if not new.any():
            return chosen
        idx = np.flatnonzero(new)
        state = pairs.pair_state[idx]
        first = np.unique(state, return_index=True)[1]  # the lowest such pair a state
        chosen[state[first]] = idx[first]
        done[state[first]] = True
        towards = towards + (pairs.goes_on & (pairs.prob > 0) & done[pairs.next])


def _evaluate(pairs: _Pairs, chosen: np.ndarray) -> np.ndarray:
    """float64[n]: the probability of reaching the goal from each state under the policy
    ``chosen`` (:func:`_attractor`; a state without a pair is worth 0, a goal state 1)."""
    value = np.zeros(pairs.n)
    value[pairs.goal_states] = 1.0
    states = np.flatnonzero(chosen >= 0)
    if not len(states):
        return value
    ends = np.append(pairs.starts[1:], len(pairs.prob))
    lo, hi = pairs.starts[chosen[states]], ends[chosen[states]]
    row_of = np.full(pairs.n, -1, dtype=np.int64)
    row_of[states] = np.arange(len(states))
    length = hi - lo
    row = np.repeat(np.arange(len(states)), length)
    outcome = np.repeat(lo - np.cumsum(length) + length, length) + np.arange(int(length.sum()))
    b = np.bincount(row, weights=pairs.prob[outcome] * pairs.success[outcome],
                    minlength=len(states))
    inner = pairs.goes_on[outcome] & (row_of[pairs.next[outcome]] >= 0)
    matrix = csr_matrix((pairs.prob[outcome][inner],
                         (row[inner], row_of[pairs.next[outcome][inner]])),
                        shape=(len(states), len(states)))
    value[states] = np.clip(spsolve((identity(len(states), format="csc") - matrix).tocsc(),
                                    b), 0.0, 1.0)
    return value
