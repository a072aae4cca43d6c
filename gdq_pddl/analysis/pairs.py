"""The data and statistics of a pairs folder (``gdq-pddl pairs``), from ``runs.csv``
(one mean return per pair, method and run) and ``optimal.json``: per pair and method
the mean over runs and its standard error; per pair and baseline the paired difference
of the reference (GDQ when it ran) minus the baseline, its Student's t 95% interval and
win / tie / loss; summaries over sets of pairs; the IQM over pairs. docs/decisions.md
("Every start/goal pair") defines each; :mod:`.pairs_report` writes the figure and text.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats as sps

from gdq_pddl.analysis.results import load_config, order_methods
from gdq_pddl.analysis.stats import iqm_ci
from gdq_pddl.analysis.writer import number
from gdq_pddl.errors import GdqError
from gdq_pddl.outputs import write_text
from gdq_pddl.world import builtin_world, load_world

LEVEL = 0.95
WIN, TIE, LOSS = "win", "tie", "loss"
WORST = 10
"""How many of the worst pairs the summary lists per baseline."""
TABLE_STEM = "pairs"


@dataclass(frozen=True)
class PairRuns:
    """A pairs folder's results: ``means[pair, method, run]`` (NaN: no such run), methods
    in the report's order (:func:`~gdq_pddl.analysis.results.order_methods`)."""

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


def load_pair_runs(out: Path) -> PairRuns:
    """Read ``runs.csv``, ``optimal.json`` and ``config.json`` of a pairs folder."""
    path = out / "runs.csv"
    if not path.exists():
        raise GdqError(f"{out} has no runs.csv: the pairs run has not finished "
                       "(continue it with --resume)")
    facts = json.loads((out / "optimal.json").read_text(encoding="utf-8"))
    runs = pd.read_csv(path, dtype={"pair": str, "method": str}, keep_default_na=False)
    config = load_config(out).raw
    exp = config["experiments"][0]
    pairs, methods = tuple(facts), tuple(order_methods(exp["methods"]))
    grid = pd.MultiIndex.from_product([pairs, methods, range(int(exp["runs"]))])
    means = runs.set_index(["pair", "method", "run"])["mean_return"].reindex(grid)
    world = exp["world"]
    world = builtin_world(world) if world in ("office", "office_robot") else load_world(world)
    return PairRuns(pairs, methods, means.to_numpy().reshape(len(pairs), len(methods), -1),
                    facts, config, world.positions)


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


def table(res: PairRuns, diffs: list[Differences]) -> pd.DataFrame:
    """One row per pair: facts, each method's mean and se, each difference (every digit)."""
    means, ses = over_runs(res.means)
    facts = pd.DataFrame([res.facts[p] for p in res.pairs])
    out = pd.DataFrame({"pair": res.pairs, "start": facts["start"], "goal": facts["goal"],
                        "tuning": facts["tuning"].fillna(""),
                        "shortest_plan": facts["shortest_plan"], "v_star": facts["v_star"]})
    for j, m in enumerate(res.methods):
        out[f"mean_{m}"], out[f"se_{m}"] = means[:, j], ses[:, j]
    for d in diffs:
        b = d.baseline
        out[f"diff_{b}"], out[f"diff_se_{b}"] = d.mean, d.se
        out[f"ci_low_{b}"], out[f"ci_high_{b}"], out[f"outcome_{b}"] = d.low, d.high, d.outcome
    return out


def table_markdown(res: PairRuns, diffs: list[Differences]) -> str:
    """The table as Markdown (rounded; the CSV has every digit)."""
    full = table(res, diffs)
    ref = res.reference
    md = pd.DataFrame({
        "pair": [f"**{p}**" if t else p for p, t in zip(full["pair"], full["tuning"],
                                                         strict=True)],
        "tuning": [f"task {t}" if t else "" for t in full["tuning"]],
        "shortest plan": [str(n) if n >= 0 else "none" for n in full["shortest_plan"]],
        "V*": [number(v) for v in full["v_star"]]})
    for m in res.methods:
        md[m] = [f"{number(a)} ({number(b)})" for a, b in zip(full[f"mean_{m}"],
                                                             full[f"se_{m}"], strict=True)]
    for d in diffs:
        md[f"{ref} - {d.baseline}"] = [f"{number(a, sign=True)} ({number(b)}) {o}" for a, b, o
                                       in zip(d.mean, d.se, d.outcome, strict=True)]
    return md.to_markdown(index=False, disable_numparse=True) + "\n"


def iqm_table(res: PairRuns, seed: int = 20240501) -> pd.DataFrame:
    """Per method over the pairs with V* > 0: the interquartile mean of every run's mean
    return / V* (one score per pair and run) and its stratified bootstrap 95% CI (runs
    resampled within each pair, :func:`~gdq_pddl.analysis.stats.iqm_ci`)."""
    v_star = np.array([float(res.facts[p].get("v_star") or math.nan) for p in res.pairs])
    keep = np.flatnonzero(v_star > 0)
    rows = {m: iqm_ci([res.means[i, j] / v_star[i] for i in keep], seed)
            for j, m in enumerate(res.methods)}
    return pd.DataFrame.from_dict(rows, orient="index", columns=["iqm", "low", "high"]).assign(
        pairs=len(keep))


def write_tables(res: PairRuns, diffs: list[Differences], out: Path) -> list[Path]:
    """``tables/pairs.csv`` and ``tables/pairs.md``."""
    target = out / "tables"
    target.mkdir(parents=True, exist_ok=True)
    csv_path, md_path = target / f"{TABLE_STEM}.csv", target / f"{TABLE_STEM}.md"
    frame = table(res, diffs)
    floats = [c for c in frame if frame[c].dtype == float]
    frame[floats] = frame[floats].map(lambda x: repr(float(x)))  # every digit
    write_text(csv_path, frame.to_csv(index=False, lineterminator="\n"))
    write_text(md_path, table_markdown(res, diffs))
    return [csv_path, md_path]
