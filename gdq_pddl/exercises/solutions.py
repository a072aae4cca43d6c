"""Reference solutions of the graded exercises (:mod:`gdq_pddl.exercises`).

``gdq-pddl exercises init`` does not write this file: students get the stubs only. Each
function is the plain-Python reading of a rule of the learners, and
``tests/exercises/test_exercises.py`` checks that it computes what the learners compute
(the grader itself compares a student's function with the learners' own code wherever the
rule is one of theirs).
"""

from __future__ import annotations

import numpy as np


def q_update(q: np.ndarray, s: int, a: int, r: float, s2: int, done: bool, alpha: float,
             gamma: float) -> float:
    """Exercise 1: the new value of ``Q(s, a)`` after the real step ``(s, a, r, s2)``."""
    target = r if done else r + gamma * q[s2].max()
    return float(q[s, a] + alpha * (target - q[s, a]))


def dyna_planning(q: np.ndarray, counts: np.ndarray, stuck: np.ndarray, cost: np.ndarray,
                  goal: np.ndarray, pairs: list[tuple[int, int]], gamma: float,
                  r_max: float) -> np.ndarray:
    """Exercise 2: ``q`` after Dyna-Q's backups of ``pairs``, in order, on the model."""
    q = q.copy()
    for s, a in pairs:
        total = stuck[s, a] * -r_max
        for s2 in np.flatnonzero(counts[s, a]):
            k = counts[s, a, s2]
            total += k * (r_max if goal[s2] else -cost[s, a] + gamma * q[s2].max())
        q[s, a] = total / (counts[s, a].sum() + stuck[s, a])
    return q


def optinit(next_state: np.ndarray, goal: np.ndarray, gamma: float, r_max: float,
            step_cost: float = 1.0) -> np.ndarray:
    """Exercise 3: the Q table of value iteration on the knowledge's model."""
    n_states, n_actions = next_state.shape
    successor = np.where(next_state < 0, np.arange(n_states)[:, None], next_state)
    applicable = next_state >= 0
    allowed = applicable | ~applicable.any(axis=1, keepdims=True)
    v = np.zeros(n_states)
    while True:
        q = np.where(goal[successor], r_max, -step_cost + gamma * v[successor])
        q[goal] = 0.0
        new = np.where(allowed, q, -np.inf).max(axis=1)
        new[goal] = 0.0
        if np.abs(new - v).max() <= 1e-10:
            return q
        v = new


def hybrid_backup(s: int, a: int, v: np.ndarray, goal: np.ndarray, prior_next: np.ndarray,
                  visits: np.ndarray, learned: float, m: int, w: float, gamma: float,
                  r_max: float, prior_cost: float = 1.0) -> float:
    """Exercise 4: GDQ's value of ``(s, a)``: the prior's backup, mixed with the learned
    model's once the pair is known."""
    x = s if prior_next[s, a] < 0 else int(prior_next[s, a])
    prior = r_max if goal[x] else -prior_cost + gamma * v[x]
    n = int(visits[s, a])
    known = n > (m if prior_next[s, a] >= 0 else 0)
    if not known:
        return float(prior)
    return float((n * learned + w * prior) / (n + w))


def trials_to_turn_away(prior_value: float, trial_value: float, alternative: float,
                        w: float, m: int) -> int | None:
    """Exercise 5: how many failed trials of a pair the knowledge is wrong about before
    its value is below the alternative's (0: it already is; None: never)."""
    if prior_value < alternative:
        return 0
    if trial_value >= alternative:
        return None

    def value(n: int) -> float:
        return (n * trial_value + w * prior_value) / (n + w)

    # value(n) < alternative  <=>  n > w (prior - alternative) / (alternative - trial)
    n = max(m + 1, int(w * (prior_value - alternative) / (alternative - trial_value)) + 1)
    while n > m + 1 and value(n - 1) < alternative:  # the division's rounding, either way
        n -= 1
    while value(n) >= alternative:
        n += 1
    return n
