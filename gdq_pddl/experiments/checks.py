"""What is checked before an experiment runs (:func:`preflight`, before the output folder
is touched): its tasks can be learnt and it fits in memory (the models and plans it builds
are then shared by forked workers)."""

from __future__ import annotations

from gdq_pddl.envs.office import OfficeInstance
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.envs.solve import check_solvable
from gdq_pddl.errors import WorldError
from gdq_pddl.experiments.protocol import Experiment
from gdq_pddl.experiments.work import instance_of
from gdq_pddl.limits import check_memory

EPISODE_BYTES = 400
"""Memory per episode while a unit runs and is saved (copies included)."""
UNIT_BYTES = 2000
"""Memory per unit in the driver."""
ROW_BYTES = 500
"""Memory per episode of ``episodes.csv`` when the report reads it back."""


def preflight(experiments: list[Experiment], jobs: int = 1) -> None:
    """Raise a :class:`~gdq_pddl.errors.GdqError` for anything that would make the
    experiments fail or give meaningless results."""
    check_sizes(experiments, jobs)
    for exp in experiments:
        for spec, _ in exp.schedule:
            instance = instance_of(exp, spec)
            if not isinstance(instance, OnlineInstance):  # checked as it is made
                check_instance(instance)


def check_instance(instance: PDDLInstance | OfficeInstance) -> None:
    """Refuse an office task whose V* would not fit in memory, or an instance on which no
    episode can reach the goal (a WorldError naming the file and key)."""
    model = instance.model
    source, key = instance.step_limit_key
    if not isinstance(instance, PDDLInstance):  # a PDDL problem's V* is within a budget
        check_solvable(model, f"{source}: {key}")
    # the plan table's length at the start, without running a planner (a learner that
    # reads no plans never pays for one)
    shortest = instance.goal_distance(instance.learner_start)
    if shortest < 0:  # World.resolve checks reachability: the knowledge disagrees
        raise WorldError(source, f"tasks.{instance.name}", "the planner finds no plan for "
                         f"task {instance.name}")
    if shortest > model.step_limit:
        raise WorldError(source, key, f"{model.step_limit} is less than the shortest plan of "
                         f"task {instance.name} ({shortest} actions): no episode can reach "
                         "the goal")


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
