"""The figure and ``REPORT.md`` of a pairs folder: setup, summary (with the IQM over
pairs), figure, losses, worst pairs, definitions.

Every number is computed by :mod:`gdq_pddl.analysis.pairs` from the folder's data. The
figure has one row per baseline: a start-by-goal heatmap of the mean paired difference
(diverging colours centred at 0, the diagonal blank, ``+`` on wins and ``-`` on losses,
the tuning tasks boxed), and every pair's difference sorted, with its 95% interval.
"""

from __future__ import annotations

import shlex
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.colors import TwoSlopeNorm
from matplotlib.patches import Rectangle
from matplotlib.ticker import MaxNLocator

from gdq_pddl.analysis.figures import save_all
from gdq_pddl.analysis.pairs import (
    LEVEL,
    LOSS,
    TABLE_STEM,
    TIE,
    WIN,
    WORST,
    Differences,
    PairRuns,
    Summary,
    differences,
    iqm_table,
    load_pair_runs,
    summarise,
    write_tables,
)
from gdq_pddl.analysis.writer import markdown_rows, number
from gdq_pddl.outputs import write_text

FIGURE_STEM = "pairs"
OUTCOME_COLOURS = {WIN: "#2166ac", "tie": "#999999", LOSS: "#b2182b"}
TIE_STRENGTH = 0.3
"""A tie's colour in the heatmap, as a share of its full strength (the rest white)."""
LABELLED = 30
"""Up to this many pairs, the sorted plot names each one."""


def heatmap(ax: Axes, res: PairRuns, diff: Differences) -> None:
    """Start (rows) by goal (columns), colour = mean difference; grey: the diagonal and
    pairs not run."""
    names = res.positions
    at = {n: i for i, n in enumerate(names)}
    grid = np.full((len(names), len(names)), np.nan)
    for i, p in enumerate(res.pairs):
        grid[at[res.facts[p]["start"]], at[res.facts[p]["goal"]]] = diff.mean[i]
    # white is no difference; each side of 0 spans its own extreme, so small losses
    # against large wins still show in full red
    low, high = (float(np.nanmin(grid)), float(np.nanmax(grid))) if np.isfinite(
        grid).any() else (-1.0, 1.0)
    norm = TwoSlopeNorm(0.0, min(low, -1e-9), max(high, 1e-9))
    cmap = plt.get_cmap("RdBu").with_extremes(bad="#b0b0b0")
    rgba = cmap(norm(np.ma.masked_invalid(grid)))
    for i, p in enumerate(res.pairs):
        r, c = at[res.facts[p]["start"]], at[res.facts[p]["goal"]]
        if diff.outcome[i] == TIE:  # faded: a tie's small mean must not look like a loss
            rgba[r, c, :3] = 1 - TIE_STRENGTH * (1 - rgba[r, c, :3])
    ax.imshow(rgba)
    for i, p in enumerate(res.pairs):
        r, c = at[res.facts[p]["start"]], at[res.facts[p]["goal"]]
        mark = {WIN: "+", LOSS: "\u2212"}.get(str(diff.outcome[i]), "")
        if mark:
            dark = abs(norm(diff.mean[i]) - 0.5) > 0.3
            ax.text(c, r, mark, ha="center", va="center", fontsize=7,
                    color="white" if dark else "black")
        if res.facts[p].get("tuning"):
            ax.add_patch(Rectangle((c - 0.5, r - 0.5), 1, 1, fill=False, lw=1.5,
                                   edgecolor="black"))
    ax.set_xticks(range(len(names)), names, rotation=90, fontsize=6)
    ax.set_yticks(range(len(names)), names, fontsize=6)
    ax.set(xlabel="goal", ylabel="start",
           title=f"{res.reference} - {diff.baseline}: mean return difference")
    ax.title.set_fontsize(9)
    ax.figure.colorbar(ScalarMappable(norm, cmap), ax=ax, shrink=0.8,
                       label="each side of 0 scaled to its own extreme; ties faded")


