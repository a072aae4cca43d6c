"""The robot protocol (simulated): returns, first successes and routes per trial."""

from __future__ import annotations

import math

import numpy as np

from gdq_pddl.analysis.data import ROBOT_EXPERIMENT
from gdq_pddl.analysis.figures import slug
from gdq_pddl.analysis.sections.writer import Writer, fmt, route_str
from gdq_pddl.analysis.stats import route_indicator, settles


def write(w: Writer) -> None:
    study, opts = w.study, w.opts
    exp = ROBOT_EXPERIMENT
    if not w.section("Robot protocol (simulated)", study.has(exp), "Robot protocol",
                     "the robot experiment is missing"):
        return
    ep = study.episodes
    tasks = ep.tasks(exp)
    task = tasks[-1]
    world = study.world(exp)
    truth = study.truth(exp, task)
    w.figure("robot_returns", "robot protocol, return per trial")
    w.figure(f"routes_robot_{slug(task)}", "robot greedy routes")
    w.figure(f"heatmap_robot_{slug(task)}", "robot area visits")
    w.add(f"Task {task} in `{world.name}`; V* = {truth.v_star:.1f}; optimal route "
          f"(areas) {route_str(truth.optimal_route_areas)}. A trial *follows the "
          "optimal route* when it succeeds visiting exactly those areas; the route "
          f"*becomes optimal* at the trial from which at least {opts.robot_share:.0%} "
          f"of the last {opts.robot_window} trials follow it, to the end.", "",
          "| Method | runs | mean return per trial | runs with a success | first "
          "success (mean trial) | trial route becomes optimal (per run) | final "
          "greedy route optimal |", "|---|--:|--:|--:|--:|---|--:|")
    for m in ep.methods(exp):
        ret = study.returns(exp, m, task)
        success = ep.matrix("success", exp, m, task)
        if ret.size == 0:
            continue
        n = ret.shape[0]
        succ_runs = int(np.sum(np.nansum(success, axis=1) > 0))
        firsts = [float(np.flatnonzero(row > 0)[0] + 1) for row in success
                  if np.any(row > 0)]
        ind = route_indicator(ep.area_visits(exp, m, task), success,
                              truth.optimal_route_areas, ep.areas)
        conv = [settles(row, opts.robot_window, opts.robot_share) for row in ind]
        conv_txt = ", ".join("never" if math.isnan(c) else str(int(c)) for c in conv)
        summary = study.route_summary(exp, m, task)
        final = "–"
        if summary is not None:
            final = f"{summary.on_route(world, truth.optimal_route_areas)}/{summary.runs}"
        w.add(f"| {m} | {n} | {np.nanmean(ret):.1f} | {succ_runs}/{n} | "
              f"{fmt(float(np.mean(firsts)), 3) if firsts else 'none'} | {conv_txt} | "
              f"{final} |")
    w.add("")
    if "Dyna-Q" in ep.methods(exp):
        success = ep.matrix("success", exp, "Dyna-Q", task)
        k = int(np.sum(np.nansum(success, axis=1) > 0))
        w.add(f"Dyna-Q reached the goal at least once within {success.shape[1]} trials "
              f"in {k} of {success.shape[0]} runs"
              + (" (the paper: no meaningful solution in 30 trials)." if k == 0
                 else " (the paper reports no meaningful solution in 30 trials)."), "")
