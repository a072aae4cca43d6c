"""The table, summary and ``REPORT.md`` of a pairs folder (``gdq-pddl pairs``).

Everything is computed from ``runs.csv`` (one mean return per pair, method and run) and
``optimal.json`` (:mod:`gdq_pddl.experiments.pairs`):

- per pair and method, the **mean return** over the episodes of a run, then the mean
  over runs and its standard error (ddof 1);
- per pair and baseline, the **paired difference** of the reference (GDQ when it ran,
  else the first method) minus the baseline: run ``r`` of both starts from the same
  seeds, so ``d_r`` = reference's run-``r`` mean minus the baseline's; its mean over
  runs, standard error ``sd(d) / sqrt(n)`` and the 95% interval ``mean +- t(0.975,
  n - 1) se`` (Student's t). **win** when the interval lies above 0, **loss** when it
  lies below, **tie** otherwise (and always with a single run: no interval);
- the **summary** over a set of pairs: the mean of the per-pair differences, its
  standard error ``sqrt(sum se_p^2) / P`` (the pairs' runs are independent), the counts
  of wins, ties and losses, and the worst pairs (lowest mean difference). Over all pairs
  and over the pairs that are not tasks A-D, the ones every setting was tuned on.

342 intervals at 95% are 342 tests: two methods that were equal everywhere would still
show about 17 wins or losses by chance, which the report says beside the counts.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import stats as sps

from gdq_pddl.analysis.data import load_config, load_world_spec
from gdq_pddl.analysis.names import order_methods
from gdq_pddl.errors import GdqError
from gdq_pddl.outputs import write_text, writing

LEVEL = 0.95
WIN, TIE, LOSS = "win", "tie", "loss"
WORST = 10
"""How many of the worst pairs the summary lists per baseline."""
TABLE_STEM = "pairs"


@dataclass(frozen=True)
class PairRuns:
    """A pairs folder's results: ``means[pair, method, run]`` (NaN: no such run), methods
    in the report's order (:func:`~gdq_pddl.analysis.names.order_methods`)."""

    pairs: tuple[str, ...]
    methods: tuple[str, ...]
    means: np.ndarray
    facts: dict[str, dict]
    """``optimal.json``: start, goal, shortest_plan, v_star, tuning per pair."""
    config: dict
    positions: tuple[str, ...]
    """The world's positions, in its order (the heatmaps' rows and columns)."""

    @property
    def reference(self) -> str:
        """The method the others are compared with: GDQ if it ran, else the first."""
        return "GDQ" if "GDQ" in self.methods else self.methods[0]

    @property
    def baselines(self) -> tuple[str, ...]:
        return tuple(m for m in self.methods if m != self.reference)

    def tuning(self) -> np.ndarray:
        """bool[pairs]: the pair is one of the tuning tasks A-D."""
        return np.array([bool(self.facts[p].get("tuning")) for p in self.pairs])


def is_pairs_folder(out: Path) -> bool:
    """Whether ``out`` is an output folder of ``gdq-pddl pairs`` (by its config)."""
    from gdq_pddl.experiments.pairs import PAIRS_EXPERIMENT

    exps = load_config(out).experiments
    return bool(exps) and all(e.get("name") == PAIRS_EXPERIMENT for e in exps)


def load_pair_runs(out: Path) -> PairRuns:
    """Read ``runs.csv``, ``optimal.json`` and ``config.json`` of a pairs folder."""
    path = out / "runs.csv"
    if not path.exists():
        raise GdqError(f"{out} has no runs.csv: the pairs run has not finished "
                       "(continue it with --resume)")
    facts = json.loads((out / "optimal.json").read_text(encoding="utf-8"))
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    pairs = tuple(facts)
    config = load_config(out).raw
    methods = tuple(order_methods(config["experiments"][0]["methods"]))
    runs = max((int(r["run"]) for r in rows), default=-1) + 1
    means = np.full((len(pairs), len(methods), runs), np.nan)
    p_index = {p: i for i, p in enumerate(pairs)}
    m_index = {m: i for i, m in enumerate(methods)}
    for r in rows:
        means[p_index[r["pair"]], m_index[r["method"]], int(r["run"])] = float(r["mean_return"])
    world = load_world_spec(config["experiments"][0]["world"])
    return PairRuns(pairs, methods, means, facts, config, world.positions)


