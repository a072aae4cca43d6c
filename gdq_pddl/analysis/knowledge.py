"""Figures and ``REPORT.md`` of the wrong-knowledge experiments (``gdq-pddl knowledge``).

Per case, experiments ``<case>--accurate`` and ``<case>--wrong`` run on the same real
world; :func:`analyse` measures each method's convergence, final greedy policy and
whether the knowledge holds an optimal action along the optimal route (the report's
definitions, ``templates/knowledge.md.j2``; docs/decisions.md says why).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from gdq_pddl.analysis.figures import grid, method_colour, save_all
from gdq_pddl.analysis.stats import moving_average
from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.writer import render, table_text
from gdq_pddl.experiments.knowledge import (
    ACCURATE,
    CASES,
    CHECKS,
    WRONG,
    CaseTruth,
    ProblemTruth,
    RouteStep,
    case_truth,
    problem_truth,
)
from gdq_pddl.experiments.protocol import ProblemSpec
from gdq_pddl.experiments.scale import converged_at
from gdq_pddl.outputs import write_text

WINDOW, CURVE_WINDOW, FINAL = 100, 50, 100  # episodes: convergence, curves, final return
FRACTION = 0.85  # convergence threshold: V* - (1 - FRACTION) |V*|


def threshold(v_star: float, fraction: float = FRACTION) -> float:
    """The return level a converged learner's moving average reaches."""
    return v_star - (1.0 - fraction) * abs(v_star)


@dataclass
class MethodResult:
    """One method in one experiment (accurate or wrong knowledge) of a case: per run the
    convergence episode, final greedy policy's value and area route (``()``: no goal);
    ``on_route``: runs whose policy follows the optimal area route to the goal; ``curve``:
    mean over runs of the trailing moving average (episodes CURVE_WINDOW..n)."""

    runs: int
    episodes: int
    convergence: list[int | None]
    final_return: float
    on_route: int
    policy_values: list[float]
    routes: list[tuple[int, ...]]
    curve: np.ndarray

    @property
    def converged(self) -> int:
        return sum(e is not None for e in self.convergence)

    @property
    def median(self) -> float:
        """Median over runs, unconverged runs as +inf (inf: most runs never converged)."""
        if not self.convergence:
            return float("nan")
        return float(np.median([np.inf if e is None else e for e in self.convergence]))


@dataclass
class CaseResult:
    """One case: the real world's :class:`CaseTruth` and ``results[ACCURATE|WRONG][method]``."""

    name: str
    description: str
    real: str
    knowledge: str
    truth: CaseTruth | ProblemTruth
    methods: list[str]
    results: dict[str, dict[str, MethodResult]]

    def paired(self) -> list[tuple[str, MethodResult, MethodResult]]:
        """``(method, accurate, wrong)`` for each method with results in both."""
        return [(m, self.results[ACCURATE][m], self.results[WRONG][m]) for m in self.methods
                if m in self.results[ACCURATE] and m in self.results[WRONG]]


def analyse(out: str | Path) -> list[CaseResult]:
    """Measure every case of an output folder of ``gdq-pddl knowledge``."""
    study = Study.open(out)
    exps = {e["name"]: e for e in study.config.experiments}
    described = {c.name: c.description for c in CASES}
    names = sorted({n.rsplit("--", 1)[0] for n in exps if n.endswith(("--accurate", "--wrong"))},
                   key=lambda n: (list(described).index(n) if n in described else 99, n))
    cases = []
    for name in names:
        acc, wrong = exps.get(f"{name}--{ACCURATE}"), exps.get(f"{name}--{WRONG}")
        if acc is None or wrong is None:
            continue
        truth = problem_truth(wrong) if wrong.get("pddl") else case_truth(wrong)
        task, level = truth.task, threshold(truth.v_star)
        methods = [m for m in wrong["methods"] if m in acc["methods"]]
        results: dict[str, dict[str, MethodResult]] = {}
        for kind, exp in ((ACCURATE, acc), (WRONG, wrong)):
            results[kind] = {}
            for m in methods:
                returns = study.returns(exp["name"], m)
                if returns.size == 0:
                    continue
                w = min(CURVE_WINDOW, returns.shape[1])
                results[kind][m] = MethodResult(
                    len(returns), returns.shape[1],
                    [converged_at(row, level, min(WINDOW, len(row))) for row in returns],
                    float(np.mean(returns[:, -FINAL:])),
                    *truth.measure({r: study.policy(exp["name"], m, task.name, r)
                                    for r in range(len(returns))}),
                    moving_average(returns, w)[:, w - 1:].mean(axis=0))
        real = _shown(ProblemSpec.from_record(wrong["pddl"]).domain) if wrong.get("pddl") \
            else wrong["world"]
        cases.append(CaseResult(name, described.get(name, ""), real,
                                _shown(str(wrong.get("knowledge") or wrong["world"])), truth,
                                methods, results))
    return cases


