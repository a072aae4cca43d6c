"""The report of a run on a PDDL domain (``gdq-pddl run --domain ...``), and the
per-method summary it shares with the office report.

The office's report (:mod:`gdq_pddl.analysis.report`) is about areas, the paper's tasks
and hypotheses; a generic domain has none of those. This one gives, per problem, the
size of the learner's problem, the planner's shortest plan length, the optimal value V*
(value iteration on the true model, from ``optimal.json``), the learning curves, and the
office report's *Methods compared* table: per method the mean return per episode over
all episodes and over the last 10% of them (mean over runs with its standard error), the
success rate and the episode the moving average turns positive, then each GDQ variant
tested against each baseline.

:func:`summarise` and :func:`optimal_entry` are shared with the office report's
*Methods compared* section (:mod:`gdq_pddl.analysis.sections.methods`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from gdq_pddl.analysis.data import load_config
from gdq_pddl.analysis.episodes import Episodes
from gdq_pddl.analysis.stats import run_means
from gdq_pddl.outputs import write_text

if TYPE_CHECKING:
    from gdq_pddl.analysis.sections.writer import ReportOptions


@dataclass(frozen=True)
class MethodSummary:
    """One method on one task: per-run mean returns summarised over runs."""

    runs: int
    episodes: int
    """Episodes per run (the longest run's)."""
    tail: int
    """Episodes in the last 10%: ``max(1, episodes // 10)``."""
    mean: float
    """Mean over runs of the run's mean return per episode (all episodes)."""
    se: float
    """Its standard error over runs (NaN with a single run)."""
    last: float
    """The same over each run's last :attr:`tail` episodes."""
    last_se: float
    success: float
    """Share of all episodes of all runs that reached the goal (NaN: no column)."""


def summarise(returns: np.ndarray, success: np.ndarray | None = None) -> MethodSummary:
    """The :class:`MethodSummary` of ``returns[runs, episodes]`` (and the matching 0/1
    ``success`` matrix, if any)."""
    runs, episodes = returns.shape
    tail = max(1, episodes // 10)
    means, lasts = run_means(returns), run_means(returns, episodes - tail)
    rate = float(np.nanmean(success)) if success is not None and success.size else math.nan
    return MethodSummary(runs, episodes, tail, _mean(means), _se(means), _mean(lasts),
                         _se(lasts), rate)


def task_summary(ep: Episodes, experiment: str, method: str, task: str) -> MethodSummary | None:
    """:func:`summarise` of one (experiment, method, task) slice (None: no episodes)."""
    returns = ep.matrix("return", experiment, method, task)
    if returns.size == 0:
        return None
    success = ep.matrix("success", experiment, method, task) if "success" in ep.values \
        else None
    return summarise(returns, success)


def optimal_entry(optimal: Mapping[str, Mapping[str, Any]], task: str,
                  world: str | None = None) -> Mapping[str, Any]:
    """The ``optimal.json`` facts of task label ``task`` (empty when absent).

    The runner keys a task ``task`` in the office and ``task@world`` elsewhere (a PDDL
    task ``task@problem file``), and each entry names its ``world``; with ``world``
    given, only an entry of that world matches.
    """
    return next((v for k, v in optimal.items() if k.split("@", 1)[0] == task
                 and (world is None or v.get("world", world) == world)), {})


def _mean(xs: np.ndarray) -> float:
    xs = xs[~np.isnan(xs)]
    return float(np.mean(xs)) if xs.size else math.nan


def _se(xs: np.ndarray) -> float:
    xs = xs[~np.isnan(xs)]
    return float(np.std(xs, ddof=1) / math.sqrt(xs.size)) if xs.size >= 2 else math.nan


def fmt2(x: float) -> str:
    """Two decimals, ``n/a`` for NaN."""
    return "n/a" if math.isnan(x) else f"{x:.2f}"


def _reality(info: dict) -> str:
    """Where reality comes from: the dynamics file, or a PPDDL domain (and its overlay)."""
    if not info.get("determinisation"):
        return f"dynamics `{info.get('dynamics')}`"
    overlay = f"overlay `{info['dynamics']}`" if info.get("dynamics") else "no overlay"
    return (f"PPDDL: reality is the domain's probabilistic model ({overlay}; r_max "
            f"{info.get('r_max'):g}, step limit {info.get('step_limit')}), the planner knows "
            f"its {info['determinisation']} determinisation")


def generic_report(out: Path, opts: ReportOptions | None = None) -> str:
    """The Markdown text of the report of output folder ``out``: per problem its facts,
    the learning curves (when ``figures/`` has them, :func:`make_generic_report`) and the
    office report's per-method table with milestones and comparisons
    (:func:`gdq_pddl.analysis.sections.methods.write_task`), with ``opts``' windows
    (default :class:`ReportOptions`)."""
    from gdq_pddl.analysis.sections.methods import curves_stem, definitions, write_task
    from gdq_pddl.analysis.sections.writer import ReportOptions, Writer
    from gdq_pddl.analysis.stats import ALPHA
    from gdq_pddl.analysis.study import Study

    opts = opts or ReportOptions()
    study = Study.open(out)
    w = Writer(study, opts, Path(out))
    w.add("# Run on a PDDL domain", "",
          f"{definitions(opts.window)} Welch's t-test (two-sided) and a percentile "
          f"bootstrap 95% CI of the difference in means over runs (10,000 resamples, seed "
          f"{opts.seed}); a difference counts when the CI excludes 0 and p < {ALPHA}.", "")
    for exp in study.episodes.experiments:
        w.add(f"## {exp}", "")
        w.figure(curves_stem(exp), f"learning curves, {exp}")
        for task in study.episodes.tasks(exp):
            info = optimal_entry(study.optimal, task)
            if info:
                w.add(f"- domain `{info.get('domain')}`, problem `{info.get('problem')}`, "
                      + _reality(info),
                      f"- learner: {info.get('states')} states (every reachable planner "
                      f"state), {info.get('actions')} actions (ground actions)",
                      f"- shortest plan: {info.get('shortest_plan')} actions",
                      f"- optimal value V* (expected return from the start, value "
                      f"iteration on the true model): {info.get('v_star', math.nan):.2f}",
                      "")
            write_task(w, exp, task)
    return "\n".join(w.lines)


def write_generic_report(out: Path) -> Path:
    """Write ``out/REPORT.md`` for a PDDL run and return its path (embedding the figures
    already in ``out/figures``)."""
    out = Path(out)
    path = out / "REPORT.md"
    write_text(path, generic_report(out))
    return path


def make_generic_report(out: Path) -> list[Path]:
    """The learning-curve figures (``figures/learning_curves_<experiment>.png`` and
    ``.pdf``) and ``REPORT.md`` of a PDDL run's output folder; returns every path written."""
    from gdq_pddl.analysis.figures import learning_curves
    from gdq_pddl.analysis.study import Study

    out = Path(out)
    study = Study.open(out)
    paths: list[Path] = []
    for exp in study.episodes.experiments:
        paths += learning_curves(study, out / "figures", experiment=exp)
    paths.append(write_generic_report(out))
    return paths


def is_pddl_folder(out: Path) -> bool:
    """Whether every experiment of an output folder's ``config.json`` ran on a PDDL
    problem (``gdq-pddl run --domain``)."""
    from gdq_pddl.analysis.study import PDDL_WORLD

    experiments = load_config(out).experiments
    return bool(experiments) and all(e.get("world") == PDDL_WORLD for e in experiments)
