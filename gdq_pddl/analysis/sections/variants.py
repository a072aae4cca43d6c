"""The paper's GDQ against the authors'-code variant (GDQ-code), task by task."""

from __future__ import annotations

from gdq_pddl.analysis.data import TASKS_EXPERIMENT
from gdq_pddl.analysis.sections.writer import Writer, fmt
from gdq_pddl.analysis.stats import compare, mean_se, run_means


def write(w: Writer) -> None:
    study = w.study
    exp = TASKS_EXPERIMENT
    methods = study.methods(exp) if study.has(exp) else []
    if not w.section("The paper's GDQ vs the authors'-code variant (GDQ-code)",
                     "GDQ" in methods and "GDQ-code" in methods, "GDQ vs GDQ-code",
                     "the tasks experiment lacks GDQ or GDQ-code"):
        return
    w.add("Mean return per episode over all episodes, mean (SE) over runs; the "
          "difference is GDQ - GDQ-code.", "",
          "| Task | GDQ | GDQ-code | difference (95% CI) | Welch p |",
          "|---|--:|--:|--:|--:|")
    for task in study.episodes.tasks(exp):
        a = run_means(study.returns(exp, "GDQ", task))
        b = run_means(study.returns(exp, "GDQ-code", task))
        if a.size == 0 or b.size == 0:
            continue
        c = compare(a, b, "GDQ", "GDQ-code", seed=w.opts.seed)
        (ma, sa), (mb, sb) = mean_se(a), mean_se(b)
        w.add(f"| {task} | {ma:.2f} ({sa:.2f}) | {mb:.2f} ({sb:.2f}) | "
              f"{c.diff:+.2f} [{c.ci_low:+.2f}, {c.ci_high:+.2f}] | {fmt(c.p)} |")
    w.add("")
