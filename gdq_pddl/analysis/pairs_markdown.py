"""``REPORT.md`` of a pairs folder: setup, summary, figure, losses, worst pairs, definitions.

Every number is computed by :mod:`gdq_pddl.analysis.pairs` from the folder's data.
"""

from __future__ import annotations

import shlex
from pathlib import Path

import numpy as np

from gdq_pddl.analysis.pairs import (
    LEVEL,
    LOSS,
    TABLE_STEM,
    WORST,
    Differences,
    PairRuns,
    Summary,
    number,
    summarise,
)
from gdq_pddl.analysis.pairs_figures import FIGURE_STEM
from gdq_pddl.outputs import write_text

LISTED_PAIRS = 12
"""Up to this many pairs, the command line lists them (``--pairs``)."""


def command(res: PairRuns) -> str:
    """The command line that makes this folder (its pairs listed when they are few)."""
    exp = res.config["experiments"][0]
    argv = ["gdq-pddl", "pairs", "--method", *res.methods, "--episodes",
            str(exp["schedule"][0][1]), "--runs", str(exp["runs"]), "--seed", str(exp["seed"])]
    if exp["world"] != "office":
        argv += ["--world", exp["world"]]
    if exp["planner"] != "graph":
        argv += ["--planner", exp["planner"]]
    n = len(res.positions)
    if len(res.pairs) < n * (n - 1) and len(res.pairs) <= LISTED_PAIRS:
        argv += ["--pairs", " ".join(res.pairs)]
    return shlex.join(argv)


def _setup(res: PairRuns) -> list[str]:
    exp = res.config["experiments"][0]
    n = len(res.positions)
    hyper = ", ".join(f"{k} = {v}" for k, v in exp["hyper"].items())
    subset = "" if len(res.pairs) == n * (n - 1) else f" (of the {n * (n - 1)})"
    return [
        f"**Setup.** {len(res.pairs)} ordered (start, goal) pairs{subset} of the world "
        f"`{exp['world']}`; methods {', '.join(res.methods)}; each learns every pair from "
        f"scratch {exp['runs']} times for {exp['schedule'][0][1]} episodes, with the paper's "
        f"hyperparameters ({hyper}), planner `{exp['planner']}`, seed {exp['seed']}. Run r of "
        "every method on a pair starts from the same seeds, so differences are paired.", "",
        f"    {command(res)}", ""]


def _tuning(res: PairRuns) -> list[str]:
    tuned = [p for p in res.pairs if res.facts[p].get("tuning")]
    names = ", ".join(f"{p} (task {res.facts[p]['tuning']})" for p in tuned)
    if not tuned:
        return ["**Tuning.** Every setting of the learners was chosen on tasks A-D only; "
                "none of their pairs is among these, so every pair here is untuned.", ""]
    return [f"**Tuning.** Every setting of the learners was chosen on tasks A-D only: {names}. "
            "They are bold in the table and boxed in the figure, and the summary is given "
            "over all pairs and over the others.", ""]


def _summary_table(res: PairRuns, summaries: list[tuple[str, Summary]]) -> list[str]:
    ref = res.reference
    lines = [f"| {ref} minus | pairs | mean difference (s.e.) | wins | ties | losses |",
             "|---|---|---|---|---|---|"]
    for label, s in summaries:
        lines.append(f"| {s.baseline}{label} | {s.pairs} | {number(s.mean, sign=True)} "
                     f"({number(s.se)}) | {s.wins} | {s.ties} | {s.losses} |")
    chance = (1 - LEVEL) * len(res.pairs)
    return [*lines, "",
            f"A win (loss) is a pair whose paired {LEVEL:.0%} interval of {ref} minus the "
            f"baseline lies above (below) 0. With {len(res.pairs)} pairs, two methods that "
            f"were equal everywhere would still show about {chance:.1f} wins or losses by "
            "chance.", ""]


def _pair_line(res: PairRuns, d: Differences, i: int) -> str:
    p = res.pairs[i]
    tuning = res.facts[p].get("tuning")
    mark = f" (task {tuning})" if tuning else ""
    return (f"{p}{mark}: {number(d.mean[i], sign=True)} ({LEVEL:.0%} interval "
            f"[{number(d.low[i], sign=True)}, {number(d.high[i], sign=True)}]), {d.outcome[i]}")


