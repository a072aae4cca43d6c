"""What a learner's inputs hold before any episode: Q at the start state right after OptInit
(:func:`optinit_values`, the report's *why GDQ-literal fails*)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gdq_pddl.experiments.protocol import GDQ_VARIANTS, Hyper
from gdq_pddl.experiments.results import RunConfig
from gdq_pddl.experiments.work import make_learner
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.world_types import Task, World


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
