"""GDQ against the two readings of the paper's GDQ (GDQ-literal, GDQ-code), task by
task."""

from __future__ import annotations

from gdq_pddl.analysis.data import TASKS_EXPERIMENT
from gdq_pddl.analysis.sections.writer import Writer, fmt
from gdq_pddl.analysis.stats import compare, mean_se, run_means

OTHERS = ("GDQ-literal", "GDQ-code")


def write(w: Writer) -> None:
    study = w.study
    exp = TASKS_EXPERIMENT
    methods = study.methods(exp) if study.has(exp) else []
    others = [m for m in OTHERS if m in methods]
    if not w.section("GDQ vs the paper read literally (GDQ-literal) and the authors' code "
                     "(GDQ-code)", "GDQ" in methods and bool(others), "GDQ vs its variants",
                     "the tasks experiment lacks GDQ or both of its variants"):
        return
    w.add("Mean return per episode over all episodes, mean (SE) over runs; each "
          "difference is GDQ minus the variant, with its bootstrap 95% CI and Welch p.", "",
          "| Task | GDQ | " + " | ".join(f"{m} | GDQ - {m} (95% CI) | p" for m in others)
          + " |", "|---|--:|" + "--:|--:|--:|" * len(others))
    for task in study.episodes.tasks(exp):
        a = run_means(study.returns(exp, "GDQ", task))
        if a.size == 0:
            continue
        ma, sa = mean_se(a)
        cells = [f"{ma:.2f} ({sa:.2f})"]
        for m in others:
            b = run_means(study.returns(exp, m, task))
            if b.size == 0:
                cells += ["–", "–", "–"]
                continue
            c = compare(a, b, "GDQ", m, seed=w.opts.seed)
            mb, sb = mean_se(b)
            cells += [f"{mb:.2f} ({sb:.2f})", f"{c.diff:+.2f} [{c.ci_low:+.2f}, "
                      f"{c.ci_high:+.2f}]", fmt(c.p)]
        w.add(f"| {task} | " + " | ".join(cells) + " |")
    w.add("")
