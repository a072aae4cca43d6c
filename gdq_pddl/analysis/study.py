"""One output folder, read lazily: what figures, tables and reports share. A problem
has a map (areas, positions, routes) when its rows carry area visits."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd

from gdq_pddl.envs.evaluate import RouteSummary, TaskTruth, resolve_task_label, task_truth
from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.knowledge import load_world_named
from gdq_pddl.experiments.results import (
    ROBOT_EXPERIMENT,
    SWITCH_PREFIX,
    TASKS_EXPERIMENT,
    RunConfig,
    area_columns,
    is_gdq,
    load_config,
    load_optimal,
    load_policies,
    load_results,
    optimal_entry,
)
from gdq_pddl.learners import registry
from gdq_pddl.world_types import Task, World

PAPER_EXPERIMENTS = (TASKS_EXPERIMENT, ROBOT_EXPERIMENT)  # and every switch-*


def slug(label: str) -> str:
    """A label as a file-name part (``p0->p17`` -> ``p0_p17``)."""
    return re.sub(r"[^A-Za-z0-9]+", "_", label).strip("_") or "task"


def curves_stem(experiment: str) -> str:
    """The file stem of an uncovered experiment's learning-curve figure."""
    return "learning_curves_" + (slug(experiment) if slug(experiment) != "task" else "x")


