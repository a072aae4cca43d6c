"""Task C route finding: final greedy routes and behavioural convergence to the
paper's best route."""

from __future__ import annotations

import math

import numpy as np

from gdq_pddl.analysis.data import TASKS_EXPERIMENT
from gdq_pddl.analysis.routes import BEST_ROUTE_C
from gdq_pddl.analysis.sections.writer import Writer, fmt, route_str
from gdq_pddl.analysis.stats import convergence_episode


def write(w: Writer) -> None:
    study, opts = w.study, w.opts
    exp = TASKS_EXPERIMENT
    if not w.section("Task C: route finding",
                     study.has(exp) and "C" in study.episodes.tasks(exp),
                     "Task C routes", "Task C is not in the tasks experiment"):
        return
    world = study.world(exp)
    best = study.truth(exp, "C").optimal_route_areas
    w.add(f"The paper's best route is areas {route_str(BEST_ROUTE_C)}; the true "
          f"optimal policy's likeliest route is {route_str(best)}. A run's final "
          "greedy policy is walked from the start along each action's likeliest "
          "outcome (at most 30 steps). Convergence (behavioural, from `episodes.csv`): "
          f"the episode from which at least {opts.route_share:.0%} of the last "
          f"{opts.route_window} episodes succeed while visiting exactly the areas of "
          f"{route_str(BEST_ROUTE_C)}, to the end of the run.", "")
    w.figure("routes_C", "Task C greedy routes")
    have_policies = study.policies is not None
    if not have_policies:
        w.add("_No `policies.csv`: final greedy routes are not available._", "")
    w.add(f"| Method | final route {route_str(BEST_ROUTE_C)} | most common final route "
          "| converged runs | convergence episode (mean) |", "|---|--:|---|--:|--:|")
    ep = study.episodes
    for m in ep.methods(exp):
        summary = study.route_summary(exp, m, "C") if have_policies else None
        share, common = "–", "–"
        if summary is not None:
            on = summary.on_route(world, BEST_ROUTE_C)
            share = f"{on}/{summary.runs} ({on / summary.runs:.0%})"
            k = summary.count
            common = (f"{route_str(summary.areas)} ({summary.end}, {k} "
                      f"run{'s' if k != 1 else ''})")
        conv = convergence_episode(ep.area_visits(exp, m, "C"),
                                   ep.matrix("success", exp, m, "C"), BEST_ROUTE_C,
                                   ep.areas, opts.route_window, opts.route_share)
        reached = [c for c in conv if not math.isnan(c)]
        mean_conv = fmt(float(np.mean(reached)), 5) if reached else "never"
        w.add(f"| {m} | {share} | {common} | {len(reached)}/{len(conv)} | "
              f"{mean_conv} |")
    w.add("")
    gdq = convergence_episode(ep.area_visits(exp, "GDQ", "C"),
                              ep.matrix("success", exp, "GDQ", "C"), BEST_ROUTE_C,
                              ep.areas, opts.route_window, opts.route_share)
    if gdq:
        w.add("GDQ's convergence episode per run: "
              + ", ".join(fmt(c, 5) if not math.isnan(c) else "never" for c in gdq)
              + ".", "")
