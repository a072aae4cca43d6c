"""Tables, figure and ``REPORT.md`` of a pairs folder (``gdq-pddl pairs``): per pair the
reference (GDQ when it ran) minus each baseline, paired over runs, with its t-interval
and win / tie / loss, summaries and the IQM over pairs (docs/decisions.md, "Every
start/goal pair", defines each)."""

from __future__ import annotations

import math
import shlex
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle
from matplotlib.ticker import MaxNLocator
from scipy.special import stdtrit  # t's quantile: scipy.stats costs 0.6 s of start-up

from gdq_pddl.analysis.figures import save_all
from gdq_pddl.analysis.stats import iqm_ci
from gdq_pddl.analysis.writer import number, render, table_text
from gdq_pddl.experiments.pairs import PairRuns, load_pair_runs
from gdq_pddl.outputs import write_text

LEVEL = 0.95
WIN, TIE, LOSS = "win", "tie", "loss"
OUTCOME_COLOURS = {WIN: "#2166ac", TIE: "#999999", LOSS: "#b2182b"}
WORST = 10  # pairs listed per baseline
TIE_STRENGTH = 0.3  # a tie's colour in the heatmap, as a share of its full strength
LABELLED, LISTED_PAIRS = 30, 12  # up to so many pairs the plot / the command names each


