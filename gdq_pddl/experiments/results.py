"""An output folder's files as pandas tables: ``episodes.csv`` (:func:`load_results`,
checked against ``config.json``), ``policies.csv`` and ``optimal.json``."""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from gdq_pddl.errors import ResultsError
from gdq_pddl.learners import registry

METHOD_ORDER = registry.built_in_names()
"""The order the built-in methods are listed in every figure and table (the registry's;
methods with settings follow their learner, unknown ones follow all, sorted)."""
TASKS_EXPERIMENT, ROBOT_EXPERIMENT, SWITCH_PREFIX = "tasks", "robot", "switch-"
TEXT = ("experiment", "method", "task")
KEYS = (*TEXT, "run", "episode")
"""The columns that name one episode: no two rows share them."""
_WHOLE = {"run": 0, "episode": 1, "steps": 0}
"""Columns holding whole numbers, and their least value."""


def order_methods(methods: Iterable[str]) -> list[str]:
    """``methods`` in the registry's order (:func:`gdq_pddl.learners.registry.order`:
    a learner's name, then the same learner with settings), unknown names after them in
    sorted order."""
    return registry.order(methods)


def is_gdq(method: str) -> bool:
    """GDQ or one of its variants (``GDQ-literal``, ``GDQ-code``, with settings or not):
    not a baseline."""
    return registry.family(method) == registry.REFERENCE


def area_columns(columns: Iterable[str]) -> list[str]:
    """The ``area_<k>`` columns among ``columns``, in area order (any number of areas)."""
    return sorted((c for c in columns if c.startswith("area_") and c[5:].isdigit()),
                  key=lambda c: int(c[5:]))


def damaged_file(path: Path, why: str) -> ResultsError:
    """The error of an unreadable results file (the run's ``units/`` rebuild it)."""
    return ResultsError(f"{path} is damaged ({why}); the run's units/ rebuild it: give the "
                        "command that made it again, with --resume")


@dataclass(frozen=True)
class RunConfig:
    """``config.json``: ``{"experiments": [{"name", "schedule", "methods", "runs",
    "world", "seed", "planner", ...}, ...], "versions": {...}}`` (absent: empty)."""

    experiments: tuple[Mapping[str, Any], ...] = ()
    versions: Mapping[str, Any] = field(default_factory=dict)
    raw: Mapping[str, Any] = field(default_factory=dict)

    def experiment(self, name: str) -> Mapping[str, Any]:
        """The (first) config entry of experiment ``name`` (empty when absent)."""
        return next((e for e in self.experiments if e.get("name") == name), {})

    def world_spec(self, experiment: str) -> str:
        """The world (``office``, ``office_robot`` or a world file) ``experiment`` ran in."""
        value = self.experiment(experiment).get("world")
        if isinstance(value, str) and value:
            return value
        return "office_robot" if experiment == ROBOT_EXPERIMENT else "office"

    def planned(self) -> dict[tuple[str, str], tuple[int, int]]:
        """``(experiment, method) -> (runs, episodes per run)`` over the entries that say
        their schedule, methods and runs."""
        out: dict[tuple[str, str], tuple[int, int]] = {}
        for e in self.experiments:
            sched, methods, runs = e.get("schedule"), e.get("methods"), e.get("runs")
            if not (isinstance(sched, list) and isinstance(methods, list)
                    and isinstance(runs, int)):
                continue
            for m in methods:
                key = (str(e.get("name")), str(m))
                out[key] = (runs, out.get(key, (runs, 0))[1] + sum(int(n) for _, n in sched))
        return out


def load_config(folder: str | Path) -> RunConfig:
    """Read ``config.json`` if present (unreadable or absent: an empty :class:`RunConfig`)."""
    path = Path(folder) / "config.json"
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return RunConfig()
    if not isinstance(raw, dict):
        return RunConfig()
    exps = [e if isinstance(e, dict) else {"name": e} for e in raw.get("experiments") or []
            if isinstance(e, dict | str)]
    versions = raw.get("versions") if isinstance(raw.get("versions"), dict) else {}
    return RunConfig(tuple(exps), versions, raw)


def load_results(folder: str | Path, check: bool = True) -> pd.DataFrame:
    """The episodes of an output folder (or an ``episodes.csv``), one row per episode.

    Columns: ``experiment``, ``method``, ``task`` (category: e.g. ``switch-C-D``,
    ``GDQ``, ``C``), ``run`` (0-based), ``episode`` (1-based over the whole run),
    ``return``, ``steps``, ``success`` (1: goal reached), then ``area_1`` .. ``area_K``
    for a problem with areas (visits per area). ``return`` and the areas are float64 (an
    empty area cell is NaN), the other numbers int64.

    With ``check`` (default), a file that contradicts the folder's ``config.json`` (too
    few or too many episodes, a repeated episode, a method never run, a run beyond its
    runs) is refused. Raises :class:`~gdq_pddl.errors.ResultsError` naming the file.
    """
    path = Path(folder)
    path = path / "episodes.csv" if path.is_dir() else path
    try:
        df = pd.read_csv(path, dtype=dict.fromkeys(TEXT, "category"), keep_default_na=False,
                         na_values=[""])
    except FileNotFoundError:
        raise ResultsError(f"{path}: no such file (is this an experiment output "
                           "folder?)") from None
    except OSError as exc:
        raise ResultsError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except pd.errors.EmptyDataError:
        raise damaged_file(path, "empty file, expected a header row") from None
    except (pd.errors.ParserError, UnicodeDecodeError, ValueError) as exc:
        raise damaged_file(path, str(exc).strip().splitlines()[-1]) from None
    missing = [c for c in (*KEYS, "return") if c not in df.columns]
    if missing:
        raise damaged_file(path, f"missing columns {missing} (header: {list(df.columns)})")
    if df.empty:
        raise damaged_file(path, "no episodes, only the header")
    for name in df.columns.drop(list(TEXT)):
        df[name] = _numbers(path, df, name)
    for name in TEXT:
        if df[name].isna().any():
            raise damaged_file(path, f"line {_line(df[name].isna())}, column {name}: empty")
    if check:
        check_against_config(path, df, load_config(path.parent))
    return df


