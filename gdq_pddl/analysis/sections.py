"""The paper's sections of ``REPORT.md``, each a ``write_<name>(w)`` on a :class:`Writer`:
its hypotheses on its ``tasks``, ``switch-*`` and ``robot`` experiments, the ground truth,
Task C's routes and GDQ against its variants. The sections any folder gets (the header,
*Methods compared* for any other experiment, the IQM table) are in
:mod:`gdq_pddl.analysis.generic`."""

from __future__ import annotations

import math

import numpy as np

from gdq_pddl.analysis.generic import say, write_iqm
from gdq_pddl.analysis.stats import (
    compare,
    first_positive,
    mean_se,
    route_settles,
    run_means,
    verdict,
    verdict_reason,
)
from gdq_pddl.analysis.study import slug
from gdq_pddl.analysis.tables import area_markdown, area_table
from gdq_pddl.analysis.writer import (
    TABLE_DIR,
    Writer,
    areas_str,
    fmt,
    milestone_str,
    pct,
    route_str,
)
from gdq_pddl.experiments.probes import optinit_values
from gdq_pddl.experiments.protocol import GDQ_VARIANTS
from gdq_pddl.experiments.results import ROBOT_EXPERIMENT, TASKS_EXPERIMENT, optimal_entry
from gdq_pddl.learners import registry

__all__ = ["BEST_ROUTE_C", "write_ground_truth", "write_hypothesis_1", "write_hypothesis_2",
           "write_hypothesis_3", "write_robot", "write_route_c", "write_variants",
           "write_why_gdq_fails"]


def write_ground_truth(w: Writer) -> None:
    """Ground truth: V*, relevant areas and optimal routes per task, and learning as a
fraction of V*."""
    study, exp = w.study, TASKS_EXPERIMENT
    w.add("## Ground truth: V* and relevant areas", "")
    if not study.has(exp):
        w.add("_The tasks experiment is missing: skipped._", "")
        return
    w.add(say("ground_truth"), "")
    pairs = {t: exp for t in study.tasks(exp)}
    for switch in study.switch_experiments:
        pairs |= {t: switch for t in study.tasks(switch) if t not in pairs}
    rows = []
    for task, e in pairs.items():
        tr, t = study.truth(e, task), study.task(e, task)
        info = optimal_entry(study.optimal, task, study.config.world_spec(e))
        goal = (f"{info['goal_v_star_policy']:.3f} / {info['goal_no_limit']:.3f}"
                if "goal_no_limit" in info else "–")
        rows.append([task, f"{t.start} -> {t.goal}", f"{tr.v_star:.2f}", goal,
                     ", ".join(map(str, tr.relevant_areas)), areas_str(tr.irrelevant_areas),
                     areas_str(tr.irrelevant_areas_paper), route_str(tr.optimal_route_areas)])
    w.table(rows, ["Task", "start -> goal", "V*", "goal: V*'s policy / no limit",
                   "relevant areas", "irrelevant (computed)", "irrelevant (paper)",
                   "optimal route (areas)"], "llrrllll")
    w.add("The goal column: the probability that V*'s policy reaches the goal within the "
          "step limit, and the most any policy has with no step limit (value iteration on "
          "the same true model; – where `optimal.json` does not have them).", "")
    methods, fw = study.methods(exp), w.opts.final_window

    def fraction(task: str, m: str) -> str:
        r, v = study.returns(exp, m, task), study.truth(exp, task).v_star
        if r.size == 0:
            return "–"
        return (f"{np.nanmean(run_means(r)) / v:.2f} "
                f"({np.nanmean(run_means(r, max(0, r.shape[1] - fw))) / v:.2f})")

    w.add(f"Learning as a fraction of V*: mean return over all episodes / V* "
          f"(over the last {fw} episodes in brackets), mean over runs.", "")
    w.table([[t, *(fraction(t, m) for m in methods)] for t in study.tasks(exp)],
            ["Task", *methods])
    write_iqm(w, [(exp, t) for t in study.tasks(exp)])
    w.figure("fraction_of_vstar", "return as a fraction of V*")


