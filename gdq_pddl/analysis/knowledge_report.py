"""Figures and ``REPORT.md`` of the wrong-knowledge experiments: learning curves per
case, convergence episodes per method and case, and per case the measurements of
:mod:`gdq_pddl.analysis.knowledge`, every sentence generated from them."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from gdq_pddl.analysis.figures import grid, save_all
from gdq_pddl.analysis.figures import method_colour as _colour
from gdq_pddl.analysis.knowledge import (
    ACCURATE,
    CURVE_WINDOW,
    FINAL,
    FRACTION,
    WINDOW,
    WRONG,
    CaseResult,
    MethodResult,
    RouteStep,
    analyse,
    threshold,
)
from gdq_pddl.analysis.writer import markdown_rows
from gdq_pddl.outputs import write_text


def write_figures(cases: list[CaseResult], out: Path) -> list[Path]:
    """Learning curves per case (wrong solid, accurate dashed, V* and the convergence
    threshold) and a bar chart of convergence episodes per method and case."""
    paths: list[Path] = []
    if not cases:
        return paths
    n = len(cases)
    fig, axes = grid(n, 6.2, 4.0)
    for ax, case in zip(axes, cases, strict=True):
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
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8)
    paths += save_all(fig, out, "knowledge_curves")

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
    paths += save_all(fig, out, "knowledge_convergence")
    return paths


def _ep(value: float) -> str:
    if np.isnan(value):
        return "n/a"
    return "never" if not np.isfinite(value) else f"{value:.0f}"


def _extra(acc: MethodResult | None, wrong: MethodResult | None) -> str:
    if acc is None or wrong is None:
        return "n/a"
    a, w = acc.median, wrong.median
    if np.isfinite(a) and np.isfinite(w):
        return f"{w - a:+.0f}"
    if np.isfinite(a):
        return "never converges"
    if np.isfinite(w):
        return "converges only with wrong knowledge"
    return "neither converges"


def _frac(values: list[float], v_star: float) -> str:
    if not values:
        return "n/a"
    m = float(np.mean(values))
    return f"{m / v_star:.2f}" if v_star > 0 else f"{m:.2f}"


def _route_summary(r: MethodResult) -> str:
    return ", ".join(f"{'-'.join(map(str, k)) if k else 'no goal'} x{v}"
                     for k, v in Counter(r.routes).most_common()) or "n/a"


def _check_summary(steps: list[RouteStep], attr: str) -> str:
    missing = [f"{s.state} ({' / '.join(s.optimal)})" for s in steps if not getattr(s, attr)]
    if not missing:
        return "yes, at every step"
    return "no, not at " + "; ".join(missing)


def _findings(case: CaseResult) -> list[str]:
    out = []
    for m, a, w in case.paired():
        out.append(
            f"**{m}**: greedy policy on the optimal route in {w.on_route}/{w.runs} runs with "
            f"wrong knowledge, {a.on_route}/{a.runs} with accurate; converged in "
            f"{w.converged}/{w.runs} vs {a.converged}/{a.runs} runs (median episode "
            f"{_ep(w.median)} vs {_ep(a.median)}: {_extra(a, w)}).")
    steps = case.checks[WRONG]
    excluded = [s for s in steps if not s.darling_allowed]
    if excluded:
        out.append("DARLING's allowed set (wrong knowledge) excludes every optimal action at "
                   + ", ".join(s.state for s in excluded) + ".")
    else:
        out.append("DARLING's allowed set (wrong knowledge) contains an optimal action at "
                   "every step of the optimal route.")
    return out


def write_report(cases: list[CaseResult], out: Path, command: str = "gdq-pddl knowledge"
                 ) -> Path:
    """``REPORT.md``: per case the measurements described in the module docstring."""
    lines = [
        "# Knowledge that disagrees with the world",
        "",
        f"Command: `{command}`. The env simulates the *real* world; the learners' knowledge "
        "(PDDL problem, plans) is built from the *knowledge* world. Each case is run twice on "
        "the same real world: with wrong knowledge, and with accurate knowledge (built from "
        "the real world) as the reference. V* and the optimal route come from value "
        "iteration on the real world.",
        "",
        "Definitions (measured, see `gdq_pddl/analysis/knowledge.py`):",
        "",
        f"- *converged at episode e*: e is the first episode at which the trailing {WINDOW}"
        f"-episode mean return of a run reaches V* - {1 - FRACTION:.2f} |V*| (first passage; "
        "'stays above until the end' measured mostly the last exploration dip). The median "
        "is over runs, unconverged runs counting as 'never'; *extra* = median with wrong "
        "knowledge - median with accurate knowledge. The control case's extra episodes "
        "show the noise of this comparison.",
        "- *on route*: the final greedy policy, walked along likeliest outcomes in the real "
        "world, reaches the goal along the optimal policy's area route.",
        "- *policy value*: the exact expected return of the final greedy policy in the real "
        "world, as a fraction of V* (the raw value when V* <= 0).",
        f"- *final return*: mean return of the last {FINAL} episodes over all runs.",
        "",
        "Figures: `knowledge_curves.png` (learning curves; solid: wrong knowledge, dashed: "
        "accurate), `knowledge_convergence.png` (convergence episodes).",
        "",
    ]
    for case in cases:
        lines += [
            f"## {case.name}",
            "",
            case.description + "." if case.description else "",
            "",
            f"- real world `{case.real}`, knowledge world `{case.knowledge}`, task "
            f"{case.task.name} ({case.task.start} -> {case.task.goal})",
            f"- V* = {case.v_star:.3f}; convergence threshold {threshold(case.v_star):.3f}",
            f"- optimal route: {' '.join(case.optimal_positions)} (areas "
            f"{'-'.join(map(str, case.optimal_areas))})",
            "",
            *markdown_rows(pd.DataFrame([[
                m, f"{w.on_route}/{w.runs} / {a.on_route}/{a.runs}",
                f"{w.converged} / {a.converged}", f"{_ep(w.median)} / {_ep(a.median)}",
                _extra(a, w), f"{_frac(w.policy_values, case.v_star)} / "
                f"{_frac(a.policy_values, case.v_star)}",
                f"{w.final_return:.2f} / {a.final_return:.2f}", _route_summary(w)]
                for m, a, w in case.paired()], columns=[
                "method", "on route (wrong / accurate)", "converged runs",
                "median convergence episode", "extra episodes", "policy value",
                "final return", "greedy routes (wrong)"])),
            "", "(pairs are wrong knowledge / accurate knowledge)", "",
            "Does the knowledge contain the true optimum? Along the optimal route:", "",
            *markdown_rows(pd.DataFrame([[kind, *(_check_summary(case.checks[kind], a) for a in (
                "darling_allowed", "in_prior", "in_shortest_plans", "in_tolerant_plans"))]
                for kind in (WRONG, ACCURATE)], columns=[
                "knowledge", "DARLING allows an optimal action", "an optimal action is "
                "applicable in the prior model (GDQ)", "... starts a shortest plan "
                "(GDQ-literal)", "... a plan within 1.3x (GDQ-code)"]))]
        lines += ["", "Findings:", ""] + [f"- {f}" for f in _findings(case)] + [""]
    path = out / "REPORT.md"
    write_text(path, "\n".join(lines))
    return path


def make_knowledge_report(out: str | Path, command: str = "gdq-pddl knowledge") -> list[Path]:
    """Analyse ``out`` and write its figures and ``REPORT.md``; returns the paths."""
    out = Path(out)
    cases = analyse(out)
    paths = write_figures(cases, out)
    paths.append(write_report(cases, out, command))
    return paths