def _line(bad: pd.Series) -> int:
    """The file line of the first True row (the header is line 1)."""
    return int(np.flatnonzero(bad.to_numpy())[0]) + 2


def _numbers(path: Path, df: pd.DataFrame, name: str) -> pd.Series:
    """Column ``name`` as float64 (int64 for whole numbers), refusing what the runner
    never writes: text, non-finite values, bad counts, successes or visit counts."""
    raw = df[name]
    col = raw.astype("float64") if pd.api.types.is_numeric_dtype(raw) else \
        pd.to_numeric(raw, errors="coerce").astype("float64")
    area = name.startswith("area_")
    bad = (col.isna() & raw.notna()) | ~(np.isfinite(col) | (area & col.isna()))
    if name in _WHOLE:
        bad |= (col != np.floor(col)) | (col < _WHOLE[name])
    elif name == "success":
        bad |= (col != 0) & (col != 1)
    elif area:
        bad |= col < 0
    if bad.any():
        i = _line(bad)
        raise damaged_file(path, f"line {i}, column {name}: {raw.iloc[i - 2]!r} is not a "
                           "value a run writes")
    return col.astype("int64") if name in _WHOLE or name == "success" else col


def check_against_config(path: Path, df: pd.DataFrame, cfg: RunConfig) -> None:
    """Refuse ``df`` (read from ``path``) where it contradicts ``cfg``."""
    planned = cfg.planned()
    if not planned:
        return
    repeated = df.duplicated(list(KEYS))
    if repeated.any():
        row = df[list(KEYS)].iloc[_line(repeated) - 2]
        raise ResultsError(f"{path}: line {_line(repeated)} repeats an episode (experiment "
                           f"{row.experiment}, method {row.method}, task {row.task}, run "
                           f"{int(row.run)}, episode {int(row.episode)})")
    counts = df.groupby(["experiment", "method"], observed=True).size()
    for exp, method in counts.index:
        if (exp, method) not in planned:
            ran = ", ".join(m for e, m in planned if e == exp) or "nothing"
            raise ResultsError(f"{path}: method {method!r} of experiment {exp!r} was never "
                               f"run (config.json: {exp!r} ran {ran})")
    for (exp, method), (runs, episodes) in planned.items():
        n = int(counts.get((exp, method), 0))
        if n != runs * episodes:
            raise ResultsError(f"{path}: experiment {exp!r}, method {method!r} has {n} "
                               f"episodes, config.json says {runs * episodes} ({runs} runs "
                               f"x {episodes})")
    runs = df["run"].to_numpy()
    top = df["experiment"].map({e: r for (e, _), (r, _) in planned.items()}).to_numpy()
    if (runs >= top).any():
        i = int(np.flatnonzero(runs >= top)[0])
        raise ResultsError(f"{path}: line {i + 2}: run {runs[i]} of experiment "
                           f"{df['experiment'].iloc[i]!r}, config.json says "
                           f"{top[i]} runs (0 to {top[i] - 1})")


def load_policies(folder: str | Path) -> pd.DataFrame | None:
    """``policies.csv``: ``experiment, method, task, run, state, action`` (one greedy
    action per learner state and run); None when the folder has none."""
    path = Path(folder) / "policies.csv"
    if not path.exists():
        return None
    try:
        df = pd.read_csv(path, dtype=dict.fromkeys(TEXT, "string"), keep_default_na=False)
        df = df[[*TEXT, "run", "state", "action"]]
        return df.astype({"run": int, "state": int, "action": int})
    except (KeyError, ValueError, pd.errors.ParserError) as exc:
        raise damaged_file(path, f"{type(exc).__name__}: {exc}") from None


def load_optimal(folder: str | Path) -> dict[str, dict[str, Any]]:
    """``optimal.json``: task -> facts (``v_star``, ``relevant_areas``...); empty if absent."""
    path = Path(folder) / "optimal.json"
    if not path.exists():
        return {}
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except ValueError as exc:
        raise damaged_file(path, f"not JSON: {exc}") from None
    return {str(k): v for k, v in raw.items() if isinstance(v, dict)} if isinstance(
        raw, dict) else {}


def optimal_entry(optimal: Mapping[str, Mapping[str, Any]], task: str,
                  world: str | None = None) -> Mapping[str, Any]:
    """The ``optimal.json`` facts of task label ``task`` (keys are ``task`` or
    ``task@world``; with ``world``, only an entry of that world); empty when absent."""
    return next((v for k, v in optimal.items() if k.split("@", 1)[0] == task
                 and (world is None or v.get("world", world) == world)), {})
