"""One unit of work: a method learning along a schedule of tasks, in one process.

:func:`run_unit` is what the local process pool and Ray workers execute; it depends only
on the :class:`~gdq_pddl.experiments.protocol.Unit`, so where it runs never changes what
it returns.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.protocol import Hyper, Unit
from gdq_pddl.experiments.worlds import load_world_named
from gdq_pddl.world import Task, World


def resolve_task(world: World, spec: str) -> Task:
    """A task name (``C``) or an ad-hoc ``start->goal``."""
    if "->" in spec:
        start, goal = spec.split("->", 1)
        return world.resolve(start=start, goal=goal)
    return world.task(spec)


def make_learner(method: str, context, hyper: Hyper):
    """A fresh learner of ``method`` (a name of ``protocol.METHODS``) for ``context``."""
    from gdq_pddl.experiments.protocol import METHODS
    from gdq_pddl.learners import make_learner as learner_by_name

    if method not in METHODS:
        raise GdqError(f"unknown method {method!r} (known: {', '.join(METHODS)})")
    common = {"alpha": hyper.alpha, "gamma": hyper.gamma, "epsilon": hyper.epsilon}
    for variant in ("code", "literal"):  # GDQ-code, DARLING-code, GDQ-literal
        if method.endswith(f"-{variant}"):
            return learner_by_name(method.removesuffix(f"-{variant}"), context,
                                   variant=variant, **common)
    return learner_by_name(method, context, **common)


def run_unit(unit: Unit) -> dict[str, np.ndarray]:
    """Run one unit; returns per-episode arrays, the tasks in force and the final policy."""
    from gdq_pddl.envs.office import OfficeEnv
    from gdq_pddl.learners.runner import run_episodes

    exp = unit.experiment
    if exp.pddl is not None:
        return _run_pddl_unit(unit)
    world = load_world_named(exp.world)
    rng, env_seed = unit.seeds()
    learner, parts = None, []
    for i, (spec, episodes) in enumerate(exp.schedule):
        task = resolve_task(world, spec)
        context = _office_context(exp, world, spec)
        if learner is None:
            learner = make_learner(unit.method, context, exp.hyper)
        else:
            learner.start_task(context)
        env = OfficeEnv(world=world, start=task.start, goal=task.goal)
        env.reset(seed=env_seed + i)
        parts.append(run_episodes(learner, env, episodes, rng))
    return _unit_result(parts, [resolve_task(world, t).name for t, _ in exp.schedule], exp,
                        learner)


def _unit_result(parts: list, tasks: list[str], exp, learner) -> dict[str, np.ndarray]:
    """What a unit returns: its episodes' records, the tasks in force and the final policy."""
    return {
        "returns": np.concatenate([p.returns for p in parts]),
        "steps": np.concatenate([p.steps for p in parts]),
        "success": np.concatenate([p.success for p in parts]),
        "areas": np.concatenate([p.area_visits for p in parts]),
        "tasks": np.array(tasks),
        "counts": np.array([n for _, n in exp.schedule], dtype=np.int64),
        "policy": np.asarray(learner.greedy_policy(), dtype=np.int64),
    }


@cache
def load_pddl_instance(files: tuple[str, ...]):
    """The :class:`~gdq_pddl.envs.pddl_env.PDDLInstance` of ``(domain, problem, dynamics)``
    or ``(domain, problem, dynamics, determinisation)`` (dynamics ``""``: none)."""
    from gdq_pddl.envs.pddl_env import PDDLInstance

    domain, problem, dynamics, *determinisation = files
    return PDDLInstance.from_files(domain, problem, dynamics or None,
                                   determinisation=determinisation[0] if determinisation
                                   else "all-outcomes")


def _run_pddl_unit(unit: Unit) -> dict[str, np.ndarray]:
    """:func:`run_unit` on a PDDL problem: every schedule entry runs on it (no areas)."""
    from gdq_pddl.envs.pddl_env import PDDLEnv
    from gdq_pddl.learners.context import pddl_task_context
    from gdq_pddl.learners.runner import run_episodes

    exp = unit.experiment
    instance = load_pddl_instance(tuple(exp.pddl))
    rng, env_seed = unit.seeds()
    context = pddl_task_context(instance, exp.planner)
    learner = make_learner(unit.method, context, exp.hyper)
    env = PDDLEnv(instance=instance)
    parts = []
    for i, (_, episodes) in enumerate(exp.schedule):
        if i:
            learner.start_task(context)
        env.reset(seed=env_seed + i)
        parts.append(run_episodes(learner, env, episodes, rng))
    return _unit_result(parts, [t for t, _ in exp.schedule], exp, learner)


def warm_up(units: list[Unit]) -> None:
    """Compile every kernel once in this process (so forked workers need not).

    The episode loop compiles in a second process meanwhile
    (:mod:`gdq_pddl.learners.precompile`): first every learner is built here (its OptInit
    kernels), then, once the other process is done, one tiny run each loads the loop
    from numba's cache.
    """
    from dataclasses import replace

    from gdq_pddl.learners import precompile

    tiny: dict[tuple[str, str], Unit] = {}
    for u in units:
        if (u.experiment.world, u.method) not in tiny:
            exp = replace(u.experiment, name="warm-up",
                          schedule=((u.experiment.schedule[0][0], 2),), runs=1)
            tiny[u.experiment.world, u.method] = Unit(exp, u.method, 0)
    loop = precompile.start()
    try:
        for unit in tiny.values():
            first_learner(unit)
    finally:
        precompile.wait(loop)
    for unit in tiny.values():
        run_unit(unit)


def first_learner(unit: Unit):
    """A learner of ``unit`` for its first task, OptInit done (what it learns from)."""
    exp = unit.experiment
    if exp.pddl is not None:
        from gdq_pddl.learners.context import pddl_task_context

        context = pddl_task_context(load_pddl_instance(tuple(exp.pddl)), exp.planner)
    else:
        context = _office_context(exp, load_world_named(exp.world), exp.schedule[0][0])
    return make_learner(unit.method, context, exp.hyper)


def _office_context(exp, world: World, spec: str):
    """The task context of schedule entry ``spec`` of an office experiment."""
    from gdq_pddl.experiments.knowledge import knowledge_world
    from gdq_pddl.learners.context import office_task_context

    task = resolve_task(world, spec)
    return office_task_context(knowledge_world(world, exp.knowledge), task, exp.planner)
