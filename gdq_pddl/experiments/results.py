"""An output folder's files as pandas tables: ``episodes.csv`` (:func:`load_results`,
checked against ``config.json``), ``policies.csv`` and ``optimal.json``."""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from gdq_pddl.errors import GdqError, ResultsError
from gdq_pddl.learners import registry

TASKS_EXPERIMENT, ROBOT_EXPERIMENT, SWITCH_PREFIX = "tasks", "robot", "switch-"
TEXT = ("experiment", "method", "task")
KEYS = (*TEXT, "run", "episode")
"""The columns that name one episode: no two rows share them."""
_WHOLE = {"run": 0, "episode": 1, "steps": 0}
"""Columns holding whole numbers, and their least value."""


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
    """Read ``config.json`` if present (absent: an empty :class:`RunConfig`, nothing to
    check against). A damaged one is refused, a :class:`ResultsError` naming the file and
    the key: not JSON, not an object, or an experiment entry without a name, a schedule of
    ``[task, episodes]``, methods and runs (what the runner writes)."""
    path = Path(folder) / "config.json"
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return RunConfig()
    except OSError as exc:
        raise ResultsError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise _damaged_config(path, f"not UTF-8 text: {exc}") from None
    try:
        raw = json.loads(text)
    except ValueError as exc:
        raise _damaged_config(path, f"not JSON: {exc}") from None
    if not isinstance(raw, dict):
        raise _damaged_config(path, f"a JSON {type(raw).__name__}, not an object")
    listed = raw.get("experiments", [])
    if not isinstance(listed, list):
        raise _damaged_config(path, f"key experiments is {listed!r}, expected a list")
    exps = []
    for i, e in enumerate(listed):
        if isinstance(e, str):  # a bare name: an experiment of defaults, nothing planned
            exps.append({"name": e})
            continue
        _check_entry(path, i, e)
        exps.append(e)
    versions = raw.get("versions") if isinstance(raw.get("versions"), dict) else {}
    return RunConfig(tuple(exps), versions, raw)


def _damaged_config(path: Path, why: str) -> ResultsError:
    return ResultsError(f"{path} is damaged ({why}); it records what the folder holds, so "
                        "its results cannot be checked: run the command that made them again "
                        "into another --out")


def _whole(x: object, least: int) -> bool:
    return isinstance(x, int) and not isinstance(x, bool) and x >= least


def _check_entry(path: Path, i: int, e: object) -> None:
    """Refuse experiment entry ``i`` of ``config.json`` unless it is what the runner writes."""
    where = f"experiments[{i}]"
    if not isinstance(e, dict):
        raise _damaged_config(path, f"{where} is {e!r}, expected an object")
    expected = {"name": "a name", "schedule": "a list of [task, episodes]",
                "methods": "a list of method names", "runs": "a whole number >= 1"}
    sched, methods = e.get("schedule"), e.get("methods")
    good = {"name": isinstance(e.get("name"), str) and e.get("name") != "",
            "schedule": isinstance(sched, list) and len(sched) > 0 and all(
                isinstance(x, list) and len(x) == 2 and isinstance(x[0], str)
                and _whole(x[1], 1) for x in sched),
            "methods": isinstance(methods, list) and len(methods) > 0
            and all(isinstance(m, str) and m for m in methods),
            "runs": _whole(e.get("runs"), 1)}
    for key, ok in good.items():
        if not ok:
            value = e.get(key, "missing")
            raise _damaged_config(path, f"{where}.{key} is {value!r}, expected "
                                  f"{expected[key]}")


def unfinished(folder: Path) -> ResultsError | None:
    """The error of a folder whose run stopped before writing ``episodes.csv`` (its
    ``config.json`` lists the experiments), saying how to finish it; None if it is no
    such folder (another command's, a ``scale`` folder, or none)."""
    if not (folder / "config.json").is_file():
        return None
    planned = load_config(folder).experiments
    if not planned:
        return None
    total = sum(int(e.get("runs", 0)) * len(e.get("methods", ())) for e in planned)
    units = folder / "units"
    done = sum(1 for _ in units.glob("*.npz")) if units.is_dir() else 0
    of = f" of {total}" if total else ""
    return ResultsError(f"{folder} holds a run that did not finish ({done}{of} runs saved in "
                        "units/, no episodes.csv yet): finish it by giving the command that "
                        "started it again with --resume, then report")