@dataclass(frozen=True)
class Study:
    """The contents of an output folder (each file read on first use)."""

    out_dir: Path
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def open(cls, out_dir: str | Path) -> Study:
        study = cls(Path(out_dir))
        study.results  # noqa: B018  (read and check episodes.csv now: errors name the file)
        return study

    @cached_property
    def results(self) -> pd.DataFrame:
        return load_results(self.out_dir)

    @cached_property
    def config(self) -> RunConfig:
        return load_config(self.out_dir)

    @cached_property
    def policies(self) -> pd.DataFrame | None:
        return load_policies(self.out_dir)

    @cached_property
    def optimal(self) -> dict[str, dict]:
        return load_optimal(self.out_dir)

    @cached_property
    def _groups(self) -> dict[tuple, np.ndarray]:
        """Row indices per (experiment, method, task) and per (experiment, method)."""
        df = self.results
        out = dict(df.groupby(["experiment", "method", "task"], observed=True).indices)
        for key, rows in df.groupby(["experiment", "method"], observed=True).indices.items():
            out[(*key, None)] = rows
        return out

    def rows(self, experiment: str, method: str | None = None,
             task: str | None = None) -> pd.DataFrame:
        """The rows of one experiment (and method, and task)."""
        if method is not None:
            return self.results.iloc[self._groups.get((experiment, method, task), [])]
        if ("rows", experiment) not in self._cache:
            df = self.results
            self._cache[("rows", experiment)] = df[df["experiment"] == experiment]
        return self._cache[("rows", experiment)]

    @cached_property
    def experiments(self) -> list[str]:
        return sorted(self.results["experiment"].unique())

    def methods(self, experiment: str | None = None) -> list[str]:
        df = self.results if experiment is None else self.rows(experiment)
        return registry.order(df["method"].unique())

    def tasks(self, experiment: str) -> list[str]:
        """Task labels in order of first appearance (a switch's old task first)."""
        key = ("tasks", experiment)
        if key not in self._cache:
            first = self.rows(experiment).groupby("task", observed=True)["episode"].min()
            self._cache[key] = sorted(first.index, key=lambda t: (first[t], t))
        return list(self._cache[key])

    def has(self, experiment: str) -> bool:
        return experiment in self.experiments

    @property
    def switch_experiments(self) -> list[str]:
        return [e for e in self.experiments if e.startswith(SWITCH_PREFIX)]

    @property
    def uncovered(self) -> list[str]:
        """The experiments no paper section covers (``gdq-pddl run`` and the like)."""
        return [e for e in self.experiments
                if e not in PAPER_EXPERIMENTS and not e.startswith(SWITCH_PREFIX)]

    def baselines(self, experiment: str) -> list[str]:
        """Methods GDQ is tested against: every method but GDQ and its variants."""
        return [m for m in self.methods(experiment) if not is_gdq(m)]

    def matrix(self, column: str, experiment: str, method: str,
               task: str | None = None) -> np.ndarray:
        """``float64[runs, episodes]`` of ``column`` for one slice (runs and episodes
        ascending; NaN where a run lacks one); with a ``task``, only its episodes."""
        key = ("matrix", column, experiment, method, task)
        if key not in self._cache:
            rows = self.rows(experiment, method, task)
            self._cache[key] = np.empty((0, 0)) if rows.empty else rows.pivot(
                index="run", columns="episode", values=column).to_numpy(dtype=float)
        return self._cache[key]

    def returns(self, experiment: str, method: str, task: str | None = None) -> np.ndarray:
        return self.matrix("return", experiment, method, task)

    @cached_property
    def area_columns(self) -> list[str]:
        return area_columns(self.results.columns)

    @property
    def areas(self) -> tuple[int, ...]:
        """Area numbers that have a column."""
        return tuple(int(c[5:]) for c in self.area_columns)

    def has_areas(self, experiment: str) -> bool:
        """Whether ``experiment``'s rows record area visits (a PDDL problem's do not; an
        old folder's hold zeros), hence a map with areas and positions."""
        key = ("areas", experiment)
        if key not in self._cache:
            cols = self.area_columns
            self._cache[key] = bool(cols) and bool(self.rows(experiment)[cols].gt(0).any(
                axis=None))
        return self._cache[key]

    def area_visits(self, experiment: str, method: str, task: str | None = None
                    ) -> np.ndarray:
        """``float64[runs, episodes, n_areas]`` of area visits (areas as in :attr:`areas`;
        NaN where a run lacks an episode)."""
        mats = [self.matrix(c, experiment, method, task) for c in self.area_columns]
        if not mats or mats[0].size == 0:
            return np.empty((0, 0, len(mats)))
        return np.stack(mats, axis=-1)

    def world(self, experiment: str = TASKS_EXPERIMENT) -> World:
        """The world ``experiment`` ran in (one object per world, so models compile once)."""
        return load_world_named(self.config.world_spec(experiment))

    def task(self, experiment: str, label: str) -> Task | None:
        """The world task a ``task`` label names (None: the problem has no map)."""
        if not self.has_areas(experiment):
            return None
        try:
            return resolve_task_label(self.world(experiment), label)
        except GdqError:
            return None

    def v_star(self, experiment: str, task: str) -> float:
        """V* of ``task``: ``optimal.json``'s, else computed from the map (NaN: neither)."""
        value = optimal_entry(self.optimal, task, self.config.world_spec(experiment)).get(
            "v_star", optimal_entry(self.optimal, task).get("v_star"))
        if isinstance(value, int | float):
            return float(value)
        return self.truth(experiment, task).v_star if self.has_areas(experiment) else math.nan

    def truth(self, experiment: str, task: str) -> TaskTruth:
        """V*, relevant areas and optimal route of ``task`` on ``experiment``'s map
        (``optimal.json`` keys a task ``name`` in the office, ``name@world`` elsewhere)."""
        spec = self.config.world_spec(experiment)
        key = ("truth", spec, task)
        if key not in self._cache:
            t = self.task(experiment, task)
            if t is None:
                raise GdqError(f"experiment {experiment!r} has no map: no ground truth of "
                               f"task {task!r}")
            given = self.optimal.get(f"{t.name}@{spec}") or self.optimal.get(f"{task}@{spec}")
            if given is None and spec == "office":
                given = self.optimal.get(t.name) or self.optimal.get(task)
            self._cache[key] = task_truth(self.world(experiment), t, given)
        return self._cache[key]

    def switch_episode(self, experiment: str) -> int | None:
        """First episode of the new task in a switch experiment (None: a single task)."""
        tasks = self.tasks(experiment)
        if len(tasks) < 2:
            return None
        rows = self.rows(experiment)
        return int(rows.loc[rows["task"] == tasks[1], "episode"].min())

    @cached_property
    def _policy_map(self) -> dict[tuple[str, str, str, int], dict[int, int]]:
        if self.policies is None:
            return {}
        return {key: dict(zip(g["state"], g["action"], strict=True)) for key, g in
                self.policies.groupby(["experiment", "method", "task", "run"])}

    def policy(self, experiment: str, method: str, task: str, run: int) -> dict[int, int]:
        """Learner state -> greedy action of one run's final policy (empty: none stored)."""
        return self._policy_map.get((experiment, method, task, run), {})

    def route_summary(self, experiment: str, method: str, task: str) -> RouteSummary | None:
        """The intended routes of ``method``'s final greedy policies, walked per run, and
        the most common one (None: no policies or no map)."""
        if (t := self.task(experiment, task)) is None:
            return None
        return RouteSummary.of(self.world(experiment), t, {
            r: p for (*key, r), p in self._policy_map.items() if key == [experiment, method, task]})
