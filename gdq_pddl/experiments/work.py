"""One unit of work: a method learning along a schedule of tasks, in one process
(:func:`run_unit`, what the process pool and Ray workers run: it depends only on the
:class:`~gdq_pddl.experiments.protocol.Unit`)."""

from __future__ import annotations

import io
from dataclasses import replace

import numpy as np

from gdq_pddl.envs.office import OfficeInstance
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.online_env import OnlineEnv
from gdq_pddl.envs.pddl_env import PDDLEnv, PDDLInstance
from gdq_pddl.errors import ConfigError
from gdq_pddl.experiments.knowledge import (  # load_pddl_instance: also read from here
    knowledge_instance,
    knowledge_world,
    load_pddl_instance,
    load_world_named,
)
from gdq_pddl.experiments.protocol import Experiment, Hyper, Unit
from gdq_pddl.learners import precompile
from gdq_pddl.learners.context import TaskContext, task_context
from gdq_pddl.learners.episodes import run_episodes
from gdq_pddl.learners.online import online_context
from gdq_pddl.learners.registry import learner_class
from gdq_pddl.learners.registry import make_learner as learner_by_name
from gdq_pddl.learners.saving import save_learner
from gdq_pddl.learners.tabular import TabularLearner
from gdq_pddl.world_types import Task, World


def resolve_task(world: World, spec: str) -> Task:
    """A task name (``C``) or an ad-hoc ``start->goal``."""
    if "->" in spec:
        start, goal = spec.split("->", 1)
        return world.resolve(start=start, goal=goal)
    return world.task(spec)


def make_learner(method: str, context, hyper: Hyper):
    """A fresh learner of ``method`` (a name, or a name with settings) for ``context``
    with the experiment's ``hyper`` where the method does not set them."""
    return learner_by_name(method, context, defaults={
        "alpha": hyper.alpha, "gamma": hyper.gamma, "epsilon": hyper.epsilon})


def instance_of(exp: Experiment, spec: str, reader: type[TabularLearner] = TabularLearner
                ) -> PDDLInstance | OfficeInstance:
    """The instance schedule entry ``spec`` of ``exp`` runs on: its PDDL problem
    (``exp.pddl``), or the task ``spec`` of its world (a name or ``start->goal``). A
    problem explored online is made for the learner class ``reader``: no estimates for
    one that reads no knowledge, estimates weighted by its ``estimate_weight``
    (:class:`OnlineInstance`)."""
    if exp.pddl is not None:
        if exp.pddl.online:  # states found as episodes reach them: one per run
            return OnlineInstance(load_pddl_instance(exp.pddl),
                                  estimate="h_add" if reader.reads_knowledge else None,
                                  estimate_weight=reader.estimate_weight)
        return load_pddl_instance(exp.pddl)
    world = load_world_named(exp.world)
    return OfficeInstance(world, resolve_task(world, spec))


def context_of(exp: Experiment, instance: PDDLInstance | OfficeInstance) -> TaskContext:
    """The learners' task context of ``instance``, planned on ``exp.knowledge`` (an office
    world, or of a PDDL experiment the knowledge's domain file). Its identity is
    ``instance``'s, what the learner acts in, whatever knowledge it planned on: a learner
    of a PDDL problem with a knowledge domain file belongs to the problem's env."""
    if exp.knowledge is not None and isinstance(instance, PDDLInstance):
        known = knowledge_instance(instance, exp.pddl, exp.knowledge)
        return replace(task_context(known, exp.planner),
                       identity=getattr(instance, "identity", None))
    if exp.knowledge is not None:  # the same task, planned on another world's building
        instance = replace(instance, world=knowledge_world(instance.world, exp.knowledge))
    if isinstance(instance, OnlineInstance):
        return online_context(instance, exp.planner)
    return task_context(instance, exp.planner)


def run_unit(unit: Unit, keep_learner: bool = False) -> dict[str, np.ndarray]:
    """Run one unit; returns per-episode arrays, the tasks in force and the final policy
    (``keep_learner``: and under ``learner`` the bytes of the learner's saved file)."""
    exp = unit.experiment
    rng, env_seed = unit.seeds()
    learner, parts, names = None, [], []
    for i, (spec, episodes) in enumerate(exp.schedule):
        instance = instance_of(exp, spec, learner_class(unit.method))
        context = context_of(exp, instance)
        if learner is None:
            learner = make_learner(unit.method, context, exp.hyper)
        else:
            learner.start_task(context)
        env = OnlineEnv(instance) if isinstance(instance, OnlineInstance) else \
            PDDLEnv(instance=instance)
        env.reset(seed=env_seed + i)
        parts.append(run_episodes(learner, env, episodes, rng))
        names.append(instance.name)
    result = {
        "returns": np.concatenate([p.returns for p in parts]),
        "steps": np.concatenate([p.steps for p in parts]),
        "success": np.concatenate([p.success for p in parts]),
        "areas": np.concatenate([p.area_visits for p in parts]),
        "tasks": np.array(names),
        "counts": np.array([n for _, n in exp.schedule], dtype=np.int64),
        "policy": np.asarray(learner.greedy_policy(), dtype=np.int64),
    }
    if keep_learner:
        if not isinstance(learner, TabularLearner):
            raise ConfigError(f"{unit.method}: --keep-learners saves tabular learners; a "
                              f"{type(learner).__name__} is not one")
        buf = io.BytesIO()
        save_learner(buf, learner, rng=rng, env=env.np_random)
        result["learner"] = np.frombuffer(buf.getvalue(), dtype=np.uint8)
    return result


def warm_up(units: list[Unit]) -> int:
    """Compile every kernel once in this process, so forked workers need not; returns the
    bytes of the largest learner's tables (what each worker adds to what it inherits)."""
    tiny: dict[tuple[str, str], Unit] = {}
    for u in units:
        if hasattr(learner_class(u.method), "run_own_episodes"):
            continue  # a deep-RL agent: no kernel to compile (torch imported in the workers)
        if (u.experiment.world, u.method) not in tiny:
            exp = replace(u.experiment, name="warm-up",
                          schedule=((u.experiment.schedule[0][0], 2),), runs=1)
            tiny[u.experiment.world, u.method] = Unit(exp, u.method, 0)
    loop = precompile.start(sorted({u.method for u in tiny.values()}))
    largest = 0
    try:
        for unit in tiny.values():  # a learner for the first task: its OptInit kernels
            exp = unit.experiment
            learner = make_learner(unit.method, context_of(exp, instance_of(
                exp, exp.schedule[0][0])), exp.hyper)
            largest = max(largest, learner.nbytes)
            del learner
    finally:
        precompile.wait(loop)
    for unit in tiny.values():
        run_unit(unit)
    return largest
