"""Hypothesis II: GDQ avoids irrelevant areas."""

from __future__ import annotations

from gdq_pddl.analysis.data import TASKS_EXPERIMENT
from gdq_pddl.analysis.figures import slug
from gdq_pddl.analysis.sections.writer import TABLE_DIR, Writer
from gdq_pddl.analysis.stats import compare
from gdq_pddl.analysis.tables import area_table, run_area_totals, to_markdown


def write(w: Writer) -> None:
    study = w.study
    if not w.section("Hypothesis II: GDQ avoids irrelevant areas",
                     study.has(TASKS_EXPERIMENT), "Hypothesis II",
                     "the tasks experiment (A-D) is missing"):
        return
    table = area_table(study)
    w.add("Area visits summed over a run, mean (SE) over runs; bold: fewest visits "
          "among the methods in an area irrelevant by either definition. "
          f"(Also in `{TABLE_DIR}/area_visits.md`, `.tex`, `.csv`.)", "",
          to_markdown(table))
    w.add("Statistic: per run, the visits to the task's irrelevant areas summed over "
          "the run (fewer is better), for the paper's and for the computed set.", "")
    areas = study.episodes.areas
    for task in study.episodes.tasks(TASKS_EXPERIMENT):
        totals = {v: run_area_totals(study, v, task)
                  for v in w.variants(TASKS_EXPERIMENT)}
        totals = {v: t for v, t in totals.items() if t.shape[0]}
        if "GDQ" not in totals:
            w.add(f"- {task}: no GDQ runs; skipped.")
        for label, irr in (("paper", table.irrelevant_paper[task]),
                           ("computed", table.irrelevant_computed[task])):
            cols = [areas.index(a) for a in irr if a in areas]
            case = f"Task {task}, {label} irrelevant areas {{{', '.join(map(str, irr))}}}"
            if not cols:
                if totals:
                    w.add(f"- {case}: no irrelevant areas; nothing to test.", "")
                continue
            for variant, gdq in totals.items():
                comps = []
                for b in study.baselines(TASKS_EXPERIMENT):
                    base = run_area_totals(study, b, task)
                    if base.shape[0]:
                        comps.append(compare(gdq[:, cols].sum(axis=1),
                                             base[:, cols].sum(axis=1), variant, b,
                                             higher_is_better=False, seed=w.opts.seed))
                w.verdict_line("II", case, comps,
                               "Welch + bootstrap on per-run visits to those areas",
                               variant)
                fewest = sum(row.bold[areas.index(a)] for row in table.rows
                             if row.task == task and row.method == variant for a in irr
                             if a in areas)
                w.add(f"  {variant} has the fewest visits in {fewest} of {len(cols)} "
                      "of these areas.")
                w.comparisons(comps, " visits")
    for task in study.episodes.tasks(TASKS_EXPERIMENT):
        w.figure(f"heatmap_{slug(task)}", f"area visits, task {task}")