def _losses(res: PairRuns, diffs: list[Differences]) -> list[str]:
    ref = res.reference
    lines = [f"## Where {ref} loses", ""]
    lost = [i for i in range(len(res.pairs)) if any(d.outcome[i] == LOSS for d in diffs)]
    if not lost:
        return [*lines, "Nowhere: no pair's interval lies below 0 against any baseline.", ""]
    worst = min((d.mean[i], d.baseline, res.pairs[i]) for d in diffs for i in lost
                 if d.outcome[i] == LOSS)
    lines += [f"{len(lost)} pairs, where {ref} minus the baseline is significantly negative "
              "against at least one baseline (mean difference, its interval); the largest "
              f"loss is {number(worst[0], sign=True)} per episode ({worst[2]} against "
              f"{worst[1]}):", ""]
    for i in lost:
        parts = [f"{d.baseline} {number(d.mean[i], sign=True)} [{number(d.low[i], sign=True)}, "
                 f"{number(d.high[i], sign=True)}]" for d in diffs if d.outcome[i] == LOSS]
        tuning = res.facts[res.pairs[i]].get("tuning")
        mark = f" (task {tuning})" if tuning else ""
        lines.append(f"- {res.pairs[i]}{mark}: against " + "; ".join(parts))
    return [*lines, ""]


def _worst(res: PairRuns, diffs: list[Differences], all_pairs: list[Summary]) -> list[str]:
    lines = ["## The worst pairs against each baseline", "",
             f"The {WORST} pairs with the lowest mean difference, worst first.", ""]
    for d, s in zip(diffs, all_pairs, strict=True):
        lines += [f"**{res.reference} - {d.baseline}:**", ""]
        lines += [f"{k}. {_pair_line(res, d, i)}" for k, i in enumerate(s.worst, 1)]
        lines.append("")
    return lines


def _definitions(res: PairRuns) -> list[str]:
    ref = res.reference
    return [
        "## The table", "",
        f"[`tables/{TABLE_STEM}.md`](tables/{TABLE_STEM}.md) (rounded) and "
        f"[`tables/{TABLE_STEM}.csv`](tables/{TABLE_STEM}.csv) (every digit), one row per "
        "pair:", "",
        "- `shortest plan`: actions in a shortest plan of the knowledge from start to goal "
        "(`none`: no plan); `V*`: the optimal expected return of an episode (value "
        "iteration on the true model, doors closed at the start);",
        "- per method, the mean return per episode over a run's episodes, then the mean "
        "over runs (standard error);",
        f"- per baseline, {ref} minus it: the mean over runs of the paired difference of "
        f"per-run means (standard error), and the outcome: `win` when the {LEVEL:.0%} "
        "interval mean +- t(0.975, runs - 1) x s.e. lies above 0, `loss` when below, "
        "`tie` otherwise (always with one run).", "",
        "The summary's mean difference is the mean over pairs of the per-pair differences; "
        "its standard error sqrt(sum of squared per-pair s.e.) / pairs (runs on different "
        "pairs are independent). The raw data: `runs.csv` (one mean return per pair, "
        "method and run) and `units/` (every episode's return and success).", ""]


def write_report(res: PairRuns, diffs: list[Differences], out: Path) -> Path:
    """Write ``out/REPORT.md``; returns its path."""
    keep_all = np.ones(len(res.pairs), dtype=bool)
    untuned = ~res.tuning()
    all_pairs = [summarise(d, keep_all) for d in diffs]
    summaries = [("", s) for s in all_pairs]
    if untuned.sum() < len(res.pairs):
        summaries += [(", excluding A-D", summarise(d, untuned)) for d in diffs]
    lines = ["# Every ordered start/goal pair", "", *_setup(res), *_tuning(res)]
    if diffs:
        lines += ["## Summary", "", *_summary_table(res, summaries),
                  f"![{res.reference} minus each baseline on every pair]"
                  f"(figures/{FIGURE_STEM}.png)", "",
                  f"Left: {res.reference} minus the baseline, mean return per episode, start "
                  "by goal (blue: "
                  f"{res.reference} better; `+` win, `\u2212` loss; boxed: tasks A-D). Right: "
                  f"every pair's difference, sorted, with its {LEVEL:.0%} interval.", "",
                  *_losses(res, diffs), *_worst(res, diffs, all_pairs)]
    else:
        lines += ["Only one method ran: there is nothing to compare.", ""]
    lines += _definitions(res)
    path = out / "REPORT.md"
    write_text(path, "\n".join(lines))
    return path
