"""``episodes.csv`` as numpy columns.

The file has one row per episode, columns ``experiment, method, task, run, episode,
return, steps, success, area_1 .. area_k``. :func:`load_episodes` reads it once (about
600k rows for a full reproduction) into an :class:`Episodes` table: the three text
columns are stored as integer codes plus their labels, everything else as float64, and
:meth:`Episodes.matrix` reshapes one (experiment, method[, task]) slice into
``[runs, episodes]``.
"""

from __future__ import annotations

import csv
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from gdq_pddl.analysis.names import order_methods
from gdq_pddl.errors import ResultsError

CATEGORICAL = ("experiment", "method", "task")
"""Text columns of ``episodes.csv`` (stored as codes into sorted labels)."""


@dataclass(frozen=True)
class Episodes:
    """The rows of ``episodes.csv`` as columns.

    ``codes[c]`` holds int codes into ``labels[c]`` for the text columns ``experiment``,
    ``method`` and ``task``; ``values[c]`` holds every other column as float64.
    """

    codes: Mapping[str, np.ndarray]
    labels: Mapping[str, tuple[str, ...]]
    values: Mapping[str, np.ndarray]
    _cache: dict = field(default_factory=dict, repr=False, compare=False)
    """Memoised slices and label lists (the report asks for the same ones many times)."""

    def __len__(self) -> int:
        return len(next(iter(self.values.values()))) if self.values else 0

    @cached_property
    def area_columns(self) -> tuple[str, ...]:
        """``area_1 .. area_k`` in area order."""
        cols = [c for c in self.values if c.startswith("area_") and c[5:].isdigit()]
        return tuple(sorted(cols, key=lambda c: int(c[5:])))

    @property
    def areas(self) -> tuple[int, ...]:
        """Area numbers that have a column."""
        return tuple(int(c[5:]) for c in self.area_columns)

    def column(self, name: str) -> np.ndarray:
        """One column: labels (str array) for text columns, float64 otherwise."""
        if name in self.codes:
            return np.asarray(self.labels[name], dtype=object)[self.codes[name]]
        try:
            return self.values[name]
        except KeyError:
            known = ", ".join([*self.codes, *self.values])
            raise KeyError(f"no column {name!r} in episodes.csv (known: {known})") from None

    def _code(self, column: str, label: str) -> int:
        try:
            return self.labels[column].index(label)
        except ValueError:
            return -1

    def mask(self, experiment: str | None = None, method: str | None = None,
             task: str | None = None) -> np.ndarray:
        """Boolean row mask of the rows matching every given label."""
        out = np.ones(len(self), dtype=bool)
        for column, label in (("experiment", experiment), ("method", method), ("task", task)):
            if label is not None:
                out &= self.codes[column] == self._code(column, label)
        return out

    def unique(self, column: str, experiment: str | None = None,
               method: str | None = None) -> list[str]:
        """Labels of a text column present in the selected rows (methods in figure order)."""
        key = ("unique", column, experiment, method)
        if key not in self._cache:
            self._cache[key] = self._unique(column, experiment, method)
        return list(self._cache[key])

    def _unique(self, column: str, experiment: str | None, method: str | None) -> list[str]:
        rows = self.mask(experiment, method)
        labels = [self.labels[column][c] for c in np.unique(self.codes[column][rows])]
        if column == "method":
            return order_methods(labels)
        if column == "task":  # in order of first appearance (a switch's old task first)
            first = {lab: self._first_episode(rows & self.mask(task=lab)) for lab in labels}
            return sorted(labels, key=lambda lab: (first[lab], lab))
        return sorted(labels)

    def _first_episode(self, rows: np.ndarray) -> float:
        ep = self.values["episode"][rows]
        return float(ep.min()) if ep.size else np.inf

    @property
    def experiments(self) -> list[str]:
        return self.unique("experiment")

    def methods(self, experiment: str | None = None) -> list[str]:
        return self.unique("method", experiment)

    def tasks(self, experiment: str | None = None, method: str | None = None) -> list[str]:
        return self.unique("task", experiment, method)

    def has(self, experiment: str) -> bool:
        return experiment in self.experiments

    def _slice(self, experiment: str, method: str, task: str | None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Rows of one slice, their run and episode column indices, runs and episodes."""
        key = ("slice", experiment, method, task)
        if key not in self._cache:
            rows = np.flatnonzero(self.mask(experiment, method, task))
            runs, run_idx = np.unique(self.values["run"][rows], return_inverse=True)
            eps, ep_idx = np.unique(self.values["episode"][rows], return_inverse=True)
            self._cache[key] = (rows, run_idx, ep_idx, runs, eps)
        return self._cache[key]

    def matrix(self, column: str, experiment: str, method: str,
               task: str | None = None) -> np.ndarray:
        """``float64[runs, episodes]`` of ``column`` for one slice, NaN where a run lacks one.

        Runs are in ascending run order and episodes in ascending episode order; with a
        ``task``, only that task's episodes (for a switch: those after the switch).
        """
        rows, run_idx, ep_idx, runs, eps = self._slice(experiment, method, task)
        if rows.size == 0:
            return np.empty((0, 0))
        out = np.full((len(runs), len(eps)), np.nan)
        out[run_idx, ep_idx] = self.column(column)[rows]
        return out

    def episode_numbers(self, experiment: str, method: str, task: str | None = None) -> np.ndarray:
        """The episode numbers (columns) of :meth:`matrix` for the same slice."""
        return self._slice(experiment, method, task)[4].copy()

    def area_visits(self, experiment: str, method: str, task: str | None = None) -> np.ndarray:
        """``float64[runs, episodes, n_areas]`` of area visits (areas as in :attr:`areas`)."""
        mats = [self.matrix(c, experiment, method, task) for c in self.area_columns]
        if not mats or mats[0].size == 0:
            return np.empty((0, 0, len(mats)))
        return np.stack(mats, axis=-1)


def load_episodes(path: str | Path) -> Episodes:
    """Read ``episodes.csv`` (or the folder holding it) into an :class:`Episodes`.

    One pass of numpy's C reader into a structured array (about 1 s for a million
    rows); files it cannot read (empty numeric cells, long or non-ASCII labels) go
    through the :mod:`csv` module instead, with the same result.
    """
    path = Path(path)
    if path.is_dir():
        path = path / "episodes.csv"
    try:
        with path.open(newline="", encoding="utf-8") as f:
            header = [h.strip() for h in next(csv.reader(f), [])]
        if not header:
            raise damaged_file(path, "empty file, expected a header row")
        missing = [c for c in (*CATEGORICAL, "run", "episode", "return") if c not in header]
        if missing:
            raise damaged_file(path, f"missing columns {missing} (header: {header})")
        fast = _load_fast(path, header)
        episodes = fast if fast is not None else _load_csv(path, header)
    except OSError as exc:
        raise ResultsError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise damaged_file(path, str(exc)) from None
    _check_values(path, episodes)
    return episodes


_WHOLE = {"run": 0, "episode": 1, "steps": 0}
"""Columns holding whole numbers, and their least value."""


def _check_values(path: Path, episodes: Episodes) -> None:
    """Refuse what the runner never writes: no rows, a value that is not finite (an
    empty area cell is NaN and allowed), a run, episode or step count that is not a whole
    number at least its least value, a success other than 0 or 1, a negative visit count.
    A message names the column, the line and the value."""
    n = len(episodes)
    if n == 0:
        raise damaged_file(path, "no episodes, only the header")
    for name, col in episodes.values.items():
        area = name.startswith("area_")
        bad = ~np.isfinite(col) & ~(area & np.isnan(col))
        if name in _WHOLE:
            bad |= (col != np.floor(col)) | (col < _WHOLE[name])
        elif name == "success":
            bad |= (col != 0) & (col != 1)
        elif area:
            bad |= col < 0
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise damaged_file(path, f"line {i + 2}, column {name}: {float(col[i])!r} is not a "
                               f"value a run writes")


def damaged_file(path: Path, why: str) -> ResultsError:
    """The error of an unreadable results file (``episodes.csv``, ``policies.csv``,
    ``optimal.json``: the runner makes them from ``units/``)."""
    return ResultsError(f"{path} is damaged ({why}); the run's units/ rebuild it: give the "
                        "command that made it again, with --resume")


_LABEL_WIDTH = 32
"""Bytes per text cell in the fast reader; a label this long may be cut, so re-read."""


def _load_fast(path: Path, header: list[str]) -> Episodes | None:
    """The numpy reader, or None when the file needs the csv module."""
    if len(set(header)) != len(header):
        return None
    dtype = [(h, f"S{_LABEL_WIDTH}") if h in CATEGORICAL else (h, "f8") for h in header]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
            table = np.loadtxt(path, delimiter=",", skiprows=1, dtype=dtype, quotechar='"',
                               encoding="utf-8", ndmin=1)
    except (ValueError, UnicodeError):
        return None
    codes: dict[str, np.ndarray] = {}
    labels: dict[str, tuple[str, ...]] = {}
    values: dict[str, np.ndarray] = {}
    for name in header:
        if name in CATEGORICAL:
            col = table[name]
            if col.size and int(np.char.str_len(col).max()) >= _LABEL_WIDTH:
                return None
            labels[name], codes[name] = _encode_sorted_runs(col)
        else:
            values[name] = np.ascontiguousarray(table[name])
    return Episodes(codes=codes, labels=labels, values=values)


def _encode_sorted_runs(col: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:
    """Sorted labels and int32 codes of a bytes column, encoding only where the value
    changes (the runner writes rows grouped, so there are few changes)."""
    if col.size == 0:
        return (), np.empty(0, dtype=np.int32)
    starts = np.flatnonzero(np.concatenate([[True], col[1:] != col[:-1]]))
    heads, inverse = np.unique(col[starts], return_inverse=True)
    lengths = np.diff(np.append(starts, col.size))
    labels = tuple(h.decode("utf-8") for h in heads)
    return labels, np.repeat(inverse.astype(np.int32), lengths)


def _load_csv(path: Path, header: list[str]) -> Episodes:
    """The :mod:`csv` module reader (slow, but reads anything the fast one refuses)."""
    with path.open(newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        next(reader)
        rows = []
        for r in reader:
            if r and len(r) != len(header):
                raise damaged_file(path, f"line {reader.line_num} has {len(r)} fields, the "
                               f"header {len(header)}")
            if r:
                rows.append(r)
    columns = list(zip(*rows, strict=True)) if rows else [() for _ in header]
    codes: dict[str, np.ndarray] = {}
    labels: dict[str, tuple[str, ...]] = {}
    values: dict[str, np.ndarray] = {}
    for name, col in zip(header, columns, strict=True):
        if name in CATEGORICAL:
            labels[name], codes[name] = _encode(col)
        else:
            try:
                values[name] = _floats(col)
            except ValueError:
                bad = next(v for v in col if not _is_number(v))
                raise damaged_file(path, f"column {name}: {bad!r} is not a number") from None
    return Episodes(codes=codes, labels=labels, values=values)


def _is_number(text: str) -> bool:
    try:
        float(text or "nan")
    except ValueError:
        return False
    return True


def _encode(col: Sequence[str]) -> tuple[tuple[str, ...], np.ndarray]:
    """Sorted labels and int32 codes of a text column (a dict pass: fast for few labels)."""
    seen: dict[str, int] = {}
    raw = np.fromiter((seen.setdefault(v, len(seen)) for v in col), dtype=np.int32,
                      count=len(col))
    ordered = sorted(seen)
    remap = np.empty(len(seen), dtype=np.int32)
    for new, label in enumerate(ordered):
        remap[seen[label]] = new
    return tuple(ordered), remap[raw] if len(col) else raw


def _floats(col: Sequence[str]) -> np.ndarray:
    """A numeric column as float64 (empty cells become NaN)."""
    try:
        return np.array(col, dtype=np.float64)
    except ValueError:
        return np.array([v if v.strip() else "nan" for v in col], dtype=np.float64)
