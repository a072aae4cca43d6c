"""The paper's two readings of GDQ: GDQ-literal (Algorithms 1-3 read literally) and
GDQ-code (the authors' released code). Both are Q-learning plus the learned model plus N
backups per real step along the plans H from the current state (:func:`backup_plans`).
GDQ-literal's OptInit is :func:`policy_iteration` on an optimistic model, its backups
assign the expected value; GDQ-code's OptInit is :func:`seed_plan_pairs`, its backups are
TD updates on replayed outcomes (:mod:`gdq_pddl.learners.learned_model`).
``docs/learners.md`` sets them side by side.
"""

from __future__ import annotations

import numba
import numpy as np

from gdq_pddl.learners.learned_model import expected_value, model_backup
from gdq_pddl.learners.tables import Model, Params, Plans, QTable, recompute_all_v


@numba.njit(cache=True)
def backup_plans(table: QTable, model: Model, plans: Plans, p: Params, s: int,
                 rng: np.random.Generator) -> bool:
    """N backups of a random transition of a random plan from ``s``; False if it has none."""
    lo, hi = plans.plan_ptr[s], plans.plan_ptr[s + 1]
    if hi <= lo:
        return False
    for _ in range(p.n_backups):
        k = lo + rng.integers(0, hi - lo)
        j = plans.pair_ptr[k] + rng.integers(0, plans.pair_ptr[k + 1] - plans.pair_ptr[k])
        model_backup(table, model, plans.opt_r, p, plans.pair_state[j], plans.pair_action[j],
                     rng)
    return True


@numba.njit(cache=True)
def policy_iteration(table: QTable, model: Model, opt_r: np.ndarray, p: Params,
                     eval_tol: float = 1e-10, improve_tol: float = 1e-6,
                     max_iter: int = 10_000) -> np.ndarray:
    """GDQ-literal's OptInit: policy iteration on the model (learned for known pairs,
    optimistic otherwise) from "action 0 everywhere", keeping the current action on ties
    (within ``improve_tol``), else the lowest index, until pi is stable. Writes the final
    Q into the Q table (goal rows 0) and returns pi."""
    goal = table.goal
    n_states, n_actions = table.q.shape
    pi = np.zeros(n_states, dtype=np.int64)
    v = np.zeros(n_states)
    qq = np.zeros((n_states, n_actions))
    for _ in range(max_iter):
        for _sweep in range(1_000_000):
            delta = 0.0
            for s in range(n_states):
                if goal[s]:
                    continue
                x = expected_value(model, goal, opt_r, p, s, pi[s], v)
                delta = max(delta, abs(x - v[s]))
                v[s] = x
            if delta < eval_tol:
                break
        stable = True
        for s in range(n_states):
            if goal[s]:
                continue
            best = -np.inf
            for a in range(n_actions):
                qq[s, a] = expected_value(model, goal, opt_r, p, s, a, v)
                best = max(best, qq[s, a])
            if qq[s, pi[s]] < best - improve_tol:
                stable = False
                for a in range(n_actions):
                    if qq[s, a] >= best - improve_tol:
                        pi[s] = a
                        break
        if stable:
            break
    table.q[:, :] = qq
    recompute_all_v(table)
    return pi


@numba.njit(cache=True)
def seed_plan_pairs(table: QTable, opt_r: np.ndarray, value: float) -> None:
    """GDQ-code's OptInit: Q <- 0, then Q <- ``value`` on OptInit's plan pairs ``opt_r``."""
    q = table.q
    q[:, :] = 0.0
    for s in range(q.shape[0]):
        for a in range(q.shape[1]):
            if opt_r[s, a]:
                q[s, a] = value
    recompute_all_v(table)
