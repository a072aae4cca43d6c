"""Figures of the wrong-knowledge report: learning curves per case and convergence
episodes per method and case."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from gdq_pddl.analysis.figures import method_colour as _colour
from gdq_pddl.analysis.knowledge_cases import CaseResult
from gdq_pddl.analysis.knowledge_measures import ACCURATE, CURVE_WINDOW, WRONG, threshold
from gdq_pddl.outputs import save_figure


def write_figures(cases: list[CaseResult], out: Path) -> list[Path]:
    """Learning curves per case (wrong solid, accurate dashed, V* and the convergence
    threshold) and a bar chart of convergence episodes per method and case."""
    paths: list[Path] = []
    if not cases:
        return paths
    n = len(cases)
    cols = min(2, n)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(6.2 * cols, 4.0 * rows), squeeze=False,
                             layout="constrained")
    for ax, case in zip(axes.ravel(), cases, strict=False):
        for m in case.methods:
            for kind, style in ((WRONG, "-"), (ACCURATE, "--")):
                r = case.results[kind].get(m)
                if r is None:
                    continue
                x = np.arange(len(r.curve)) + min(CURVE_WINDOW, r.episodes)
                ax.plot(x, r.curve, style, color=_colour(m), lw=1.2 if kind == WRONG else 0.9,
                        label=f"{m} ({kind})")
        ax.axhline(case.v_star, color="black", lw=1, ls=":", label="V* (real world)")
        ax.axhline(threshold(case.v_star), color="grey", lw=0.8, ls="-.",
                   label="convergence threshold")
        lo = min(case.v_star, threshold(case.v_star))
        ax.set_ylim(max(-40.0, lo - 25.0), max(case.v_star, 0.0) + 4.0)
        ax.set_title(f"{case.name}: task {case.task.name} ({case.task.start}->{case.task.goal})",
                     fontsize=10)
        ax.set_xlabel("episode")
        ax.set_ylabel(f"return, {CURVE_WINDOW}-episode mean over runs")
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    handles, labels = axes.ravel()[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8)
    for ext in ("png", "pdf"):
        save_figure(fig, out / f"knowledge_curves.{ext}", dpi=120)
        paths.append(out / f"knowledge_curves.{ext}")
    plt.close(fig)

    methods = list(dict.fromkeys(m for c in cases for m in c.methods))
    fig, axes = plt.subplots(1, n, figsize=(max(3.2 * n, 6), 3.8), squeeze=False,
                             layout="constrained")
    for ax, case in zip(axes.ravel(), cases, strict=True):
        episodes = max((r.episodes for k in case.results.values() for r in k.values()),
                       default=1)
        x = np.arange(len(methods))
        for j, (kind, hatch) in enumerate(((ACCURATE, "//"), (WRONG, ""))):
            for i, m in enumerate(methods):
                r = case.results[kind].get(m)
                if r is None:
                    continue
                med = r.median
                never = not np.isfinite(med)
                ax.bar(x[i] + (j - 0.5) * 0.38, episodes if never else med, width=0.38,
                       color="white" if never else _colour(m), edgecolor=_colour(m),
                       hatch="xx" if never else hatch, lw=1)
        ax.set_xticks(x, methods, rotation=45, ha="right", fontsize=8)
        ax.set_title(case.name, fontsize=10)
        ax.set_ylim(0, episodes * 1.05)
    axes.ravel()[0].set_ylabel("convergence episode (median of runs)")
    fig.suptitle("left bar of each pair (hatched //): accurate knowledge; right: wrong "
                 "knowledge; crossed white bar: never converged", fontsize=8)
    for ext in ("png", "pdf"):
        save_figure(fig, out / f"knowledge_convergence.{ext}", dpi=120)
        paths.append(out / f"knowledge_convergence.{ext}")
    plt.close(fig)
    return paths