def over_runs(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error (ddof 1) over the last axis, the runs. Unlike
    :func:`gdq_pddl.analysis.stats.mean_se`, one run has no standard error (NaN, shown
    ``n/a``), not 0: a single run is no evidence of a difference."""
    n = x.shape[-1]
    se = x.std(axis=-1, ddof=1) / math.sqrt(n) if n > 1 else np.full(x.shape[:-1], np.nan)
    return x.mean(axis=-1), se


@dataclass(frozen=True)
class Differences:
    """The reference minus one baseline, per pair (arrays over pairs)."""

    baseline: str
    mean: np.ndarray
    se: np.ndarray
    low: np.ndarray
    high: np.ndarray
    outcome: np.ndarray
    """``win`` / ``tie`` / ``loss`` per pair (the module docstring's rule)."""


def differences(res: PairRuns, baseline: str) -> Differences:
    """Paired differences ``reference - baseline`` on every pair."""
    ref, base = res.methods.index(res.reference), res.methods.index(baseline)
    d = res.means[:, ref, :] - res.means[:, base, :]
    mean, se = over_runs(d)
    n = d.shape[-1]
    half = sps.t.ppf((1 + LEVEL) / 2, n - 1) * se if n > 1 else np.full_like(mean, np.nan)
    low, high = mean - half, mean + half
    outcome = np.where(low > 0, WIN, np.where(high < 0, LOSS, TIE))
    return Differences(baseline, mean, se, low, high, outcome)


@dataclass(frozen=True)
class Summary:
    """One baseline over a set of pairs."""

    baseline: str
    pairs: int
    mean: float
    """Mean over the pairs of the per-pair mean difference."""
    se: float
    wins: int
    ties: int
    losses: int
    worst: tuple[int, ...]
    """Indices of the :data:`WORST` pairs with the lowest mean difference, worst first."""


def summarise(diff: Differences, keep: np.ndarray) -> Summary:
    """:class:`Summary` of ``diff`` over the pairs where ``keep`` is True."""
    idx = np.flatnonzero(keep)
    mean = float(diff.mean[idx].mean()) if idx.size else math.nan
    se = float(np.sqrt(np.sum(diff.se[idx] ** 2)) / idx.size) if idx.size else math.nan
    counts = [int(np.sum(diff.outcome[idx] == o)) for o in (WIN, TIE, LOSS)]
    worst = idx[np.argsort(diff.mean[idx], kind="stable")[:WORST]]
    return Summary(diff.baseline, int(idx.size), mean, se, *counts, tuple(int(i) for i in worst))


def number(x: float, digits: int = 2, sign: bool = False) -> str:
    """``x`` rounded to ``digits`` decimals (``sign``: always signed; NaN: ``n/a``)."""
    if x is None or math.isnan(x):
        return "n/a"
    return f"{x:+.{digits}f}" if sign else f"{x:.{digits}f}"


def table_columns(res: PairRuns) -> list[str]:
    """The CSV table's header (see :func:`table_rows`)."""
    cols = ["pair", "start", "goal", "tuning", "shortest_plan", "v_star"]
    for m in res.methods:
        cols += [f"mean_{m}", f"se_{m}"]
    for b in res.baselines:
        cols += [f"diff_{b}", f"diff_se_{b}", f"ci_low_{b}", f"ci_high_{b}", f"outcome_{b}"]
    return cols


def table_rows(res: PairRuns, diffs: list[Differences]) -> list[list]:
    """One row per pair: facts, each method's mean (se) and each difference."""
    means, ses = over_runs(res.means)
    rows = []
    for i, p in enumerate(res.pairs):
        f = res.facts[p]
        row = [p, f["start"], f["goal"], f.get("tuning") or "", f["shortest_plan"],
               repr(f["v_star"])]
        for j in range(len(res.methods)):
            row += [repr(float(means[i, j])), repr(float(ses[i, j]))]
        for d in diffs:
            row += [repr(float(d.mean[i])), repr(float(d.se[i])), repr(float(d.low[i])),
                    repr(float(d.high[i])), str(d.outcome[i])]
        rows.append(row)
    return rows


def table_markdown(res: PairRuns, diffs: list[Differences]) -> str:
    """The table as Markdown (rounded; the CSV has every digit)."""
    ref = res.reference
    head = ["pair", "tuning", "shortest plan", "V*", *res.methods,
            *(f"{ref} - {d.baseline}" for d in diffs)]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    means, ses = over_runs(res.means)
    for i, p in enumerate(res.pairs):
        f = res.facts[p]
        tuning = f.get("tuning")
        cells = [f"**{p}**" if tuning else p, f"task {tuning}" if tuning else "",
                 str(f["shortest_plan"]) if f["shortest_plan"] >= 0 else "none",
                 number(f["v_star"])]
        cells += [f"{number(m)} ({number(e)})" for m, e in zip(means[i], ses[i], strict=True)]
        cells += [f"{number(d.mean[i], sign=True)} ({number(d.se[i])}) {d.outcome[i]}"
                  for d in diffs]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_tables(res: PairRuns, diffs: list[Differences], out: Path) -> list[Path]:
    """``tables/pairs.csv`` and ``tables/pairs.md``."""
    target = out / "tables"
    target.mkdir(parents=True, exist_ok=True)
    csv_path, md_path = target / f"{TABLE_STEM}.csv", target / f"{TABLE_STEM}.md"
    with writing(csv_path), open(csv_path, "w", encoding="utf-8", newline="") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(table_columns(res))
        writer.writerows(table_rows(res, diffs))
    write_text(md_path, table_markdown(res, diffs))
    return [csv_path, md_path]


def make_pairs_report(out: str | Path) -> list[Path]:
    """The table, figure and ``REPORT.md`` of a pairs folder; returns the paths."""
    from gdq_pddl.analysis.pairs_figures import write_figure
    from gdq_pddl.analysis.pairs_markdown import write_report

    out = Path(out)
    res = load_pair_runs(out)
    diffs = [differences(res, b) for b in res.baselines]
    paths = write_tables(res, diffs, out)
    paths += write_figure(res, diffs, out)
    paths.append(write_report(res, diffs, out))
    return paths
