"""Hypothesis I: GDQ collects more reward (tasks A-D), and when the moving average of
return first turns positive."""

from __future__ import annotations

from gdq_pddl.analysis.data import TASKS_EXPERIMENT
from gdq_pddl.analysis.sections.writer import Writer, milestone_str
from gdq_pddl.analysis.stats import compare, first_positive, run_means, verdict, verdict_reason


def write(w: Writer) -> None:
    study, opts = w.study, w.opts
    if not w.section("Hypothesis I: GDQ collects more reward (tasks A-D)",
                     study.has(TASKS_EXPERIMENT), "Hypothesis I",
                     "the tasks experiment (A-D) is missing"):
        return
    w.figure("learning_curves", "learning curves, tasks A-D")
    ep = study.episodes
    w.add("Statistic: per-run mean return over all episodes of the task (the "
          "cumulative reward of a run divided by its episodes).", "")
    for task in ep.tasks(TASKS_EXPERIMENT):
        variants = [v for v in w.variants(TASKS_EXPERIMENT)
                    if study.returns(TASKS_EXPERIMENT, v, task).size]
        if "GDQ" not in variants:
            w.add(f"- {task}: no GDQ runs; skipped.")
        for variant in variants:
            gdq = study.returns(TASKS_EXPERIMENT, variant, task)
            comps, early = [], []
            for b in study.baselines(TASKS_EXPERIMENT):
                base = study.returns(TASKS_EXPERIMENT, b, task)
                if base.size == 0:
                    continue
                comps.append(compare(run_means(gdq), run_means(base), variant, b,
                                     seed=opts.seed))
                early.append(compare(run_means(gdq, 0, opts.early_window),
                                     run_means(base, 0, opts.early_window), variant, b,
                                     seed=opts.seed))
            w.verdict_line("I", f"Task {task}", comps,
                           "Welch + bootstrap on per-run mean return", variant)
            w.comparisons(comps)
            if opts.early_window < gdq.shape[1]:
                w.add(f"  First {opts.early_window} episodes only (verdict "
                      f"{verdict(early)}: {variant} {verdict_reason(early)}):")
                w.comparisons(early)
    milestones(w)


def milestones(w: Writer) -> None:
    study, window = w.study, w.opts.window
    ep = study.episodes
    methods = ep.methods(TASKS_EXPERIMENT)
    w.add(f"Episode at which the {window}-episode moving average of return first turns "
          "positive: on the mean curve over runs; in brackets the mean over the "
          "runs that reach it and how many do.", "",
          "| Task | " + " | ".join(methods) + " |", "|---|" + "--:|" * len(methods))
    for task in ep.tasks(TASKS_EXPERIMENT):
        cells = []
        for m in methods:
            r = study.returns(TASKS_EXPERIMENT, m, task)
            ms = first_positive(r, window)
            cells.append(milestone_str(ms))
        w.add(f"| {task} | " + " | ".join(cells) + " |")
    w.add("")
