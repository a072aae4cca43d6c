"""A short REPORT.md for a run on a PDDL domain (``gdq-pddl run --domain ...``).

The office's report (:mod:`gdq_pddl.analysis.report`) is about areas, the paper's tasks
and hypotheses; a generic domain has none of those. This one lists, per problem, the
size of the learner's problem, the planner's shortest plan length, the optimal value V*
(value iteration on the true model, from ``optimal.json``) and, per method, the mean
return per episode over all episodes and over the last 10% of them (mean over runs with
its standard error), and the success rate.
"""

from __future__ import annotations

import csv
import json
import math
from collections import defaultdict
from pathlib import Path


def method_summary(out: Path) -> dict[tuple[str, str], dict[str, float]]:
    """Per (task, method): mean return (all / last 10% of episodes) over runs, their
    standard errors, the success rate and the number of runs."""
    per_run: dict[tuple[str, str, str], list[tuple[float, int]]] = defaultdict(list)
    with open(out / "episodes.csv", encoding="utf-8", newline="") as fh:
        for row in csv.DictReader(fh):
            key = (row["task"], row["method"], row["run"])
            per_run[key].append((float(row["return"]), int(row["success"])))
    grouped: dict[tuple[str, str], list[list[tuple[float, int]]]] = defaultdict(list)
    for (task, method, _), rows in per_run.items():
        grouped[(task, method)].append(rows)
    summary = {}
    for key, runs in grouped.items():
        means = [sum(r for r, _ in rows) / len(rows) for rows in runs]
        tails = []
        for rows in runs:
            tail = rows[-max(1, len(rows) // 10):]
            tails.append(sum(r for r, _ in tail) / len(tail))
        success = sum(s for rows in runs for _, s in rows) / sum(len(rows) for rows in runs)
        summary[key] = {"mean": _mean(means), "se": _se(means), "last": _mean(tails),
                        "last_se": _se(tails), "success": success, "runs": len(runs),
                        "episodes": len(runs[0])}
    return summary


def _mean(xs: list[float]) -> float:
    return sum(xs) / len(xs)


def _se(xs: list[float]) -> float:
    if len(xs) < 2:
        return float("nan")
    m = _mean(xs)
    return math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1) / len(xs))


def _fmt(x: float) -> str:
    return "n/a" if math.isnan(x) else f"{x:.2f}"


def generic_report(out: Path) -> str:
    """The Markdown text of the report of output folder ``out``."""
    optimal = json.loads((out / "optimal.json").read_text()) \
        if (out / "optimal.json").exists() else {}
    summary = method_summary(out)
    lines = ["# Run on a PDDL domain", ""]
    for task in sorted({t for t, _ in summary}):
        info = next((v for k, v in optimal.items() if k.split("@", 1)[0] == task), {})
        lines += [f"## {task}", ""]
        if info:
            lines += [f"- domain `{info.get('domain')}`, problem `{info.get('problem')}`, "
                      f"dynamics `{info.get('dynamics')}`",
                      f"- learner: {info.get('states')} states (every reachable planner "
                      f"state), {info.get('actions')} actions (ground actions)",
                      f"- shortest plan: {info.get('shortest_plan')} actions",
                      f"- optimal value V* (expected return from the start, value iteration "
                      f"on the true model): {info.get('v_star', float('nan')):.2f}", ""]
        rows = sorted(((m, s) for (t, m), s in summary.items() if t == task),
                      key=lambda ms: -ms[1]["mean"])
        n = rows[0][1]
        lines += [f"Mean return per episode, mean over {n['runs']} runs (standard error); "
                  f"{n['episodes']} episodes per run; last 10%: the final "
                  f"{max(1, n['episodes'] // 10)} episodes.", "",
                  "| method | mean return (SE) | last 10% (SE) | success rate |",
                  "|---|---|---|---|"]
        best = rows[0][0]
        for method, s in rows:
            name = f"**{method}**" if method == best else method
            lines.append(f"| {name} | {_fmt(s['mean'])} ({_fmt(s['se'])}) | "
                         f"{_fmt(s['last'])} ({_fmt(s['last_se'])}) | {s['success']:.2f} |")
        lines.append("")
    return "\n".join(lines)


def write_generic_report(out: Path) -> Path:
    """Write ``out/REPORT.md`` for a PDDL run and return its path."""
    out = Path(out)
    path = out / "REPORT.md"
    path.write_text(generic_report(out), encoding="utf-8")
    return path
