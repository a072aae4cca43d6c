"""Why the paper's GDQ read literally fails: the Q values of every GDQ variant right after
OptInit (measured by building the learners as the experiment did) and how episodes end."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gdq_pddl.analysis.data import TASKS_EXPERIMENT
from gdq_pddl.analysis.sections.writer import Writer, pct
from gdq_pddl.analysis.study import Study
from gdq_pddl.experiments.protocol import GDQ_VARIANTS


def write(w: Writer) -> None:
    """Measured evidence for the literal reading's failure: Q right after OptInit and
    how episodes end."""
    study = w.study
    exp = TASKS_EXPERIMENT
    if not w.section("Why the paper's GDQ read literally fails here",
                     study.has(exp) and bool(set(GDQ_VARIANTS) & set(study.methods(exp))),
                     "Why GDQ-literal fails", "the tasks experiment has no GDQ runs"):
        return
    tasks = study.episodes.tasks(exp)
    task = "C" if "C" in tasks else tasks[0]
    init = optinit_values(study, exp, task)
    r_max, gamma = init.r_max, init.gamma
    bound = r_max / (1 - gamma)
    w.add(f"Q values at the start state of Task {task} right after OptInit, measured "
          "by building each learner as the experiment did (before any episode); "
          f"R_max = {r_max:g}, gamma = {gamma:g}, so R_max / (1 - gamma) = "
          f"{bound:.4g} and gamma R_max / (1 - gamma) = {gamma * bound:.4g}.", "",
          "| Variant | Q(s0, greedy action) | median Q(s0, ·) | actions at s0 |",
          "|---|--:|--:|--:|")
    for method, (greedy, median, n) in init.values.items():
        w.add(f"| {method} | {greedy:.4g} | {median:.4g} | {n} |")
    w.add("")
    ep = study.episodes
    limit = study.world(exp).step_limit
    methods = study.methods(exp)
    w.add(f"How episodes end (tasks {', '.join(tasks)}, all episodes of all runs): the "
          f"share that run out of the {limit}-step limit without reaching the goal "
          f"(steps = {limit} and success = 0), and the share that reach the goal.", "",
          "| Method | step limit, no goal | goal reached | mean return |",
          "|---|--:|--:|--:|")
    shares = {}
    for m in methods:
        rows = ep.mask(exp, m)
        steps, success = ep.values["steps"][rows], ep.values["success"][rows]
        timeout = float(np.mean((steps == limit) & (success == 0)))
        shares[m] = timeout
        w.add(f"| {m} | {timeout:.1%} | {float(np.mean(success > 0)):.1%} | "
              f"{float(np.mean(ep.values['return'][rows])):.2f} |")
    w.add("")
    paper = init.values.get("GDQ-literal")
    if paper is not None:
        timeout = shares.get("GDQ-literal", math.nan)
        w.add(
            "**Mechanism.** Algorithm 1's optimistic model sends every pair back to s0 "
            "without ending the episode, so policy iteration values the plan pairs at "
            f"R_max / (1 - gamma) = {bound:.4g} and every other pair at about gamma times "
            f"that (measured: greedy {paper[0]:.4g}, median {paper[1]:.4g}), far above any "
            f"real return (at most R_max = {r_max:g}). Reaching the goal ends the episode "
            f"with a target of at most {r_max:g}, which *lowers* the value of the pair "
            "that got there relative to the inflated bootstrap of pairs that keep the "
            "episode going, so the greedy policy learns to avoid the goal; with "
            f"alpha = {init.alpha:g} the excess decays by only about "
            f"{init.alpha * (1 - gamma):.2%} per visit (alpha (1 - gamma)). Measured: "
            f"{pct(timeout)} of GDQ-literal's episodes end at the step limit without "
            f"the goal, against {pct(shares.get('GDQ-code', math.nan))} for GDQ-code, "
            "whose OptInit gives R_max only to the plan pairs (no policy iteration), and "
            f"{pct(shares.get('GDQ', math.nan))} for GDQ, whose optimistic model is "
            "the knowledge itself: a plan pair leads where the planner says, reaching "
            "the goal pays R_max and ends the episode, so its values are what a run "
            "of the shortest plan would return if every action worked.", "")


@dataclass(frozen=True)
class OptInitValues:
    """Q at the start state right after OptInit, per GDQ variant (see
    :func:`optinit_values`)."""

    task: str
    r_max: float
    gamma: float
    alpha: float
    values: dict[str, tuple[float, float, int]]
    """Method -> (Q(s0, greedy action), median Q(s0, ·), number of actions)."""


def optinit_values(study: Study, experiment: str, task: str) -> OptInitValues:
    """Build each GDQ variant for ``task`` with the experiment's hyperparameters and
    planner (as the runner does) and read Q(s0, ·) before any episode."""
    from gdq_pddl.experiments.protocol import Hyper
    from gdq_pddl.experiments.work import make_learner
    from gdq_pddl.learners import office_task_context

    entry = next((e for e in study.config.experiments if e.get("name") == experiment
                  and any(t == task for t, _ in e.get("schedule") or [])),
                 study.config.experiment(experiment))
    raw = entry.get("hyper") if isinstance(entry.get("hyper"), dict) else {}
    hyper = Hyper(**{k: float(v) for k, v in raw.items() if k in ("alpha", "gamma", "epsilon")})
    planner = entry.get("planner") if isinstance(entry.get("planner"), str) else "graph"
    ctx = office_task_context(study.world(experiment), study.task(experiment, task), planner)
    values = {}
    for method in GDQ_VARIANTS:
        learner = make_learner(method, ctx, hyper)
        q = learner.q[ctx.s0]
        greedy = int(learner.greedy_policy()[ctx.s0])
        values[method] = (float(q[greedy]), float(np.median(q)), int(q.size))
    return OptInitValues(task, float(ctx.r_max), hyper.gamma, hyper.alpha, values)