def write_hypothesis_1(w: Writer) -> None:
    """Hypothesis I: GDQ collects more reward (tasks A-D), and when the moving average of
return first turns positive."""
    study, opts, exp = w.study, w.opts, TASKS_EXPERIMENT
    if not w.section("Hypothesis I: GDQ collects more reward (tasks A-D)", study.has(exp),
                     "Hypothesis I", "the tasks experiment (A-D) is missing"):
        return
    w.figure("learning_curves", "learning curves, tasks A-D")
    w.add("Statistic: per-run mean return over all episodes of the task (the "
          "cumulative reward of a run divided by its episodes).", "")
    for task in study.tasks(exp):
        variants = [v for v in w.variants(exp) if study.returns(exp, v, task).size]
        if "GDQ" not in variants:
            w.add(f"- {task}: no GDQ runs; skipped.")
        for variant in variants:
            w.test("I", f"Task {task}", "Welch + bootstrap on per-run mean return", variant,
                   exp, lambda m, t=task: run_means(study.returns(exp, m, t)))
            if opts.early_window < study.returns(exp, variant, task).shape[1]:
                a = run_means(study.returns(exp, variant, task), 0, opts.early_window)
                early = [compare(a, run_means(study.returns(exp, b, task), 0,
                                              opts.early_window), variant, b, seed=opts.seed)
                         for b in study.baselines(exp) if study.returns(exp, b, task).size]
                w.add(f"  First {opts.early_window} episodes only (verdict "
                      f"{verdict(early)}: {variant} {verdict_reason(early)}):")
                w.comparisons(early)
    methods = study.methods(exp)
    w.add(say("milestones", window=opts.window), "")
    w.table([[t, *(milestone_str(first_positive(study.returns(exp, m, t), opts.window))
                   for m in methods)] for t in study.tasks(exp)], ["Task", *methods])


def write_hypothesis_2(w: Writer) -> None:
    """Hypothesis II: GDQ avoids irrelevant areas."""
    study, exp = w.study, TASKS_EXPERIMENT
    if not w.section("Hypothesis II: GDQ avoids irrelevant areas", study.has(exp),
                     "Hypothesis II", "the tasks experiment (A-D) is missing"):
        return
    table = area_table(study)
    w.add(say("areas", table_dir=TABLE_DIR), "", area_markdown(table), say("h2"), "")
    areas = study.areas
    for task in study.tasks(exp):
        variants = [v for v in w.variants(exp) if study.area_visits(exp, v, task).size]
        if "GDQ" not in variants:
            w.add(f"- {task}: no GDQ runs; skipped.")
        for label, irr in (("paper", table.irrelevant_paper[task]),
                           ("computed", table.irrelevant_computed[task])):
            cols = [areas.index(a) for a in irr if a in areas]
            case = f"Task {task}, {label} irrelevant areas {{{', '.join(map(str, irr))}}}"
            if not cols:
                if variants:
                    w.add(f"- {case}: no irrelevant areas; nothing to test.", "")
                continue
            for variant in variants:
                fewest = sum(bool(table.frame.loc[(task, variant), f"area_{a}_bold"])
                             for a in irr if a in areas)
                w.test("II", case, "Welch + bootstrap on per-run visits to those areas",
                       variant, exp, lambda m, t=task, c=cols: np.nansum(
                           study.area_visits(exp, m, t)[..., c], axis=(1, 2)),
                       higher_is_better=False, unit=" visits", note=f"{variant} has the "
                       f"fewest visits in {fewest} of {len(cols)} of these areas.")
    for task in study.tasks(exp):
        w.figure(f"heatmap_{slug(task)}", f"area visits, task {task}")


def write_hypothesis_3(w: Writer) -> None:
    """Hypothesis III: GDQ adapts faster to a goal change (the switch experiments)."""
    study, opts = w.study, w.opts
    exps = study.switch_experiments
    if not w.section("Hypothesis III: GDQ adapts faster to a goal change", bool(exps),
                     "Hypothesis III", "no switch experiment (switch-C-D, switch-C-E)"):
        return
    w.figure("switch_curves", "goal change")
    n = opts.switch_window
    w.add(say("h3", n=n, window=opts.window), "")
    for exp in exps:
        tasks = study.tasks(exp)
        if len(tasks) < 2:
            w.add(f"- {exp}: only task {', '.join(tasks)} in the data; skipped.", "")
            continue
        new = tasks[-1]
        variants = [v for v in w.variants(exp) if study.returns(exp, v, new).size]
        if "GDQ" not in variants:
            w.add(f"- {exp}: no GDQ runs; skipped.", "")
        for variant in variants:
            w.test("III", f"{exp} ({' -> '.join(tasks)}, switch at episode "
                   f"{study.switch_episode(exp)})", f"Welch + bootstrap on per-run mean "
                   f"return, first {n} episodes after the switch", variant, exp,
                   lambda m, e=exp, t=new: run_means(study.returns(e, m, t), 0, n))
        if variants:
            w.add("  Recovery episode: " + "; ".join(
                f"{m} {milestone_str(first_positive(study.returns(exp, m, new), opts.window))}"
                for m in study.methods(exp)) + ".", "")