def load_results(folder: str | Path, check: bool = True) -> pd.DataFrame:
    """The episodes of an output folder (or an ``episodes.csv``), one row per episode.

    Columns: ``experiment``, ``method``, ``task`` (category: e.g. ``switch-C-D``,
    ``GDQ``, ``C``), ``run`` (0-based), ``episode`` (1-based over the whole run),
    ``return``, ``steps``, ``success`` (1: goal reached), then ``area_1`` .. ``area_K``
    for a problem with areas (visits per area). ``return`` and the areas are float64 (an
    empty area cell is NaN), the other numbers int64.

    With ``check`` (default), every row is checked against the folder's ``config.json``
    (:func:`check_against_config`): a repeated episode, a method, task or run it never
    scheduled, an episode outside its schedule, a run with too few or too many episodes
    are refused, and so is a damaged ``config.json`` (:func:`load_config`). Raises
    :class:`~gdq_pddl.errors.ResultsError` naming the file and the line or key.
    """
    path = Path(folder)
    path = path / "episodes.csv" if path.is_dir() else path
    try:
        df = pd.read_csv(path, dtype=dict.fromkeys(TEXT, "category"), keep_default_na=False,
                         na_values=[""])
    except FileNotFoundError:
        stopped = unfinished(path.parent) if path.name == "episodes.csv" else None
        if stopped is not None:
            raise stopped from None
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
    """Refuse ``df`` (read from ``path``) where it contradicts ``cfg``: every row must be
    an episode the config scheduled (its experiment ran its method, its run is below the
    runs, its task is in the schedule and its episode in that task's part of it), once,
    and every run of every method must have all its episodes."""
    planned = cfg.planned()
    if not planned:
        return
    repeated = df.duplicated(list(KEYS))
    if repeated.any():
        row = df[list(KEYS)].iloc[_line(repeated) - 2]
        raise ResultsError(f"{path}: line {_line(repeated)} repeats an episode (experiment "
                           f"{row.experiment}, method {row.method}, task {row.task}, run "
                           f"{int(row.run)}, episode {int(row.episode)})")
    segments = _segments(cfg)
    run, episode = df["run"].to_numpy(), df["episode"].to_numpy()
    found = np.zeros(len(df), dtype=np.bool_)
    counts: dict[tuple[int, str, int], int] = {}
    for key, idx in df.groupby(list(TEXT), observed=True, sort=False).indices.items():
        for seg in segments.get(tuple(str(k) for k in key), ()):
            mine = idx[~found[idx]]
            hit = mine[(episode[mine] > seg.lo) & (episode[mine] <= seg.hi) &
                       (run[mine] < seg.runs)]
            found[hit] = True
            for r, n in enumerate(np.bincount(run[hit], minlength=seg.runs).tolist()):
                counts[seg.entry, seg.method, r] = counts.get((seg.entry, seg.method, r), 0) + n
    if not found.all():
        first = int(np.flatnonzero(~found)[0])
        raise ResultsError(f"{path}: line {first + 2}: " +
                           _unscheduled(df.iloc[first], segments, planned))
    for seg in dict.fromkeys((s.entry, s.method, s.runs, s.episodes)
                             for parts in segments.values() for s in parts):
        entry, method, runs, episodes = seg
        for r in range(runs):
            n = counts.get((entry, method, r), 0)
            if n != episodes:
                raise ResultsError(f"{path}: experiment {cfg.experiments[entry]['name']!r} "
                                   f"({_schedule_text(cfg.experiments[entry])}), method "
                                   f"{method!r}, run {r} has {n} episodes, config.json says "
                                   f"{episodes}")


class _Part(NamedTuple):
    """One part of a config entry's schedule, for one of its methods."""

    entry: int
    method: str
    lo: int
    hi: int
    """Its episodes are ``lo + 1`` to ``hi`` of a run."""
    runs: int
    episodes: int
    """The entry's episodes per run."""


def _segments(cfg: RunConfig) -> dict[tuple[str, str, str], list[_Part]]:
    """``(experiment, method, task label) ->`` the schedule parts that task is run in."""
    out: dict[tuple[str, str, str], list[_Part]] = {}
    for i, e in enumerate(cfg.experiments):
        sched, methods, runs = e.get("schedule"), e.get("methods"), e.get("runs")
        if not (isinstance(sched, list) and isinstance(methods, list) and isinstance(runs, int)):
            continue
        name, total, lo = str(e.get("name")), sum(int(n) for _, n in sched), 0
        for spec, n in sched:
            label = task_label(cfg, name, str(spec))
            for m in methods:
                out.setdefault((name, str(m), label), []).append(
                    _Part(i, str(m), lo, lo + int(n), runs, total))
            lo += int(n)
    return out


def task_label(cfg: RunConfig, experiment: str, spec: str) -> str:
    """The ``task`` column of schedule entry ``spec`` (a task's or a problem's name; an
    office task ``start->goal`` is labelled ``start-goal`` by its positions' names)."""
    if "->" not in spec:
        return spec
    start, goal = spec.split("->", 1)
    try:  # start-up time: the world is read only for such a task
        from gdq_pddl.experiments.knowledge import load_world_named

        return load_world_named(cfg.world_spec(experiment)).resolve(
            start=start, goal=goal).name
    except GdqError:  # a world no longer there: the names as written
        return f"{start}-{goal}"


def _schedule_text(entry: Mapping[str, Any]) -> str:
    return " then ".join(f"{t} x {n}" for t, n in entry.get("schedule", ()))


def _unscheduled(row: pd.Series, segments: Mapping[tuple[str, str, str], list[_Part]],
                 planned: Mapping[tuple[str, str], tuple[int, int]]) -> str:
    """Why ``row`` is no episode of ``segments`` (the first reason that holds)."""
    exp, method, task, run = str(row.experiment), str(row.method), str(row.task), int(row.run)
    if (exp, method) not in planned:
        ran = ", ".join(m for e, m in planned if e == exp) or "nothing"
        return f"method {method!r} of experiment {exp!r} was never run (config.json: " \
            f"{exp!r} ran {ran})"
    mine = {k[2]: v for k, v in segments.items() if k[:2] == (exp, method)}
    runs = max(p.runs for parts in mine.values() for p in parts)
    if run >= runs:
        return f"run {run} of experiment {exp!r}, config.json says {runs} runs " \
            f"(0 to {runs - 1})"
    parts = [p for p in mine.get(task, ()) if run < p.runs]
    if not parts:
        return f"task {task!r} of experiment {exp!r} was never scheduled (config.json: " \
            f"{exp!r} scheduled {', '.join(mine)})"
    spans = ", ".join(f"{p.lo + 1} to {p.hi}" for p in parts)
    return f"episode {int(row.episode)} of experiment {exp!r}, task {task!r}, run {run}: " \
        f"config.json schedules episodes {spans} of it"


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
