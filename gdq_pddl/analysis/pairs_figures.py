"""The figure of a pairs folder: the reference minus each baseline on every pair.

One row per baseline: a start-by-goal heatmap of the mean paired difference (diverging
colours centred at 0, the diagonal blank, ``+`` on wins and ``-`` on losses, the tuning
tasks boxed), and every pair's difference sorted, with its 95% interval.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

from gdq_pddl.analysis.pairs import LOSS, WIN, Differences, PairRuns  # noqa: E402
from gdq_pddl.outputs import save_figure  # noqa: E402

FIGURE_STEM = "pairs"
OUTCOME_COLOURS = {WIN: "#2166ac", "tie": "#999999", LOSS: "#b2182b"}
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
    limit = float(np.nanmax(np.abs(grid))) if np.isfinite(grid).any() else 0.0
    limit = limit or 1.0  # symmetric about 0: white is no difference
    cmap = plt.get_cmap("RdBu").with_extremes(bad="#b0b0b0")
    image = ax.imshow(grid, cmap=cmap, vmin=-limit, vmax=limit)
    for i, p in enumerate(res.pairs):
        r, c = at[res.facts[p]["start"]], at[res.facts[p]["goal"]]
        mark = {WIN: "+", LOSS: "\u2212"}.get(str(diff.outcome[i]), "")
        if mark:
            dark = abs(diff.mean[i]) > 0.6 * limit
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
    ax.figure.colorbar(image, ax=ax, shrink=0.8)


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


def write_figure(res: PairRuns, diffs: list[Differences], out: Path,
                 formats: tuple[str, ...] = ("png", "pdf"), dpi: int = 120) -> list[Path]:
    """``figures/pairs.{png,pdf}``: one row per baseline (none: no figure)."""
    if not diffs:
        return []
    fig, axes = plt.subplots(len(diffs), 2, figsize=(12.5, 5.2 * len(diffs)), squeeze=False,
                             layout="constrained", width_ratios=(1, 1.25))
    for (hx, sx), diff in zip(axes, diffs, strict=True):
        heatmap(hx, res, diff)
        sorted_differences(sx, res, diff)
    target = out / "figures"
    target.mkdir(parents=True, exist_ok=True)
    paths = []
    for ext in formats:
        path = target / f"{FIGURE_STEM}.{ext}"
        save_figure(fig, path, dpi=dpi)
        paths.append(path)
    plt.close(fig)
    return paths