def _shown(name: str) -> str:
    """A world name, or a file path relative to the package's folder when inside it."""
    try:
        return Path(name).resolve().relative_to(PACKAGE_ROOT).as_posix()
    except ValueError:
        return name


PACKAGE_ROOT = Path(__file__).resolve().parents[2]
"""The folder holding ``gdq_pddl`` (shipped files are shown relative to it)."""


def write_figures(cases: list[CaseResult], out: Path) -> list[Path]:
    """Learning curves per case (wrong solid, accurate dashed, V* and the convergence
    threshold) and a bar chart of convergence episodes per method and case."""
    if not cases:
        return []
    fig, axes = grid(len(cases), 6.2, 4.0)
    for ax, case in zip(axes, cases, strict=True):
        for m in case.methods:
            for kind, style, lw in ((WRONG, "-", 1.2), (ACCURATE, "--", 0.9)):
                if (r := case.results[kind].get(m)) is not None:
                    ax.plot(np.arange(len(r.curve)) + min(CURVE_WINDOW, r.episodes), r.curve,
                            style, color=method_colour(m), lw=lw, label=f"{m} ({kind})")
        v_star, task = case.truth.v_star, case.truth.task
        level = threshold(v_star)
        ax.axhline(v_star, color="black", lw=1, ls=":", label="V* (real world)")
        ax.axhline(level, color="grey", lw=0.8, ls="-.", label="convergence threshold")
        ax.set_ylim(max(-40.0, min(v_star, level) - 25.0), max(v_star, 0.0) + 4.0)
        ax.set_title(f"{case.name}: task {task.name} ({task.start}->{task.goal})", fontsize=10)
        ax.set(xlabel="episode", ylabel=f"return, {CURVE_WINDOW}-episode mean over runs")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=4,
               fontsize=8)
    paths = save_all(fig, out, "knowledge_curves")

    methods = list(dict.fromkeys(m for c in cases for m in c.methods))
    fig = Figure(figsize=(max(3.2 * len(cases), 6), 3.8), layout="constrained")
    axes = fig.subplots(1, len(cases), squeeze=False)
    for ax, case in zip(axes.ravel(), cases, strict=True):
        episodes = max((r.episodes for k in case.results.values() for r in k.values()),
                       default=1)
        for j, (kind, hatch) in enumerate(((ACCURATE, "//"), (WRONG, ""))):
            for i, m in enumerate(methods):
                if (r := case.results[kind].get(m)) is None:
                    continue
                never = not np.isfinite(r.median)
                ax.bar(i + (j - 0.5) * 0.38, episodes if never else r.median, width=0.38,
                       color="white" if never else method_colour(m),
                       edgecolor=method_colour(m), hatch="xx" if never else hatch, lw=1)
        ax.set_xticks(np.arange(len(methods)), methods, rotation=45, ha="right", fontsize=8)
        ax.set_title(case.name, fontsize=10)
        ax.set_ylim(0, episodes * 1.05)
    axes.ravel()[0].set_ylabel("convergence episode (median of runs)")
    fig.suptitle("left bar of each pair (hatched //): accurate knowledge; right: wrong "
                 "knowledge; crossed white bar: never converged", fontsize=8)
    return paths + save_all(fig, out, "knowledge_convergence")