def over_runs(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error (ddof 1) over the last axis, the runs; one run has no
    standard error (NaN, shown ``n/a``): a single run is no evidence of a difference."""
    n = x.shape[-1]
    se = x.std(axis=-1, ddof=1) / math.sqrt(n) if n > 1 else np.full(x.shape[:-1], np.nan)
    return x.mean(axis=-1), se


@dataclass(frozen=True)
class Differences:
    """The reference minus one baseline, per pair; ``outcome``: ``win`` when the 95%
    interval ``[low, high]`` lies above 0, ``loss`` below, ``tie`` otherwise."""

    baseline: str
    mean: np.ndarray
    se: np.ndarray
    low: np.ndarray
    high: np.ndarray
    outcome: np.ndarray


def differences(res: PairRuns, baseline: str) -> Differences:
    """Paired differences ``reference - baseline`` on every pair."""
    d = (res.means[:, res.methods.index(res.reference), :]
         - res.means[:, res.methods.index(baseline), :])
    mean, se = over_runs(d)
    n = d.shape[-1]
    half = stdtrit(n - 1, (1 + LEVEL) / 2) * se if n > 1 else np.full_like(mean, np.nan)
    outcome = np.where(mean - half > 0, WIN, np.where(mean + half < 0, LOSS, TIE))
    return Differences(baseline, mean, se, mean - half, mean + half, outcome)


def summary_row(d: Differences, keep: np.ndarray, label: str = "") -> list:
    """Over the pairs where ``keep``: the baseline, pairs, the mean of the per-pair
    differences (s.e. sqrt(sum se^2) / pairs), wins, ties and losses."""
    idx = np.flatnonzero(keep)
    mean = float(d.mean[idx].mean()) if idx.size else math.nan
    se = float(np.sqrt(np.sum(d.se[idx] ** 2)) / idx.size) if idx.size else math.nan
    return [d.baseline + label, int(idx.size), f"{number(mean, sign=True)} ({number(se)})",
            *(int(np.sum(d.outcome[idx] == o)) for o in (WIN, TIE, LOSS))]


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
    md = pd.DataFrame({
        "pair": [f"**{p}**" if t else p for p, t in zip(full["pair"], full["tuning"],
                                                         strict=True)],
        "tuning": [f"task {t}" if t else "" for t in full["tuning"]],
        "shortest plan": [str(n) if n >= 0 else "none" for n in full["shortest_plan"]],
        "V*": full["v_star"].map(number)})
    for m in res.methods:
        md[m] = [f"{number(a)} ({number(b)})" for a, b in zip(full[f"mean_{m}"],
                                                             full[f"se_{m}"], strict=True)]
    for d in diffs:
        md[f"{res.reference} - {d.baseline}"] = [
            f"{number(a, sign=True)} ({number(b)}) {o}"
            for a, b, o in zip(d.mean, d.se, d.outcome, strict=True)]
    return md.to_markdown(index=False, disable_numparse=True) + "\n"


def symmetric_top(grid: np.ndarray) -> float:
    """The half-range of the heatmap's colour scale: the largest absolute finite value of
    ``grid`` (1 where there is none, a tiny positive number where all are 0)."""
    finite = grid[np.isfinite(grid)]
    if not finite.size:
        return 1.0
    return max(float(np.max(np.abs(finite))), 1e-9)


def heatmap(ax: Axes, res: PairRuns, diff: Differences) -> None:
    """Start (rows) by goal (columns), colour = mean difference on one symmetric scale,
    ``-top .. +top`` with ``top`` the largest absolute difference (:func:`symmetric_top`), so
    a loss looks as deep as a win of the same size; ties faded; grey: the diagonal and
    pairs not run."""
    names = res.positions
    rows, cols = ([names.index(res.facts[p][end]) for p in res.pairs] for end in ("start", "goal"))
    grid = np.full((len(names), len(names)), np.nan)
    grid[rows, cols] = diff.mean
    top = symmetric_top(grid)
    norm = Normalize(-top, top)
    cmap = colormaps["RdBu"].with_extremes(bad="#b0b0b0")
    rgba = cmap(norm(np.ma.masked_invalid(grid)))
    tie = diff.outcome == TIE  # faded: a tie's small mean must not look like a loss
    r, c = np.array(rows)[tie], np.array(cols)[tie]
    rgba[r, c, :3] = 1 - TIE_STRENGTH * (1 - rgba[r, c, :3])
    ax.imshow(rgba)
    for i, (p, r, c) in enumerate(zip(res.pairs, rows, cols, strict=True)):
        if mark := {WIN: "+", LOSS: "\u2212"}.get(str(diff.outcome[i]), ""):
            ax.text(c, r, mark, ha="center", va="center", fontsize=7,
                    color="white" if abs(norm(diff.mean[i]) - 0.5) > 0.3 else "black")
        if res.facts[p].get("tuning"):
            ax.add_patch(Rectangle((c - 0.5, r - 0.5), 1, 1, fill=False, lw=1.5,
                                   edgecolor="black"))
    ax.set_xticks(range(len(names)), names, rotation=90, fontsize=6)
    ax.set_yticks(range(len(names)), names, fontsize=6)
    ax.set(xlabel="goal", ylabel="start")
    ax.set_title(f"{res.reference} - {diff.baseline}: mean return difference", fontsize=9)
    ax.figure.colorbar(ScalarMappable(norm, cmap), ax=ax, shrink=0.8, format="%.3g",
                       ticks=[-top, -top / 2, 0, top / 2, top],
                       label="one scale for wins (blue) and losses (red); ties faded")


def sorted_differences(ax: Axes, res: PairRuns, diff: Differences) -> None:
    """Every pair's mean difference, lowest first, with its 95% interval."""
    order = np.argsort(diff.mean, kind="stable")
    x, mean = np.arange(len(order)), diff.mean[order]
    err = np.vstack([mean - diff.low[order], diff.high[order] - mean])
    colours = [OUTCOME_COLOURS[str(o)] for o in diff.outcome[order]]
    ax.errorbar(x, mean, yerr=np.nan_to_num(err), fmt="none", ecolor=colours, lw=0.6)
    ax.scatter(x, mean, c=colours, s=6, zorder=3)
    tuning = res.tuning()[order]
    ax.scatter(x[tuning], mean[tuning], s=40, facecolors="none", edgecolors="black", lw=1,
               zorder=4, label="tuning task (A-D)")
    ax.axhline(0, color="black", lw=0.6)
    if (losses := diff.mean[diff.outcome == LOSS]).size:  # linear up to the largest loss
        ax.set_yscale("symlog", linthresh=float(-losses.min()))  # so that losses show
    if len(order) <= LABELLED:
        ax.set_xticks(x, [res.pairs[i] for i in order], rotation=90, fontsize=7)
    else:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    n = {o: int(np.sum(diff.outcome == o)) for o in (WIN, TIE, LOSS)}
    ax.set(xlabel="pair, sorted by difference",
           ylabel=f"{res.reference} - {diff.baseline} (95% interval)"
           + (", symmetric log scale" if losses.size else ""))
    ax.set_title(f"{n[WIN]} wins, {n[TIE]} ties, {n[LOSS]} losses of {len(order)} pairs",
                 fontsize=9)
    if tuning.any():
        ax.legend(fontsize=7, loc="upper left")


def command(res: PairRuns) -> str:
    """The command line that makes this folder (its pairs listed when they are few)."""
    exp = res.config["experiments"][0]
    argv = ["gdq-pddl", "pairs", "--method", *res.methods, "--episodes",
            str(exp["schedule"][0][1]), "--runs", str(exp["runs"]), "--seed", str(exp["seed"])]
    argv += ["--world", exp["world"]] if exp["world"] != "office" else []
    argv += ["--planner", exp["planner"]] if exp["planner"] != "graph" else []
    n = len(res.positions)
    if len(res.pairs) < n * (n - 1) and len(res.pairs) <= LISTED_PAIRS:
        argv += ["--pairs", " ".join(res.pairs)]
    return shlex.join(argv)


def report_text(res: PairRuns, diffs: list[Differences]) -> str:
    """``REPORT.md``: setup, tuning, summary, figure, losses, worst pairs, IQM, the table."""
    exp, n, all_pairs = res.config["experiments"][0], len(res.positions), len(res.pairs)
    untuned = ~res.tuning()
    rows = [summary_row(d, np.ones(all_pairs, bool)) for d in diffs]
    rows += [summary_row(d, untuned, ", excluding A-D") for d in diffs if untuned.sum() < all_pairs]
    lost = [i for i in range(all_pairs) if any(d.outcome[i] == LOSS for d in diffs)]
    iqm_pairs, iqms = iqm_rows(res)
    return render(
        "pairs.md.j2", res=res, exp=exp, ref=res.reference, command=command(res), diffs=diffs,
        lost=lost, level=f"{LEVEL:.0%}", chance=f"{(1 - LEVEL) * all_pairs:.1f}", worst_n=WORST,
        hyper=", ".join(f"{k} = {v}" for k, v in exp["hyper"].items()),
        subset="" if all_pairs == n * (n - 1) else f" (of the {n * (n - 1)})",
        tuned=", ".join(res.label(i) for i in np.flatnonzero(res.tuning())),
        summary=table_text(rows, [f"{res.reference} minus", "pairs", "mean difference (s.e.)",
                                  "wins", "ties", "losses"]),
        worst=min(((d.mean[i], d.baseline, res.pairs[i]) for d in diffs for i in lost
                   if d.outcome[i] == LOSS), default=None),
        order=[np.argsort(d.mean, kind="stable")[:WORST] for d in diffs],
        iqm_pairs=iqm_pairs, iqms=table_text(iqms, [
            "method", "IQM of return / V*", "95% interval"]) if iqm_pairs else "")


def iqm_rows(res: PairRuns) -> tuple[int, list[list[str]]]:
    """How many pairs have V* > 0 and, per method over them, the IQM of every run's mean
    return / V* with its stratified bootstrap 95% CI (:func:`.stats.iqm_ci`)."""
    v_star = np.array([float(res.facts[p].get("v_star") or math.nan) for p in res.pairs])
    keep = np.flatnonzero(v_star > 0)
    rows = []
    for j, m in enumerate(res.methods):
        point, low, high = iqm_ci([res.means[i, j] / v_star[i] for i in keep])
        rows.append([m, number(point), f"[{number(low)}, {number(high)}]"])
    return len(keep), rows


def make_pairs_report(out: str | Path) -> list[Path]:
    """``tables/pairs.{csv,md}``, ``figures/pairs.{png,pdf}`` (a row per baseline; none
    when one method ran) and ``REPORT.md`` of a pairs folder; returns the paths."""
    out = Path(out)
    res = load_pair_runs(out)
    diffs = [differences(res, b) for b in res.baselines]
    (out / "tables").mkdir(parents=True, exist_ok=True)
    paths = [out / "tables" / "pairs.csv", out / "tables" / "pairs.md"]
    frame = table(res, diffs)
    floats = [c for c in frame if frame[c].dtype == float]
    frame[floats] = frame[floats].map(lambda x: repr(float(x)))  # every digit
    write_text(paths[0], frame.to_csv(index=False, lineterminator="\n"))
    write_text(paths[1], table_markdown(res, diffs))
    if diffs:
        fig = Figure(figsize=(12.5, 5.2 * len(diffs)), layout="constrained")
        axes = fig.subplots(len(diffs), 2, squeeze=False, width_ratios=(1, 1.25))
        for (hx, sx), diff in zip(axes, diffs, strict=True):
            heatmap(hx, res, diff)
            sorted_differences(sx, res, diff)
        paths += save_all(fig, out / "figures", "pairs")
    paths.append(out / "REPORT.md")
    write_text(paths[-1], report_text(res, diffs))
    return paths
