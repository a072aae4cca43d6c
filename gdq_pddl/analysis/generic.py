"""A short REPORT.md for a run on a PDDL domain (``gdq-pddl run --domain ...``).

The office's report (:mod:`gdq_pddl.analysis.report`) is about areas, the paper's tasks
and hypotheses; a generic domain has none of those. This one lists, per problem, the
size of the learner's problem, the planner's shortest plan length, the optimal value V*
(value iteration on the true model, from ``optimal.json``) and, per method, the mean
return per episode over all episodes and over the last 10% of them (mean over runs with
its standard error), and the success rate.

:func:`summarise` and :func:`optimal_entry` are shared with the office report's
*Methods compared* section (:mod:`gdq_pddl.analysis.sections.methods`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gdq_pddl.analysis.data import load_optimal
from gdq_pddl.analysis.episodes import Episodes, load_episodes
from gdq_pddl.analysis.stats import run_means


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


def method_summary(out: Path) -> dict[tuple[str, str], MethodSummary]:
    """Per (task, method) of ``out/episodes.csv``: the :class:`MethodSummary` (a PDDL
    run has one experiment; with several, the first that has the pair)."""
    ep = load_episodes(Path(out) / "episodes.csv")
    summary: dict[tuple[str, str], MethodSummary] = {}
    for exp in ep.experiments:
        for task in ep.tasks(exp):
            for method in ep.methods(exp):
                s = summary.get((task, method)) or task_summary(ep, exp, method, task)
                if s is not None:
                    summary[(task, method)] = s
    return summary


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


def generic_report(out: Path) -> str:
    """The Markdown text of the report of output folder ``out``."""
    optimal = load_optimal(out)
    summary = method_summary(out)
    lines = ["# Run on a PDDL domain", ""]
    for task in sorted({t for t, _ in summary}):
        info = optimal_entry(optimal, task)
        lines += [f"## {task}", ""]
        if info:
            lines += [f"- domain `{info.get('domain')}`, problem `{info.get('problem')}`, "
                      + _reality(info),
                      f"- learner: {info.get('states')} states (every reachable planner "
                      f"state), {info.get('actions')} actions (ground actions)",
                      f"- shortest plan: {info.get('shortest_plan')} actions",
                      f"- optimal value V* (expected return from the start, value iteration "
                      f"on the true model): {info.get('v_star', float('nan')):.2f}", ""]
        rows = sorted(((m, s) for (t, m), s in summary.items() if t == task),
                      key=lambda ms: -ms[1].mean)
        n = rows[0][1]
        lines += [f"Mean return per episode, mean over {n.runs} runs (standard error); "
                  f"{n.episodes} episodes per run; last 10%: the final "
                  f"{n.tail} episodes.", "",
                  "| method | mean return (SE) | last 10% (SE) | success rate |",
                  "|---|---|---|---|"]
        best = rows[0][0]
        for method, s in rows:
            name = f"**{method}**" if method == best else method
            lines.append(f"| {name} | {fmt2(s.mean)} ({fmt2(s.se)}) | "
                         f"{fmt2(s.last)} ({fmt2(s.last_se)}) | {s.success:.2f} |")
        lines.append("")
    return "\n".join(lines)


def write_generic_report(out: Path) -> Path:
    """Write ``out/REPORT.md`` for a PDDL run and return its path."""
    out = Path(out)
    path = out / "REPORT.md"
    path.write_text(generic_report(out), encoding="utf-8")
    return path
