"""Methods compared: the experiments the paper's sections do not cover (``gdq-pddl run``,
or any experiment not named ``tasks``, ``switch-*`` or ``robot``), method by method and
task by task, with each GDQ variant tested against each baseline.

The per-method numbers are :func:`gdq_pddl.analysis.generic.summarise`'s (the PDDL
report's table) and the tests :func:`gdq_pddl.analysis.stats.compare`'s, so this section,
the PDDL report and the hypotheses agree on every definition.
"""

from __future__ import annotations

import math
import re

import numpy as np

from gdq_pddl.analysis.data import ROBOT_EXPERIMENT, SWITCH_PREFIX, TASKS_EXPERIMENT
from gdq_pddl.analysis.generic import MethodSummary, fmt2, optimal_entry, task_summary
from gdq_pddl.analysis.sections.writer import Writer, milestone_str, pct
from gdq_pddl.analysis.stats import compare, first_positive, run_means, verdict_reason
from gdq_pddl.analysis.study import Study

TITLE = "Methods compared"


def uncovered(study: Study) -> list[str]:
    """The experiments no paper section covers (the paper's are ``tasks``, ``robot`` and
    every ``switch-*``, whatever its tasks)."""
    return [e for e in study.episodes.experiments
            if e not in (TASKS_EXPERIMENT, ROBOT_EXPERIMENT)
            and not e.startswith(SWITCH_PREFIX)]


def curves_stem(experiment: str) -> str:
    """The file stem of an uncovered experiment's learning-curve figure."""
    return "learning_curves_" + (re.sub(r"[^A-Za-z0-9]+", "_", experiment).strip("_") or "x")


def definitions(window: int) -> str:
    """What :func:`write_task`'s table and comparisons report (for the text above them)."""
    return ("Per method: the runs; the mean return per episode over all the task's "
            "episodes, mean over runs (standard error over runs); the same over each "
            "run's last 10% of episodes; the success rate (share of all episodes of all "
            "runs that reach the goal); and the episode of the task (1 = its first) at "
            f"which the {window}-episode moving average of the mean curve over runs "
            "first turns positive (in brackets: the mean over the runs that reach it, and "
            "how many do; n/a: never within the data). Bold: the highest mean return. "
            "Then each GDQ variant against each baseline (every method but GDQ and its "
            "variants) on the per-run mean return, over all episodes and over the last "
            "10%:")


def write(w: Writer) -> None:
    """The section, or nothing at all when every experiment has its paper section."""
    exps = uncovered(w.study)
    if not exps:
        return
    w.verdicts.elsewhere.append(TITLE)
    w.add(f"## {TITLE}", "",
          f"Experiments no paper hypothesis covers ({', '.join(exps)}): each method on "
          f"each task of the experiment. {definitions(w.opts.window)} Welch's t-test "
          "and bootstrap CI as in the Method paragraph.", "")
    for exp in exps:
        w.figure(curves_stem(exp), f"learning curves, {exp}")
        for task in w.study.episodes.tasks(exp):
            write_task(w, exp, task)


def write_task(w: Writer, exp: str, task: str) -> None:
    study, window = w.study, w.opts.window
    summaries = {m: s for m in study.methods(exp)
                 if (s := task_summary(study.episodes, exp, m, task)) is not None}
    if not summaries:
        return
    w.add(f"### {exp}: task {task}", "")
    v_star = optimal_entry(study.optimal, task, study.config.world_spec(exp)).get("v_star")
    facts = [f"V* = {v_star:.2f} (optimal expected return per episode, value iteration "
             "on the true model; `optimal.json`)" if v_star is not None
             else "V*: not in `optimal.json`"]
    facts += [f"{n} episodes per run, last 10% = the final {t}"
              for n, t in sorted({(s.episodes, s.tail) for s in summaries.values()})]
    w.add("; ".join(facts) + ".", "",
          f"| Method | runs | mean return (SE) | last 10% (SE) | success rate | "
          f"MA{window} > 0 at episode |", "|---|--:|--:|--:|--:|--:|")
    best = max(summaries, key=lambda m: -math.inf if math.isnan(summaries[m].mean)
               else summaries[m].mean)
    for method, s in summaries.items():
        name = f"**{method}**" if method == best else method
        ms = first_positive(study.returns(exp, method, task), window)
        w.add(f"| {name} | {s.runs} | {fmt2(s.mean)} ({fmt2(s.se)}) | "
              f"{fmt2(s.last)} ({fmt2(s.last_se)}) | {pct(s.success)} | "
              f"{milestone_str(ms)} |")
    w.add("")
    comparisons(w, exp, task, summaries)


def comparisons(w: Writer, exp: str, task: str, summaries: dict[str, MethodSummary]) -> None:
    """Each GDQ variant against each baseline, all episodes and the last 10%."""
    study = w.study
    variants = [v for v in w.variants(exp) if v in summaries]
    baselines = [b for b in study.baselines(exp) if b in summaries]
    if not variants or not baselines:
        w.add(f"No {'GDQ variant' if not variants else 'baseline'} ran on this task: "
              "nothing to compare.", "")
        return
    for variant in variants:
        for label, tail in (("all episodes", False), ("last 10% of episodes", True)):
            comps = []
            for b in baselines:
                a_runs, b_runs = (per_run(study.returns(exp, m, task), summaries[m], tail)
                                  for m in (variant, b))
                comps.append(compare(a_runs, b_runs, variant, b, seed=w.opts.seed))
            w.add(f"- **{variant}**, {label}: {variant} {verdict_reason(comps)}")
            w.comparisons(comps)


def per_run(returns: np.ndarray, summary: MethodSummary, tail: bool) -> np.ndarray:
    """Per-run mean return: over all episodes, or over the summary's last 10%."""
    return run_means(returns, summary.episodes - summary.tail if tail else 0)
