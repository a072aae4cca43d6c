"""What is checked before an experiment runs: its tasks can be learnt and it fits in memory.

:func:`preflight` runs in the driver before the output folder is touched, so a task whose
goal cannot be reached, a step limit below the shortest plan, or sizes past what memory
holds are one clear error naming the file and key (or option) at fault, instead of a
folder of meaningless results or a crash after hours of work. It also compiles each
world's model and builds each task's shortest plans once in the driver, which forked
workers then share.
"""

from __future__ import annotations

from gdq_pddl.errors import WorldError
from gdq_pddl.experiments.protocol import Experiment
from gdq_pddl.limits import check_memory

EPISODE_BYTES = 400
"""Memory per episode while a unit runs and is saved (returns, steps, success and area
counts, copied when joined, pickled back from a worker and written)."""
UNIT_BYTES = 2000
"""Memory per unit in the driver (its description, key, file name and bookkeeping)."""
ROW_BYTES = 500
"""Memory per episode of ``episodes.csv`` when the report reads it back."""


def preflight(experiments: list[Experiment], jobs: int = 1) -> None:
    """Raise a :class:`~gdq_pddl.errors.GdqError` for anything that would make the
    experiments fail or give meaningless results (see the module docstring)."""
    check_sizes(experiments, jobs)
    for exp in experiments:
        if exp.pddl is not None:
            _check_pddl(exp)
        else:
            _check_office(exp)


def check_sizes(experiments: list[Experiment], jobs: int = 1) -> None:
    """Refuse ``--runs`` or ``--episodes`` whose units would not fit in memory."""
    n_units = sum(e.runs * len(e.methods) for e in experiments)
    longest = max(e.episodes for e in experiments)
    check_memory(n_units * UNIT_BYTES, f"--runs: {n_units:,} runs "
                 f"({' + '.join(f'{e.runs:,} x {len(e.methods)} methods' for e in experiments)})",
                 "give fewer --runs")
    check_memory(min(jobs, n_units) * longest * EPISODE_BYTES,
                 f"--episodes: {longest:,} episodes per run, {min(jobs, n_units)} run(s) at a "
                 "time,", "give fewer --episodes (or fewer --jobs)")


def check_report_size(experiments: list[Experiment]) -> None:
    """Refuse a report (which reads every episode back) that would not fit in memory."""
    rows = sum(e.runs * len(e.methods) * e.episodes for e in experiments)
    check_memory(rows * ROW_BYTES, f"the report: {rows:,} episodes read back from "
                 "episodes.csv", "give fewer --runs or --episodes, or --no-report")


def _check_office(exp: Experiment) -> None:
    from gdq_pddl.envs.model import compile_model
    from gdq_pddl.envs.solve import check_solvable
    from gdq_pddl.experiments.work import load_world_named, resolve_task
    from gdq_pddl.learners.context import office_plan_table
    from gdq_pddl.spaces import LearnerSpaces

    world = load_world_named(exp.world)
    check_solvable(compile_model(world), f"{world.source}: world.step_limit")
    for spec, _ in exp.schedule:
        task = resolve_task(world, spec)
        if task.start == task.goal:
            raise WorldError(world.source, f"tasks.{task.name}", f"start and goal are the "
                             f"same position ({task.start})")
        table = office_plan_table(world, task.goal, "graph", 0.0)
        shortest = int(table.length[LearnerSpaces(world).state(task.start)])
        if shortest < 0:  # World.resolve checks reachability: the knowledge disagrees
            raise WorldError(world.source, f"tasks.{task.name}", f"the planner finds no "
                             f"plan from {task.start} to {task.goal}")
        if shortest > world.step_limit:
            raise WorldError(world.source, "world.step_limit", f"{world.step_limit} is less "
                             f"than the shortest plan of task {task.name} ({shortest} "
                             "actions): no episode can reach the goal")


def _check_pddl(exp: Experiment) -> None:
    from gdq_pddl.envs.solve import check_solvable
    from gdq_pddl.experiments.work import load_pddl_instance

    instance = load_pddl_instance(tuple(exp.pddl))
    model = instance.model  # grounds, explores and checks the task (PDDLInstance.graph)
    check_solvable(model, f"{instance.dynamics.source}: dynamics.step_limit")