BEST_ROUTE_C = (1, 3, 2, 6)
"""The paper's best Task C route in areas (easy doors d1 and d3)."""


def write_route_c(w: Writer) -> None:
    """Task C route finding: final greedy routes and behavioural convergence to the
paper's best route."""
    study, opts, exp = w.study, w.opts, TASKS_EXPERIMENT
    if not w.section("Task C: route finding",
                     study.has(exp) and "C" in study.tasks(exp),
                     "Task C routes", "Task C is not in the tasks experiment"):
        return
    world = study.world(exp)
    best = study.truth(exp, "C").optimal_route_areas
    w.add(say("route_c", paper=route_str(BEST_ROUTE_C), best=route_str(best),
              share=f"{opts.route_share:.0%}", window=opts.route_window), "")
    w.figure("routes_C", "Task C greedy routes")
    if study.policies is None:
        w.add("_No `policies.csv`: final greedy routes are not available._", "")
    rows, conv = [], {}
    for m in study.methods(exp):
        summary = study.route_summary(exp, m, "C") if study.policies is not None else None
        share = common = "–"
        if summary is not None:
            on, k = summary.on_route(world, BEST_ROUTE_C), summary.count
            share = f"{on}/{summary.runs} ({on / summary.runs:.0%})"
            common = f"{route_str(summary.areas)} ({summary.end}, {k} run{'s' * (k != 1)})"
        conv[m] = route_settles(study.area_visits(exp, m, "C"), study.matrix(
            "success", exp, m, "C"), BEST_ROUTE_C, study.areas, opts.route_window,
            opts.route_share)
        reached = [c for c in conv[m] if not math.isnan(c)]
        rows.append([m, share, common, f"{len(reached)}/{len(conv[m])}",
                     fmt(float(np.mean(reached)), 5) if reached else "never"])
    w.table(rows, ["Method", f"final route {route_str(BEST_ROUTE_C)}", "most common final "
                   "route", "converged runs", "convergence episode (mean)"], "lrlrr")
    if conv.get("GDQ"):
        w.add("GDQ's convergence episode per run: " + ", ".join(
            fmt(c, 5) if not math.isnan(c) else "never" for c in conv["GDQ"]) + ".", "")


def write_variants(w: Writer) -> None:
    """GDQ against the two readings of the paper's GDQ (GDQ-literal, GDQ-code), task by
task."""
    study, exp = w.study, TASKS_EXPERIMENT
    methods = study.methods(exp) if study.has(exp) else []
    others = [m for m in registry.variants_of(registry.REFERENCE)[1:] if m in methods]
    if not w.section("GDQ vs the paper read literally (GDQ-literal) and the authors' code "
                     "(GDQ-code)", "GDQ" in methods and bool(others), "GDQ vs its variants",
                     "the tasks experiment lacks GDQ or both of its variants"):
        return
    w.add("Mean return per episode over all episodes, mean (SE) over runs; each "
          "difference is GDQ minus the variant, with its bootstrap 95% CI and Welch p.", "")
    rows = []
    for task in study.tasks(exp):
        a = run_means(study.returns(exp, "GDQ", task))
        if a.size == 0:
            continue
        cells = [task, "{:.2f} ({:.2f})".format(*mean_se(a))]
        for m in others:
            b = run_means(study.returns(exp, m, task))
            c = compare(a, b, "GDQ", m, seed=w.opts.seed)
            cells += ["–", "–", "–"] if b.size == 0 else [
                "{:.2f} ({:.2f})".format(*mean_se(b)),
                f"{c.diff:+.2f} [{c.ci_low:+.2f}, {c.ci_high:+.2f}]", fmt(c.p)]
        rows.append(cells)
    w.table(rows, ["Task", "GDQ", *(x for m in others for x in (m, f"GDQ - {m} (95% CI)", "p"))])


