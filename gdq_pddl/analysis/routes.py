"""Routes of greedy policies, and the ground truth (V*, relevant areas, optimal route).

A learner's final greedy policy (``policies.csv``) is walked along its *intended* route:
start at the task's start with every door closed, apply the policy's action, follow the
action's most likely outcome (ties: the first listed), and stop at the goal, after
:data:`MAX_ROUTE_STEPS` actions, on a stuck outcome, at a state without a policy entry,
or when a full state repeats (the policy loops). The route in area terms drops
consecutive repeats: ``p0 p2 p4 p8 p5 p6 p7 p17`` is areas ``1 3 2 6``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from gdq_pddl.envs.model import ModelArrays, compile_model, full_state
from gdq_pddl.envs.solve import expected_area_visits, optimal_value, solve_task
from gdq_pddl.world import Task, World

MAX_ROUTE_STEPS = 30
BEST_ROUTE_C = (1, 3, 2, 6)
"""The paper's best Task C route in areas (easy doors d1 and d3)."""
RELEVANCE_THRESHOLD = 0.05
"""Expected visits per episode of the optimal policy above which an area is relevant
(only used when ``optimal.json`` gives no ``relevant_areas``: with a threshold of 0 a
slip of a ``goto`` makes nearly every area relevant)."""


@dataclass(frozen=True)
class Route:
    """Where a greedy policy takes the robot (positions include the start)."""

    positions: tuple[str, ...]
    reached_goal: bool
    end: str
    """Why the walk stopped: ``goal``, ``stuck``, ``loop``, ``no-policy`` or ``limit``."""

    def areas(self, world: World) -> tuple[int, ...]:
        return area_route(world, self.positions)


def area_route(world: World, positions: tuple[str, ...] | list[str]) -> tuple[int, ...]:
    """Areas along ``positions``, consecutive repeats dropped (positions in no area skipped)."""
    out: list[int] = []
    for p in positions:
        a = world.area_of.get(p)
        if a is not None and (not out or out[-1] != a):
            out.append(a)
    return tuple(out)


def likeliest_next(model: ModelArrays, fs: int, action: int) -> int | None:
    """The full state that ``action`` in full state ``fs`` most likely leads to (ties: the
    first listed outcome); None when that outcome is stuck."""
    i = fs * model.n_actions + action
    lo, hi = model.ptr[i], model.ptr[i + 1]
    k = lo + int(np.argmax(model.prob[lo:hi]))
    return None if model.stuck[k] else int(model.next[k])


def _follow(world: World, model: ModelArrays, fs: int, first: str, goal_pos: int,
            action_at: Callable[[int, int], int | None], steps: int,
            stop_on_loop: bool) -> Route:
    """Walk from full state ``fs`` (at position ``first``) along likeliest outcomes, taking
    ``action_at(step, fs)`` (None: no policy there) for at most ``steps`` actions; with
    ``stop_on_loop``, stop when a full state repeats."""
    positions = [first]
    seen = {fs}
    for step in range(steps):
        action = action_at(step, fs)
        if action is None:
            return Route(tuple(positions), False, "no-policy")
        nxt = likeliest_next(model, fs, action)
        if nxt is None:
            return Route(tuple(positions), False, "stuck")
        fs = nxt
        positions.append(world.positions[model.pos_of[fs]])
        if model.pos_of[fs] == goal_pos:
            return Route(tuple(positions), True, "goal")
        if stop_on_loop:
            if fs in seen:
                return Route(tuple(positions), False, "loop")
            seen.add(fs)
    return Route(tuple(positions), False, "limit")


def walk_policy(world: World, policy: Mapping[int, int] | np.ndarray, start: str, goal: str,
                max_steps: int = MAX_ROUTE_STEPS) -> Route:
    """Follow ``policy`` (learner state -> action) along likeliest outcomes; see module doc."""
    model = compile_model(world)
    goal_pos = world.index[world.position(goal)]
    fs = full_state(world, world.position(start))

    def action_at(_step: int, fs: int) -> int | None:
        obs = int(model.obs_of[fs])
        if isinstance(policy, np.ndarray):
            if obs >= len(policy) or policy[obs] < 0:
                return None
            return int(policy[obs])
        return int(policy[obs]) if obs in policy else None

    return _follow(world, model, fs, world.positions[model.pos_of[fs]], goal_pos, action_at,
                   max_steps, stop_on_loop=True)


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
    return _follow(world, model, fs, t.start, solution.goal_pos,
                   lambda step, fs: int(solution.policy[step, fs]), model.step_limit,
                   stop_on_loop=False)


@dataclass(frozen=True)
class TaskTruth:
    """What the true model says about one task."""

    task: str
    v_star: float
    relevant_areas: tuple[int, ...]
    irrelevant_areas: tuple[int, ...]
    """Computed: areas of the world not in :attr:`relevant_areas`."""
    irrelevant_areas_paper: tuple[int, ...]
    optimal_route_areas: tuple[int, ...]


def _ints(value: Any) -> tuple[int, ...] | None:
    if isinstance(value, (list, tuple)):
        return tuple(int(v) for v in value)
    return None


def task_truth(world: World, task: Task | str,
               given: Mapping[str, Any] | None = None) -> TaskTruth:
    """Facts of ``task`` from ``optimal.json`` (``given``) where present, computed otherwise."""
    given = given or {}
    t = resolve_task_label(world, task) if isinstance(task, str) else task
    all_areas = tuple(sorted(a for a, ps in world.areas.items() if ps))
    v_star = given.get("v_star")
    v = float(v_star) if isinstance(v_star, (int, float)) else optimal_value(world, t)
    relevant = _ints(given.get("relevant_areas"))
    if relevant is None:
        visits = expected_area_visits(world, t)
        relevant = tuple(a for a in all_areas if visits.get(a, 0.0) > RELEVANCE_THRESHOLD)
    paper = _ints(given.get("irrelevant_areas_paper"))
    route = _ints(given.get("optimal_route_areas"))
    if route is None:
        route = optimal_route(world, t).areas(world)
    return TaskTruth(
        task=t.name,
        v_star=v,
        relevant_areas=tuple(sorted(relevant)),
        irrelevant_areas=tuple(a for a in all_areas if a not in relevant),
        irrelevant_areas_paper=paper if paper is not None else tuple(t.irrelevant_areas),
        optimal_route_areas=route,
    )