def _ep(value: float) -> str:
    return "n/a" if np.isnan(value) else "never" if not np.isfinite(value) else f"{value:.0f}"


def _extra(acc: MethodResult, wrong: MethodResult) -> str:
    a, w = np.isfinite(acc.median), np.isfinite(wrong.median)
    return (f"{wrong.median - acc.median:+.0f}" if a and w else "never converges" if a else
            "converges only with wrong knowledge" if w else "neither converges")


def _frac(values: list[float], v_star: float) -> str:
    m = float(np.mean(values)) if values else np.nan
    return "n/a" if not values else f"{m / v_star:.2f}" if v_star > 0 else f"{m:.2f}"


def _check(steps: list[RouteStep], attr: str) -> str:
    missing = [f"{s.state} ({' / '.join(s.optimal)})" for s in steps if not getattr(s, attr)]
    return "no, not at " + "; ".join(missing) if missing else "yes, at every step"


def problem_case_data(case: CaseResult) -> dict:
    """A PDDL case's table and findings for ``templates/knowledge.md.j2``."""
    rows = [[m, f"{w.converged} / {a.converged}", f"{_ep(w.median)} / {_ep(a.median)}",
             _extra(a, w), f"{w.final_return:.2f} / {a.final_return:.2f}"]
            for m, a, w in case.paired()]
    return {"case": case, "pddl": True, "threshold": threshold(case.truth.v_star),
            "table": table_text(rows, ["method", "converged runs",
                                       "median convergence episode", "extra episodes",
                                       "final return"]),
            "findings": [(m, a, w, f"{_ep(w.median)} vs {_ep(a.median)}: {_extra(a, w)}")
                         for m, a, w in case.paired()]}


def case_data(case: CaseResult) -> dict:
    """A case's tables and findings for ``templates/knowledge.md.j2``."""
    if isinstance(case.truth, ProblemTruth):
        return problem_case_data(case)
    rows = [[m, f"{w.on_route}/{w.runs} / {a.on_route}/{a.runs}",
             f"{w.converged} / {a.converged}", f"{_ep(w.median)} / {_ep(a.median)}",
             _extra(a, w), f"{_frac(w.policy_values, case.truth.v_star)} / "
             f"{_frac(a.policy_values, case.truth.v_star)}",
             f"{w.final_return:.2f} / {a.final_return:.2f}",
             ", ".join(f"{'-'.join(map(str, k)) if k else 'no goal'} x{v}"
                       for k, v in Counter(w.routes).most_common()) or "n/a"]
            for m, a, w in case.paired()]
    return {"case": case, "pddl": False, "threshold": threshold(case.truth.v_star),
            "table": table_text(rows, [
        "method", "on route (wrong / accurate)", "converged runs", "median convergence episode",
        "extra episodes", "policy value", "final return", "greedy routes (wrong)"]),
        "checks": table_text([[kind, *(_check(case.truth.checks[kind], a) for a in CHECKS)]
                              for kind in (WRONG, ACCURATE)], ["knowledge", *CHECKS.values()]),
        "findings": [(m, a, w, f"{_ep(w.median)} vs {_ep(a.median)}: {_extra(a, w)}")
                     for m, a, w in case.paired()],
        "excluded": [s.state for s in case.truth.checks[WRONG] if not s.darling_allowed]}


def make_knowledge_report(out: str | Path, command: str = "gdq-pddl knowledge") -> list[Path]:
    """Analyse ``out`` and write its figures and ``REPORT.md``; returns the paths."""
    out = Path(out)
    cases = analyse(out)
    path = out / "REPORT.md"
    write_text(path, render("knowledge.md.j2", command=command, window=WINDOW, final=FINAL,
                            fraction=FRACTION, cases=[case_data(c) for c in cases]))
    return [*write_figures(cases, out), path]
