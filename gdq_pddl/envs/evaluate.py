"""Policies evaluated on a world's true model: greedy routes, exact values, task facts.

A policy's *intended* route starts at the task's start, doors closed, and follows the
most likely outcome (ties: the first listed) of each action until the goal, a stuck
outcome, a state without a policy entry, a repeated full state or
:data:`MAX_ROUTE_STEPS` actions.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from gdq_pddl.envs.model import compile_model, full_state
from gdq_pddl.envs.solve import expected_area_visits, expected_costs, optimal_value, solve_task
from gdq_pddl.envs.step import ModelArrays
from gdq_pddl.world_types import Task, World

MAX_ROUTE_STEPS = 30
RELEVANCE_THRESHOLD = 0.05
"""Expected visits per episode of the optimal policy above which an area is relevant (at
0 a slip of a ``goto`` makes nearly every area relevant)."""

Policy = Mapping[int, int] | np.ndarray
"""Learner state -> action (an array: -1 or out of range means no entry)."""


@dataclass(frozen=True)
class Route:
    """Where a greedy policy takes the robot (positions include the start); ``end`` says
    why the walk stopped: ``goal``, ``stuck``, ``loop``, ``no-policy`` or ``limit``."""

    positions: tuple[str, ...]
    reached_goal: bool
    end: str

    def areas(self, world: World) -> tuple[int, ...]:
        """Areas along the route, consecutive repeats dropped (positions in no area skipped)."""
        areas = [a for p in self.positions if (a := world.area_of.get(p)) is not None]
        return tuple(a for i, a in enumerate(areas) if i == 0 or areas[i - 1] != a)


def likeliest_next(model: ModelArrays, fs: int, action: int) -> int | None:
    """The likeliest next full state of ``action`` in ``fs`` (ties: the first; None: stuck)."""
    lo, hi = model.ptr[fs * model.n_actions + action: fs * model.n_actions + action + 2]
    k = lo + int(np.argmax(model.prob[lo:hi]))
    return None if model.stuck[k] else int(model.next[k])


def _follow(world: World, model: ModelArrays, fs: int, goal_pos: int,
            action_at: Callable[[int, int], int | None], steps: int, stop_on_loop: bool
            ) -> Route:
    """Walk from ``fs`` along likeliest outcomes of ``action_at(step, fs)`` (None: none)."""
    positions, seen = [world.positions[model.pos_of[fs]]], {fs}
    for step in range(steps):
        action = action_at(step, fs)
        fs = None if action is None else likeliest_next(model, fs, action)
        if fs is None:
            return Route(tuple(positions), False, "no-policy" if action is None else "stuck")
        positions.append(world.positions[model.pos_of[fs]])
        if model.pos_of[fs] == goal_pos:
            return Route(tuple(positions), True, "goal")
        if stop_on_loop and fs in seen:
            return Route(tuple(positions), False, "loop")
        seen.add(fs)
    return Route(tuple(positions), False, "limit")


def walk_policy(world: World, policy: Policy, start: str, goal: str,
                max_steps: int = MAX_ROUTE_STEPS) -> Route:
    """The intended route of ``policy`` from ``start`` to ``goal`` (see the module doc)."""
    model = compile_model(world)

    def action_at(_step: int, fs: int) -> int | None:
        obs = int(model.obs_of[fs])
        if isinstance(policy, np.ndarray):
            return int(policy[obs]) if obs < len(policy) and policy[obs] >= 0 else None
        return int(policy[obs]) if obs in policy else None

    return _follow(world, model, full_state(world, world.position(start)),
                   world.index[world.position(goal)], action_at, max_steps, True)


@dataclass(frozen=True)
class RouteSummary:
    """The final greedy routes of one method's runs, and the most common one (grouped by
    route in *area* terms and how the walk ended; ties: the group of the lowest run).
    :attr:`example` is that group's most common position sequence, for drawing."""

    routes: dict[int, Route]
    areas: tuple[int, ...]
    end: str
    count: int
    example: Route

    @property
    def runs(self) -> int:
        return len(self.routes)

    def on_route(self, world: World, areas: tuple[int, ...]) -> int:
        """Runs whose route reaches the goal through exactly ``areas``."""
        return sum(r.reached_goal and r.areas(world) == tuple(areas)
                   for r in self.routes.values())

    @classmethod
    def of(cls, world: World, task: Task, policies: Mapping[int, Policy]
           ) -> RouteSummary | None:
        """The intended routes of per-run policies (``{run: policy}``; empty ones skipped)
        and the most common one (None: no policy)."""
        routes = {r: walk_policy(world, p, task.start, task.goal)
                  for r, p in sorted(policies.items()) if len(p)}
        if not routes:
            return None
        ends = Counter((r.areas(world), r.end) for r in routes.values())
        (areas, end), count = ends.most_common(1)[0]
        members = [r for r in routes.values() if (r.areas(world), r.end) == (areas, end)]
        top = Counter(r.positions for r in members).most_common(1)[0][0]
        return cls(routes, areas, end, count, next(r for r in members if r.positions == top))


