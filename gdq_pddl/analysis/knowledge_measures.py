"""The measurements of the wrong-knowledge report, per run and per policy: convergence
(first passage of the trailing mean return over a threshold), the exact value of a
greedy policy in the real world, and what the knowledge allows along the true optimal
route. :mod:`gdq_pddl.analysis.knowledge` defines them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gdq_pddl.analysis.routes import likeliest_next
from gdq_pddl.envs.model import ModelArrays, compile_model, full_state
from gdq_pddl.envs.solve import expected_costs, solve_task
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import Task, World

WINDOW = 100
"""Moving-average window (episodes) of the convergence criterion."""
CURVE_WINDOW = 50
"""Moving-average window (episodes) of the learning curves."""
FRACTION = 0.85
"""Convergence threshold: V* - (1 - FRACTION) |V*|."""
FINAL = 100
"""Episodes at the end over which the final mean return is reported."""
ACCURATE, WRONG = "accurate", "wrong"


def threshold(v_star: float, fraction: float = FRACTION) -> float:
    """The return level a converged learner's moving average stays at or above."""
    return v_star - (1.0 - fraction) * abs(v_star)


def moving_average(returns: np.ndarray, window: int = WINDOW) -> np.ndarray:
    """Trailing means over ``window`` episodes; entry i covers episodes i+1 .. i+window
    (1-based), so its episode number is ``i + window``. Works on [episodes] or
    [runs, episodes]."""
    x = np.asarray(returns, dtype=np.float64)
    w = min(window, x.shape[-1])
    c = np.cumsum(x, axis=-1)
    c = np.concatenate([np.zeros((*x.shape[:-1], 1)), c], axis=-1)
    return (c[..., w:] - c[..., :-w]) / w


def convergence_episode(returns: np.ndarray, level: float, window: int = WINDOW) -> int | None:
    """First episode (1-based) at which the trailing ``window``-episode mean return is
    >= ``level``; None if it never is."""
    ma = moving_average(returns, window)
    hits = np.flatnonzero(ma >= level)
    return None if hits.size == 0 else int(hits[0]) + min(window, len(returns))


def median_episode(episodes: list[int | None]) -> float:
    """Median over runs with unconverged runs as +inf (inf: most runs never converged)."""
    if not episodes:
        return float("nan")
    return float(np.median([np.inf if e is None else e for e in episodes]))


def policy_value(world: World, task: Task, policy: dict[int, int] | np.ndarray,
                 model: ModelArrays | None = None) -> float:
    """Exact expected undiscounted return from the start of a stationary learner policy
    (learner state -> action) in ``world``, by backward induction over the step limit
    (the same outcome rewards as :func:`gdq_pddl.envs.solve.solve`)."""
    model = compile_model(world) if model is None else model
    n_actions, limit, r = model.n_actions, model.step_limit, model.r_max
    n_full = model.obs_of.shape[0]
    if isinstance(policy, dict):
        pi = np.zeros(int(model.obs_of.max()) + 1, dtype=np.int64)
        for s, a in policy.items():
            pi[s] = a
    else:
        pi = np.asarray(policy, dtype=np.int64)
    act = pi[model.obs_of]
    pairs = np.arange(n_full) * n_actions + act
    lo, hi = model.ptr[pairs], model.ptr[pairs + 1]
    owner = np.repeat(np.arange(n_full), hi - lo)
    k = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi, strict=True)])
    prob, nxt, stuck = model.prob[k], model.next[k], model.stuck[k]
    goal_pos = world.index[task.goal]
    at_goal = model.pos_of[nxt] == goal_pos
    ending = stuck | at_goal
    end_reward = np.where(stuck, -r, np.where(at_goal, r, -r))
    cost = expected_costs(model)[act[owner]]
    goal_states = model.pos_of == goal_pos
    v = np.zeros(n_full)
    for t in range(limit - 1, -1, -1):
        value = end_reward if t == limit - 1 else np.where(ending, end_reward, -cost + v[nxt])
        v = np.where(goal_states, 0.0, np.bincount(owner, prob * value, minlength=n_full))
    return float(v[full_state(world, task.start)])


@dataclass(frozen=True)
class RouteStep:
    """One step of the true optimal route and what the knowledge allows there."""

    state: str
    optimal: tuple[str, ...]
    """Optimal actions (ties within 1e-9) at this step."""
    darling_allowed: bool
    in_shortest_plans: bool
    in_tolerant_plans: bool
    in_prior: bool = False
    """An optimal action is one the knowledge says can do something here (GDQ's prior
    model values it before it is tried)."""


def route_check(real: World, knowledge: World, task: Task,
                darling_tolerance: float = 0.3) -> list[RouteStep]:
    """Along the likeliest route of the true optimal policy in ``real``: are the optimal
    actions in DARLING's allowed set / in the plans / applicable in GDQ's prior model,
    with knowledge from ``knowledge``?"""
    ctx = office_task_context(knowledge, task, darling_tolerance=darling_tolerance)
    allowed = ctx.darling_plans.allowed_actions()
    shortest = ctx.plans.first_actions
    tolerant = ctx.darling_plans.first_actions
    model = compile_model(real)
    solution, fs = solve_task(real, task, model)
    spaces = LearnerSpaces(real)
    out: list[RouteStep] = []
    for t in range(model.step_limit):
        obs = int(model.obs_of[fs])
        q = solution.Q[t, fs]
        best = np.flatnonzero(q >= q.max() - 1e-9)
        out.append(RouteStep(
            state=spaces.state_name(obs),
            optimal=tuple(spaces.action_name(int(a)) for a in best),
            darling_allowed=bool(allowed[obs, best].any()),
            in_shortest_plans=bool(shortest[obs, best].any()),
            in_tolerant_plans=bool(tolerant[obs, best].any()),
            in_prior=bool(ctx.prior.applicable[obs, best].any())))
        nxt = likeliest_next(model, fs, int(solution.policy[t, fs]))
        if nxt is None or model.pos_of[nxt] == solution.goal_pos:
            break
        fs = nxt
    return out
