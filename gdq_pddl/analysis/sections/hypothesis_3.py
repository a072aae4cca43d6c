"""Hypothesis III: GDQ adapts faster to a goal change (the switch experiments)."""

from __future__ import annotations

from gdq_pddl.analysis.sections.writer import Writer, milestone_str
from gdq_pddl.analysis.stats import compare, first_positive, run_means


def write(w: Writer) -> None:
    study, opts = w.study, w.opts
    exps = study.switch_experiments
    if not w.section("Hypothesis III: GDQ adapts faster to a goal change", bool(exps),
                     "Hypothesis III", "no switch experiment (switch-C-D, switch-C-E)"):
        return
    w.figure("switch_curves", "goal change")
    n = opts.switch_window
    w.add(f"Statistic: per-run mean return over the first {n} episodes after the "
          "switch (all of them if fewer). "
          "Recovery: the episode after the switch (1 = first episode of the "
          f"new task) at which the {opts.window}-episode moving average of the new "
          "task's returns first turns positive, on the mean curve (in brackets: mean "
          "over runs that reach it, and how many).", "")
    ep = study.episodes
    for exp in exps:
        tasks = ep.tasks(exp)
        if len(tasks) < 2:
            w.add(f"- {exp}: only task {', '.join(tasks)} in the data; skipped.", "")
            continue
        new = tasks[-1]
        variants = [v for v in w.variants(exp) if study.returns(exp, v, new).size]
        if "GDQ" not in variants:
            w.add(f"- {exp}: no GDQ runs; skipped.", "")
        for variant in variants:
            gdq = study.returns(exp, variant, new)
            comps = []
            for b in study.baselines(exp):
                base = study.returns(exp, b, new)
                if base.size:
                    comps.append(compare(run_means(gdq, 0, n), run_means(base, 0, n),
                                         variant, b, seed=opts.seed))
            w.verdict_line("III", f"{exp} ({' -> '.join(tasks)}, switch at episode "
                           f"{study.switch_episode(exp)})", comps,
                           f"Welch + bootstrap on per-run mean return, first {n} "
                           "episodes after the switch", variant)
            w.comparisons(comps)
        if not variants:
            continue
        parts = []
        for m in ep.methods(exp):
            ms = first_positive(study.returns(exp, m, new), opts.window)
            parts.append(f"{m} {milestone_str(ms)}")
        w.add("  Recovery episode: " + "; ".join(parts) + ".", "")