def write_why_gdq_fails(w: Writer) -> None:
    """Measured evidence for the literal reading's failure: Q right after OptInit and
    how episodes end."""
    study, exp = w.study, TASKS_EXPERIMENT
    if not w.section("Why the paper's GDQ read literally fails here",
                     study.has(exp) and bool(set(GDQ_VARIANTS) & set(study.methods(exp))),
                     "Why GDQ-literal fails", "the tasks experiment has no GDQ runs"):
        return
    tasks = study.tasks(exp)
    task = "C" if "C" in tasks else tasks[0]
    init = optinit_values(study.config, exp, study.world(exp), study.task(exp, task))
    r_max, gamma = init.r_max, init.gamma
    bound = r_max / (1 - gamma)
    w.add(say("optinit", task=task, r_max=f"{r_max:g}", gamma=f"{gamma:g}", bound=bound,
              gbound=gamma * bound), "")
    w.table([[m, f"{g:.4g}", f"{med:.4g}", n] for m, (g, med, n) in init.values.items()],
            ["Variant", "Q(s0, greedy action)", "median Q(s0, ·)", "actions at s0"])
    limit = study.world(exp).step_limit
    w.add(say("ends", tasks=tasks, limit=limit), "")
    df = study.rows(exp)
    ends = df.assign(timeout=(df["steps"] == limit) & (df["success"] == 0),
                     goal=df["success"] > 0).groupby("method", observed=True)[
                         ["timeout", "goal", "return"]].mean().loc[study.methods(exp)]
    shares = ends["timeout"].to_dict()
    w.table([[m, f"{e.timeout:.1%}", f"{e.goal:.1%}", f"{e['return']:.2f}"]
             for m, e in ends.iterrows()],
            ["Method", "step limit, no goal", "goal reached", "mean return"])
    paper = init.values.get("GDQ-literal")
    if paper is not None:
        timeout = shares.get("GDQ-literal", math.nan)
        w.add(say("mechanism", bound=bound, greedy=paper[0], median=paper[1], r_max=f"{r_max:g}",
                  alpha=f"{init.alpha:g}", decay=f"{init.alpha * (1 - gamma):.2%}",
                  literal=pct(timeout), code=pct(shares.get("GDQ-code", math.nan)),
                  gdq=pct(shares.get("GDQ", math.nan))), "")


def write_robot(w: Writer) -> None:
    """The robot protocol (simulated): returns, first successes and routes per trial."""
    study, opts, exp = w.study, w.opts, ROBOT_EXPERIMENT
    if not w.section("Robot protocol (simulated)", study.has(exp), "Robot protocol",
                     "the robot experiment is missing"):
        return
    task = study.tasks(exp)[-1]
    world = study.world(exp)
    truth = study.truth(exp, task)
    w.figure("robot_returns", "robot protocol, return per trial")
    w.figure(f"routes_robot_{slug(task)}", "robot greedy routes")
    w.figure(f"heatmap_robot_{slug(task)}", "robot area visits")
    w.add(say("robot", task=task, world=world.name, v_star=truth.v_star,
              route=route_str(truth.optimal_route_areas), share=f"{opts.robot_share:.0%}",
              window=opts.robot_window), "")
    rows = []
    for m in study.methods(exp):
        ret, success = study.returns(exp, m, task), study.matrix("success", exp, m, task)
        if ret.size == 0:
            continue
        n, firsts = ret.shape[0], [np.argmax(row > 0) + 1.0 for row in success if any(row > 0)]
        conv = route_settles(study.area_visits(exp, m, task), success,
                             truth.optimal_route_areas, study.areas, opts.robot_window,
                             opts.robot_share)
        summary = study.route_summary(exp, m, task)
        rows.append([m, n, f"{np.nanmean(ret):.1f}", f"{len(firsts)}/{n}",
                     fmt(float(np.mean(firsts)), 3) if firsts else "none",
                     ", ".join("never" if math.isnan(c) else str(int(c)) for c in conv),
                     "–" if summary is None else
                     f"{summary.on_route(world, truth.optimal_route_areas)}/{summary.runs}"])
    w.table(rows, ["Method", "runs", "mean return per trial", "runs with a success",
                   "first success (mean trial)", "trial route becomes optimal (per run)",
                   "final greedy route optimal"], "lrrrrlr")
    if "Dyna-Q" in study.methods(exp):
        success = study.matrix("success", exp, "Dyna-Q", task)
        k = int(np.sum(np.nansum(success, axis=1) > 0))
        w.add(f"Dyna-Q reached the goal at least once within {success.shape[1]} trials "
              f"in {k} of {success.shape[0]} runs"
              + (" (the paper: no meaningful solution in 30 trials)." if k == 0
                 else " (the paper reports no meaningful solution in 30 trials)."), "")
