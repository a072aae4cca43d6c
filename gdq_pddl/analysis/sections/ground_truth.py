"""Ground truth: V*, relevant areas and optimal routes per task, and learning as a
fraction of V*."""

from __future__ import annotations

import numpy as np

from gdq_pddl.analysis.data import TASKS_EXPERIMENT
from gdq_pddl.analysis.sections.writer import Writer, route_str
from gdq_pddl.analysis.stats import run_means


def write(w: Writer) -> None:
    study = w.study
    w.add("## Ground truth: V* and relevant areas", "")
    if not study.has(TASKS_EXPERIMENT):
        w.add("_The tasks experiment is missing: skipped._", "")
        return
    w.add("V* is the optimal expected return per episode from value iteration on the "
          "true model; relevant areas are those the optimal policy visits "
          "(`optimal.json` where given, else > 0.05 expected visits per episode).", "",
          "| Task | start -> goal | V* | relevant areas | irrelevant (computed) | "
          "irrelevant (paper) | optimal route (areas) |", "|---|---|--:|---|---|---|---|")
    pairs = [(TASKS_EXPERIMENT, t) for t in study.episodes.tasks(TASKS_EXPERIMENT)]
    for exp in study.switch_experiments:
        pairs += [(exp, t) for t in study.episodes.tasks(exp)
                  if t not in [task for _, task in pairs]]
    for exp, task in pairs:
        tr = study.truth(exp, task)
        t = study.task(exp, task)
        w.add(f"| {task} | {t.start} -> {t.goal} | {tr.v_star:.2f} | "
              f"{', '.join(map(str, tr.relevant_areas))} | "
              f"{', '.join(map(str, tr.irrelevant_areas)) or 'none'} | "
              f"{', '.join(map(str, tr.irrelevant_areas_paper)) or 'none'} | "
              f"{route_str(tr.optimal_route_areas)} |")
    w.add("")
    ep = study.episodes
    methods = ep.methods(TASKS_EXPERIMENT)
    fw = w.opts.final_window
    w.add(f"Learning as a fraction of V*: mean return over all episodes / V* "
          f"(over the last {fw} episodes in brackets), mean over runs.", "",
          "| Task | " + " | ".join(methods) + " |", "|---|" + "--:|" * len(methods))
    for task in ep.tasks(TASKS_EXPERIMENT):
        v = study.truth(TASKS_EXPERIMENT, task).v_star
        cells = []
        for m in methods:
            r = study.returns(TASKS_EXPERIMENT, m, task)
            if r.size == 0:
                cells.append("–")
                continue
            overall = float(np.nanmean(run_means(r))) / v
            last = float(np.nanmean(run_means(r, max(0, r.shape[1] - fw)))) / v
            cells.append(f"{overall:.2f} ({last:.2f})")
        w.add(f"| {task} | " + " | ".join(cells) + " |")
    w.add("")
    w.figure("fraction_of_vstar", "return as a fraction of V*")