def sorted_differences(ax: Axes, res: PairRuns, diff: Differences) -> None:
    """Every pair's mean difference, lowest first, with its 95% interval."""
    order = np.argsort(diff.mean, kind="stable")
    x = np.arange(len(order))
    mean = diff.mean[order]
    err = np.vstack([mean - diff.low[order], diff.high[order] - mean])
    colours = [OUTCOME_COLOURS[str(o)] for o in diff.outcome[order]]
    ax.errorbar(x, mean, yerr=np.nan_to_num(err), fmt="none", ecolor=colours, lw=0.6)
    ax.scatter(x, mean, c=colours, s=6, zorder=3)
    tuning = res.tuning()[order]
    ax.scatter(x[tuning], mean[tuning], s=40, facecolors="none", edgecolors="black", lw=1,
               zorder=4, label="tuning task (A-D)")
    ax.axhline(0, color="black", lw=0.6)
    if len(order) <= LABELLED:
        ax.set_xticks(x, [res.pairs[i] for i in order], rotation=90, fontsize=7)
    else:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    counts = {o: int(np.sum(diff.outcome == o)) for o in (WIN, "tie", LOSS)}
    ax.set(xlabel="pair, sorted by difference",
           ylabel=f"{res.reference} - {diff.baseline} (95% interval)",
           title=f"{counts[WIN]} wins, {counts['tie']} ties, {counts[LOSS]} losses "
                 f"of {len(order)} pairs")
    ax.title.set_fontsize(9)
    if tuning.any():
        ax.legend(fontsize=7, loc="upper left")


def write_figure(res: PairRuns, diffs: list[Differences], out: Path) -> list[Path]:
    """``figures/pairs.{png,pdf}``: one row per baseline (none: no figure)."""
    if not diffs:
        return []
    fig, axes = plt.subplots(len(diffs), 2, figsize=(12.5, 5.2 * len(diffs)), squeeze=False,
                             layout="constrained", width_ratios=(1, 1.25))
    for (hx, sx), diff in zip(axes, diffs, strict=True):
        heatmap(hx, res, diff)
        sorted_differences(sx, res, diff)
    return save_all(fig, out / "figures", FIGURE_STEM)


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
    lines = markdown_rows(pd.DataFrame(
        [[s.baseline + label, s.pairs, f"{number(s.mean, sign=True)} ({number(s.se)})", s.wins,
          s.ties, s.losses] for label, s in summaries],
        columns=[f"{ref} minus", "pairs", "mean difference (s.e.)", "wins", "ties", "losses"]))
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


def _iqm(res: PairRuns) -> list[str]:
    """Each method over all pairs: the IQM of return / V* with its stratified CI."""
    iqms = iqm_table(res)
    if not len(iqms) or not iqms["pairs"].iloc[0]:
        return []
    rows = markdown_rows(pd.DataFrame(
        [[m, number(r.iqm), f"[{number(r.low)}, {number(r.high)}]"] for m, r in iqms.iterrows()],
        columns=["method", "IQM of return / V*", "95% interval"]))
    return ["## Over all pairs: interquartile mean", "",
            f"Per method, every run on every pair with V* > 0 ({iqms['pairs'].iloc[0]} "
            "pairs) gives one score, its mean return per episode / V*; the interquartile "
            "mean (IQM) of all scores is the mean of their middle 50% (robust to a few "
            "outlying pairs, less noisy than the median), with a 95% stratified bootstrap "
            "interval (runs resampled within each pair, 2,000 resamples, "
            "`scipy.stats.bootstrap`; n/a with a single run).", "",
            *rows, ""]


def make_pairs_report(out: str | Path) -> list[Path]:
    """The table, figure and ``REPORT.md`` of a pairs folder; returns the paths."""
    out = Path(out)
    res = load_pair_runs(out)
    diffs = [differences(res, b) for b in res.baselines]
    paths = write_tables(res, diffs, out)
    paths += write_figure(res, diffs, out)
    paths.append(write_report(res, diffs, out))
    return paths


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
                  f"by goal (blue: {res.reference} better; `+` win, `\u2212` loss, faded: tie; "
                  "boxed: tasks A-D). Right: "
                  f"every pair's difference, sorted, with its {LEVEL:.0%} interval.", "",
                  *_losses(res, diffs), *_worst(res, diffs, all_pairs)]
    else:
        lines += ["Only one method ran: there is nothing to compare.", ""]
    lines += [*_iqm(res), *_definitions(res)]
    path = out / "REPORT.md"
    write_text(path, "\n".join(lines))
    return path