def resolve_task_label(world: World, label: str) -> Task:
    """The task a ``task`` column names: a task of the world (``C``), or an ad-hoc
    ``start->goal`` / ``start-goal`` pair of positions or landmarks."""
    if label in world.tasks or label.upper() in world.tasks:
        return world.task(label)
    for sep in ("->", "-"):
        if sep in label:
            start, goal = label.split(sep, 1)
            return world.resolve(start=start.strip(), goal=goal.strip())
    return world.task(label)  # raises, listing the known tasks


def optimal_route(world: World, task: Task | str) -> Route:
    """The likeliest route of the true optimal (time-dependent) policy from the start."""
    t = resolve_task_label(world, task) if isinstance(task, str) else task
    model = compile_model(world)
    solution, fs = solve_task(world, t, model)
    return _follow(world, model, fs, solution.goal_pos,
                   lambda step, fs: int(solution.policy[step, fs]), model.step_limit, False)


def policy_value(world: World, task: Task, policy: Policy,
                 model: ModelArrays | None = None) -> float:
    """Exact expected undiscounted return from the start of a stationary learner policy
    (backward induction with the rewards of :func:`gdq_pddl.envs.solve.solve`)."""
    model = compile_model(world) if model is None else model
    n_full, r = model.obs_of.shape[0], model.r_max
    if isinstance(policy, np.ndarray):
        pi = np.asarray(policy, dtype=np.int64)
    else:
        pi = np.zeros(int(model.obs_of.max()) + 1, dtype=np.int64)
        pi[list(policy)] = list(policy.values())
    act = pi[model.obs_of]
    lo, hi = (model.ptr[np.arange(n_full) * model.n_actions + act + k] for k in (0, 1))
    owner = np.repeat(np.arange(n_full), hi - lo)
    k = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi, strict=True)])
    prob, nxt, stuck = model.prob[k], model.next[k], model.stuck[k]
    goal_pos = world.index[task.goal]
    at_goal = model.pos_of[nxt] == goal_pos
    end_reward = np.where(at_goal & ~stuck, r, -r)
    cost = expected_costs(model)[act[owner]]
    v = np.zeros(n_full)
    for t in range(model.step_limit - 1, -1, -1):
        value = end_reward if t == model.step_limit - 1 else np.where(
            stuck | at_goal, end_reward, -cost + v[nxt])
        v = np.where(model.pos_of == goal_pos, 0.0,
                     np.bincount(owner, prob * value, minlength=n_full))
    return float(v[full_state(world, task.start)])


@dataclass(frozen=True)
class TaskTruth:
    """What the true model says about one task (``irrelevant_areas``: all but relevant)."""

    task: str
    v_star: float
    relevant_areas: tuple[int, ...]
    irrelevant_areas: tuple[int, ...]
    irrelevant_areas_paper: tuple[int, ...]
    optimal_route_areas: tuple[int, ...]


def task_truth(world: World, task: Task | str,
               given: Mapping[str, Any] | None = None) -> TaskTruth:
    """Facts of ``task`` from ``optimal.json`` (``given``) where present, computed otherwise."""
    given = given or {}
    t = resolve_task_label(world, task) if isinstance(task, str) else task

    def ints(key: str) -> tuple[int, ...] | None:
        value = given.get(key)
        return tuple(int(v) for v in value) if isinstance(value, list | tuple) else None

    all_areas = tuple(sorted(a for a, ps in world.areas.items() if ps))
    v_star = given.get("v_star")
    relevant = ints("relevant_areas")
    if relevant is None:
        visits = expected_area_visits(world, t)
        relevant = tuple(a for a in all_areas if visits.get(a, 0.0) > RELEVANCE_THRESHOLD)
    paper, route = ints("irrelevant_areas_paper"), ints("optimal_route_areas")
    return TaskTruth(
        t.name, float(v_star) if isinstance(v_star, int | float) else optimal_value(world, t),
        tuple(sorted(relevant)), tuple(a for a in all_areas if a not in relevant),
        paper if paper is not None else tuple(t.irrelevant_areas),
        route if route is not None else optimal_route(world, t).areas(world))
