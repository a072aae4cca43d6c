"""Reading an experiment output folder into numpy arrays.

The runner writes, per output folder:

- ``episodes.csv``: one row per episode, columns ``experiment, method, task, run,
  episode, return, steps, success``, then ``area_1 .. area_k`` in an office folder (a
  PDDL run has none; older PDDL folders have columns of zeros);
- ``config.json``: the run's configuration (only a few keys are read, all optional);
- ``policies.csv``: ``experiment, method, task, run, state, action``, the final greedy
  policy of each run, and (since the names were added; not read here)
  ``state_name, action_name``;
- ``optimal.json``: ``{task: {"v_star", "relevant_areas", ...}}``.

:func:`load_episodes` (in :mod:`.episodes`) reads ``episodes.csv`` once (about 600k rows
for a full reproduction) into an :class:`Episodes` table whose :meth:`Episodes.matrix`
reshapes one (experiment, method[, task]) slice into ``[runs, episodes]``; this module
reads the other files. The experiment and method names are in :mod:`.names`; every name
stays importable from here.
"""

from __future__ import annotations

import csv
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gdq_pddl.analysis.episodes import CATEGORICAL, Episodes, damaged_file, load_episodes
from gdq_pddl.analysis.names import (
    METHOD_ORDER,
    ROBOT_EXPERIMENT,
    SWITCH_PREFIX,
    TASKS_EXPERIMENT,
    is_gdq,
    order_methods,
)
from gdq_pddl.world import World, builtin_world, load_world

__all__ = [
    "CATEGORICAL", "METHOD_ORDER", "ROBOT_EXPERIMENT", "SWITCH_PREFIX", "TASKS_EXPERIMENT",
    "Episodes", "Policies", "RunConfig", "is_gdq", "load_config", "load_episodes",
    "load_optimal", "load_policies", "load_world_spec", "order_methods",
]


@dataclass(frozen=True)
class RunConfig:
    """The keys of ``config.json`` the analysis uses, with defaults for absent ones.

    The runner writes ``{"experiments": [{"name", "schedule", "methods", "runs", "world",
    "seed", ...}, ...], "versions": {...}}``; flat keys (``world``, ``seed``, ``runs``,
    ``episodes``, ``switch_episode``, ``methods``) are read too, as fallbacks.
    """

    world: str | None = None
    seed: int | None = None
    episodes: int | None = None
    runs: int | None = None
    switch_episode: int | None = None
    methods: tuple[str, ...] = ()
    experiments: tuple[Mapping[str, Any], ...] = ()
    """One mapping per experiment (a bare name in the file becomes ``{"name": name}``)."""
    versions: Mapping[str, Any] = field(default_factory=dict)
    raw: Mapping[str, Any] = field(default_factory=dict)

    def experiment(self, name: str) -> Mapping[str, Any]:
        """The config entry of experiment ``name`` (empty when absent)."""
        return next((e for e in self.experiments if e.get("name") == name), {})

    def world_spec(self, experiment: str) -> str:
        """``office``, ``office_robot`` or a world-file path that ``experiment`` ran in."""
        value = self.experiment(experiment).get("world")
        if isinstance(value, str) and value:
            return value
        if experiment == ROBOT_EXPERIMENT:
            robot = self.raw.get("robot_world")
            return robot if isinstance(robot, str) and robot else "office_robot"
        return self.world or "office"


def load_config(out_dir: str | Path) -> RunConfig:
    """Read ``config.json`` if present; unknown keys are kept in ``raw`` and ignored."""
    path = Path(out_dir) / "config.json"
    if not path.exists():
        return RunConfig()
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except ValueError:  # JSONDecodeError, UnicodeDecodeError: the analysis does without
        return RunConfig()
    if not isinstance(raw, dict):
        return RunConfig()

    def opt_int(key: str) -> int | None:
        v = raw.get(key)
        return int(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None

    experiments = []
    for e in raw.get("experiments", []) or []:
        if isinstance(e, dict):
            experiments.append(e)
        elif isinstance(e, str):
            experiments.append({"name": e})
    world = raw.get("world")
    methods = raw.get("methods", []) or []
    return RunConfig(
        world=world if isinstance(world, str) else None,
        seed=opt_int("seed"),
        episodes=opt_int("episodes"),
        runs=opt_int("runs"),
        switch_episode=opt_int("switch_episode"),
        methods=tuple(str(m) for m in methods) if isinstance(methods, list) else (),
        experiments=tuple(experiments),
        versions=raw.get("versions", {}) if isinstance(raw.get("versions"), dict) else {},
        raw=raw,
    )


def load_world_spec(spec: str) -> World:
    """``office`` / ``office_robot`` (built in) or a world file (loud error if unreadable)."""
    if spec in ("office", "office_robot"):
        return builtin_world(spec)
    return load_world(spec)


@dataclass(frozen=True)
class Policies:
    """``policies.csv``: one greedy action per (experiment, method, task, run, state)."""

    rows: tuple[tuple[str, str, str, int, int, int], ...]

    def keys(self, experiment: str) -> list[tuple[str, str, int]]:
        """``(method, task, run)`` triples with a policy in ``experiment``."""
        return sorted({(m, t, r) for e, m, t, r, _, _ in self.rows if e == experiment})

    def policy(self, experiment: str, method: str, task: str, run: int) -> dict[int, int]:
        """State -> greedy action for one run."""
        return {s: a for e, m, t, r, s, a in self.rows
                if e == experiment and m == method and t == task and r == run}

    def grouped(self) -> dict[tuple[str, str, str, int], dict[int, int]]:
        """Every policy at once: ``(experiment, method, task, run) -> {state: action}``."""
        out: dict[tuple[str, str, str, int], dict[int, int]] = {}
        for e, m, t, r, s, a in self.rows:
            out.setdefault((e, m, t, r), {})[s] = a
        return out


def load_policies(out_dir: str | Path) -> Policies | None:
    """Read ``policies.csv``; None when the folder has none."""
    path = Path(out_dir) / "policies.csv"
    if not path.exists():
        return None
    try:
        with path.open(newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            rows = tuple((r["experiment"], r["method"], r["task"], int(float(r["run"])),
                          int(float(r["state"])), int(float(r["action"]))) for r in reader)
    except (KeyError, TypeError, ValueError, csv.Error) as exc:  # a missing cell or column
        raise damaged_file(path, f"{type(exc).__name__}: {exc}") from None
    return Policies(rows)


def load_optimal(out_dir: str | Path) -> dict[str, dict[str, Any]]:
    """Read ``optimal.json`` (task -> facts); empty when absent or malformed."""
    path = Path(out_dir) / "optimal.json"
    if not path.exists():
        return {}
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except ValueError as exc:  # JSONDecodeError, UnicodeDecodeError
        raise damaged_file(path, f"not JSON: {exc}") from None
    return {str(k): v for k, v in raw.items() if isinstance(v, dict)} if isinstance(
        raw, dict) else {}
