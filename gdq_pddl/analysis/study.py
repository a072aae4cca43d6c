"""One experiment output folder, loaded lazily: the object figures, tables and report share."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from gdq_pddl.analysis.data import (
    SWITCH_PREFIX,
    TASKS_EXPERIMENT,
    Episodes,
    Policies,
    RunConfig,
    is_gdq,
    load_config,
    load_episodes,
    load_optimal,
    load_policies,
    load_world_spec,
)
from gdq_pddl.analysis.routes import (
    Route,
    TaskTruth,
    resolve_task_label,
    task_truth,
    walk_policy,
)
from gdq_pddl.errors import GdqError
from gdq_pddl.world import Task, World

PDDL_WORLD = "pddl"
"""The ``world`` the runner records for an experiment on a PDDL problem."""


@dataclass(frozen=True)
class RouteSummary:
    """The final greedy routes of one method's runs, and the most common one.

    Runs are grouped by route in *area* terms and how the walk ended (``goal``, ``loop``
    ...); the most common group is the method's route (ties: the group of the lowest
    run). :attr:`example` is that group's most common position sequence, for drawing.
    The report's table and the route figure both use this, so they always agree.
    """

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


def summarise_routes(world: World, routes: dict[int, Route]) -> RouteSummary | None:
    """The :class:`RouteSummary` of ``routes`` (None when there are none)."""
    if not routes:
        return None
    groups = Counter((r.areas(world), r.end) for _, r in sorted(routes.items()))
    (areas, end), count = groups.most_common(1)[0]
    members = [r for _, r in sorted(routes.items()) if (r.areas(world), r.end) == (areas, end)]
    top = Counter(r.positions for r in members).most_common(1)[0][0]
    example = next(r for r in members if r.positions == top)
    return RouteSummary(dict(routes), areas, end, count, example)


@dataclass(frozen=True)
class Study:
    """The contents of an output folder (each file read on first use)."""

    out_dir: Path
    _truths: dict[tuple[str, str], TaskTruth] = field(default_factory=dict, repr=False,
                                                     compare=False)

    @classmethod
    def open(cls, out_dir: str | Path) -> Study:
        out = Path(out_dir)
        if not (out / "episodes.csv").exists():
            raise FileNotFoundError(f"{out}: no episodes.csv (is this an experiment output "
                                    "folder?)")
        return cls(out)

    @cached_property
    def episodes(self) -> Episodes:
        return load_episodes(self.out_dir / "episodes.csv")

    @cached_property
    def config(self) -> RunConfig:
        return load_config(self.out_dir)

    @cached_property
    def policies(self) -> Policies | None:
        return load_policies(self.out_dir)

    @cached_property
    def _policy_map(self) -> dict[tuple[str, str, str, int], dict[int, int]]:
        return self.policies.grouped() if self.policies is not None else {}

    @cached_property
    def optimal(self) -> dict[str, dict]:
        return load_optimal(self.out_dir)

    @cached_property
    def _worlds(self) -> dict[str, World]:
        return {}

    def world(self, experiment: str = TASKS_EXPERIMENT) -> World:
        """The world ``experiment`` ran in (one object per world, so models compile once)."""
        spec = self.config.world_spec(experiment)
        if spec not in self._worlds:
            self._worlds[spec] = load_world_spec(spec)
        return self._worlds[spec]

    def is_pddl(self, experiment: str) -> bool:
        """Whether ``experiment`` ran on a PDDL problem (``gdq-pddl run --domain``), which
        has no world file, areas or positions."""
        return self.config.world_spec(experiment) == PDDL_WORLD

    def task(self, experiment: str, label: str) -> Task:
        """The task a ``task`` column label names in ``experiment``'s world (a
        :class:`GdqError` for a PDDL experiment: it has no world)."""
        if self.is_pddl(experiment):
            raise GdqError(f"experiment {experiment!r} ran on a PDDL problem: no world task")
        return resolve_task_label(self.world(experiment), label)

    def v_star(self, experiment: str, task: str) -> float:
        """V* of ``task``: :meth:`truth`'s, or for a PDDL experiment ``optimal.json``'s
        (NaN when absent)."""
        if not self.is_pddl(experiment):
            return self.truth(experiment, task).v_star
        from gdq_pddl.analysis.generic import optimal_entry

        value = optimal_entry(self.optimal, task, PDDL_WORLD).get("v_star")
        return float(value) if isinstance(value, (int, float)) else float("nan")

    def truth(self, experiment: str, task: str) -> TaskTruth:
        """V*, relevant areas and optimal route of ``task`` in ``experiment``'s world.

        ``optimal.json`` keys a task by name in the office and ``name@world`` elsewhere
        (the runner's convention); what it lacks is computed from the true model.
        """
        spec = self.config.world_spec(experiment)
        key = (spec, task)
        if key not in self._truths:
            t = self.task(experiment, task)
            given = self.optimal.get(f"{t.name}@{spec}") or self.optimal.get(f"{task}@{spec}")
            if given is None and spec == "office":
                given = self.optimal.get(t.name) or self.optimal.get(task)
            self._truths[key] = task_truth(self.world(experiment), t, given)
        return self._truths[key]

    def has(self, experiment: str) -> bool:
        return self.episodes.has(experiment)

    @property
    def switch_experiments(self) -> list[str]:
        return [e for e in self.episodes.experiments if e.startswith(SWITCH_PREFIX)]

    def methods(self, experiment: str) -> list[str]:
        return self.episodes.methods(experiment)

    def baselines(self, experiment: str) -> list[str]:
        """Methods GDQ is tested against: every method but GDQ and its variants."""
        return [m for m in self.methods(experiment) if not is_gdq(m)]

    def switch_episode(self, experiment: str) -> int | None:
        """First episode of the new task in a switch experiment (from the data; the
        config's ``switch_episode`` only when the data show a single task)."""
        ep = self.episodes
        tasks = ep.tasks(experiment)
        if len(tasks) >= 2:
            rows = ep.mask(experiment, task=tasks[1])
            return int(ep.values["episode"][rows].min())
        return self.config.switch_episode

    def route(self, experiment: str, method: str, task: str, run: int) -> Route | None:
        """The intended route of a run's final greedy policy (None: no policy stored)."""
        policy = self._policy_map.get((experiment, method, task, run))
        if not policy:
            return None
        t = self.task(experiment, task)
        return walk_policy(self.world(experiment), policy, t.start, t.goal)

    def routes(self, experiment: str, method: str, task: str) -> dict[int, Route]:
        """Run -> route, for every run of ``method`` with a stored policy for ``task``."""
        runs = sorted({r for (e, m, t, r) in self._policy_map
                       if e == experiment and m == method and t == task})
        out = {}
        for r in runs:
            route = self.route(experiment, method, task, r)
            if route is not None:
                out[r] = route
        return out

    def route_summary(self, experiment: str, method: str, task: str) -> RouteSummary | None:
        """The most common final greedy route of ``method`` (None: no policies)."""
        return summarise_routes(self.world(experiment), self.routes(experiment, method, task))

    def returns(self, experiment: str, method: str, task: str | None = None) -> np.ndarray:
        return self.episodes.matrix("return", experiment, method, task)
