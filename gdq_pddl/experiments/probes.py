"""What a learner's inputs hold before any episode: its knowledge along the true optimal
route (:func:`route_check`, the knowledge experiments) and Q at the start state right after
OptInit (:func:`optinit_values`, the report's *why GDQ-literal fails*)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gdq_pddl.envs.evaluate import likeliest_next
from gdq_pddl.envs.model import compile_model
from gdq_pddl.envs.solve import solve_task
from gdq_pddl.experiments.protocol import GDQ_VARIANTS, Hyper
from gdq_pddl.experiments.results import RunConfig
from gdq_pddl.experiments.work import make_learner
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import Task, World


@dataclass(frozen=True)
class RouteStep:
    """One step of the true optimal route: its optimal actions and whether one is allowed
    by DARLING, starts a shortest / tolerant plan, or applies in GDQ's prior model."""

    state: str
    optimal: tuple[str, ...]
    darling_allowed: bool
    in_shortest_plans: bool
    in_tolerant_plans: bool
    in_prior: bool = False


CHECKS = {"darling_allowed": "DARLING allows an optimal action", "in_prior": "an optimal "
          "action is applicable in the prior model (GDQ)", "in_shortest_plans": "... starts "
          "a shortest plan (GDQ-literal)", "in_tolerant_plans": "... a plan within 1.3x "
          "(GDQ-code)"}


def route_check(real: World, knowledge: World, task: Task,
                darling_tolerance: float = 0.3) -> list[RouteStep]:
    """:class:`RouteStep` s along the likeliest optimal route in ``real``."""
    ctx = office_task_context(knowledge, task, darling_tolerance=darling_tolerance)
    tables = (ctx.darling_plans.allowed_actions(), ctx.plans.first_actions,
              ctx.darling_plans.first_actions, ctx.prior.applicable)
    model = compile_model(real)
    solution, fs = solve_task(real, task, model)
    spaces = LearnerSpaces(real)
    out: list[RouteStep] = []
    for t in range(model.step_limit):
        obs, q = int(model.obs_of[fs]), solution.Q[t, fs]
        best = np.flatnonzero(q >= q.max() - 1e-9)
        out.append(RouteStep(spaces.state_name(obs),
                             tuple(spaces.action_name(int(a)) for a in best),
                             *(bool(table[obs, best].any()) for table in tables)))
        nxt = likeliest_next(model, fs, int(solution.policy[t, fs]))
        if nxt is None or model.pos_of[nxt] == solution.goal_pos:
            break
        fs = nxt
    return out


@dataclass(frozen=True)
class OptInitValues:
    """Q at the start state right after OptInit, per GDQ variant."""

    task: str
    r_max: float
    gamma: float
    alpha: float
    values: dict[str, tuple[float, float, int]]
    """Method -> (Q(s0, greedy action), median Q(s0, ·), number of actions)."""


def optinit_values(config: RunConfig, experiment: str, world: World, task: Task
                   ) -> OptInitValues:
    """Build each GDQ variant for ``task`` in ``world`` with the hyperparameters and planner
    ``config`` gives ``experiment`` (as the runner does); read Q(s0, ·) before any episode."""
    entry = next((e for e in config.experiments if e.get("name") == experiment
                  and any(t == task.name for t, _ in e.get("schedule") or [])),
                 config.experiment(experiment))
    raw = entry.get("hyper") if isinstance(entry.get("hyper"), dict) else {}
    hyper = Hyper(**{k: float(v) for k, v in raw.items() if k in ("alpha", "gamma", "epsilon")})
    planner = entry.get("planner") if isinstance(entry.get("planner"), str) else "graph"
    ctx = office_task_context(world, task, planner)
    values = {}
    for method in GDQ_VARIANTS:
        learner = make_learner(method, ctx, hyper)
        q = learner.q[ctx.s0]
        greedy = int(learner.greedy_policy()[ctx.s0])
        values[method] = (float(q[greedy]), float(np.median(q)), int(q.size))
    return OptInitValues(task.name, float(ctx.r_max), hyper.gamma, hyper.alpha, values)
