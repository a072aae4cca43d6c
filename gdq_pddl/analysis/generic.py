"""The report's sections that any output folder gets, each a ``write_<name>(w)`` on a
:class:`Writer`: the header (configuration, versions, planners; :func:`setup_lines` for a
run report), *Methods compared* (:func:`write_methods`, a task at a time with a PDDL
problem's facts) for every experiment without a paper section, and the IQM of return / V*
over tasks (:func:`write_iqm`); :func:`say` renders a paragraph of the templates. The
paper's sections are in :mod:`gdq_pddl.analysis.sections`."""

from __future__ import annotations

import math

import pandas as pd

from gdq_pddl.analysis.stats import (
    ALPHA,
    compare,
    first_positive,
    iqm_ci,
    run_means,
    verdict_reason,
)
from gdq_pddl.analysis.study import Study, curves_stem
from gdq_pddl.analysis.writer import TEMPLATES, Writer, milestone_str, number, pct
from gdq_pddl.errors import PlanningError
from gdq_pddl.experiments.results import optimal_entry
from gdq_pddl.learners import DarlingConfig, registry
from gdq_pddl.planning import get_planner


def say(paragraph: str, **data) -> str:
    """A paragraph of the report: macro ``paragraph`` of ``templates/sections.md.j2``."""
    return str(getattr(TEMPLATES.get_template("sections.md.j2").module, paragraph)(**data))[:-1]


def write_header(w: Writer) -> None:
    """Output folder, configuration, versions and the method paragraph."""
    cfg, study = w.study.config, w.study
    w.add("# Experiment report", "",
          f"Output folder: `{w.out_dir}`; {len(study.results)} episodes in `episodes.csv`; "
          f"experiments: {', '.join(study.experiments) or 'none'}.", "")
    if cfg.experiments:
        w.table([[e.get("name", "?"), e.get("world", "?"), ", ".join(
            f"{t} x {n}" for t, n in (e.get("schedule") if isinstance(
                e.get("schedule"), list) else [])) or "?",
            ", ".join(e.get("methods") or []) or "?", e.get("runs", "?"), e.get("seed", "?")]
            for e in cfg.experiments],
            ["experiment", "world", "schedule (task x episodes)", "methods", "runs", "seed"],
            "llllrr")
    else:
        w.add("Configuration: not recorded (no readable `config.json`).", "")
    if cfg.versions:
        w.add("Versions: " + ", ".join(f"{k} {v}" for k, v in cfg.versions.items()), "")
    w.add(*planner_lines(study), say("method", seed=w.opts.seed, alpha=ALPHA,
                                     window=w.opts.window), "")


def setup_lines(study: Study) -> list[str]:
    """What produced the folder, per experiment (from ``config.json``), then the
    planners (:func:`planner_lines`)."""
    lines = [f"- `{e.get('name')}`: methods {', '.join(e.get('methods') or []) or '?'}; "
             f"{e.get('runs', '?')} runs; seed {e.get('seed', '?')}; planner "
             f"`{e.get('planner', '?')}`; world `{e.get('world', '?')}`"
             for e in study.config.experiments] or ["Configuration: not recorded."]
    return [*lines, "", *planner_lines(study)][:-1]


def planner_lines(study: Study) -> list[str]:
    """The planner backends that made the knowledge's plans, the plan tolerance, and a
    warning for a backend that returns one plan per query (GDQ-code's and DARLING's
    plans within the tolerance then shrink to that plan)."""
    lines = []
    tolerance = DarlingConfig().tolerance
    for name in sorted({str(e.get("planner", "graph")) for e in study.config.experiments}):
        try:
            every = get_planner(name).all_plans
        except PlanningError as exc:
            lines.append(f"Planner `{name}`: {exc}; whether it gives every plan is unknown.")
            continue
        lines += [say("planner", name=name, every=every, tolerance=f"{tolerance:g}")]
        lines += [] if every else [say("one_plan", name=name)]
    return [*lines, ""] if lines else []


def write_methods(w: Writer, full: bool = True) -> None:
    """The section (nothing when every experiment has its paper section); ``full``: in
    the full report, which has the method paragraph above."""
    exps = w.study.uncovered
    if not exps:
        return
    w.add("## Methods compared", "", say("methods", exps=exps, window=w.opts.window, full=full,
                                         seed=w.opts.seed, alpha=ALPHA), "")
    for exp in exps:
        w.figure(curves_stem(exp), f"learning curves, {exp}")
        for task in w.study.tasks(exp):
            write_task(w, exp, task)
    write_iqm(w, [(e, t) for e in exps for t in w.study.tasks(e)])


def method_summary(study: Study, exp: str, task: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Per (method, run): the mean return over the task's episodes (``return``) and over
    its last 10% (``last``); and per method (rows in method order): ``runs``,
    ``episodes``, ``tail`` (= max(1, episodes // 10)), ``mean`` and ``se`` over runs of
    ``return``, ``last`` and ``last_se`` of ``last``, ``success`` (share of episodes)."""
    df = study.rows(exp)
    df = df[df["task"] == task].sort_values(["method", "run", "episode"])
    episodes = df.groupby("method", observed=True)["episode"].nunique()
    tail = (episodes // 10).clip(lower=1)
    place = df.groupby(["method", "run"], observed=True).cumcount()
    is_last = place >= df["method"].map(episodes - tail).astype(int)
    per_run = df.assign(last=df["return"].where(is_last)).groupby(
        ["method", "run"], observed=True)[["return", "last"]].mean()
    by = per_run.groupby(level="method", observed=True)
    table = pd.DataFrame({"runs": by.size(), "episodes": episodes, "tail": tail,
                          "mean": by["return"].mean(), "se": by["return"].sem(),
                          "last": by["last"].mean(), "last_se": by["last"].sem(),
                          "success": df.groupby("method", observed=True)["success"].mean()})
    return per_run, table.reindex([m for m in study.methods(exp) if m in table.index])


def _facts(info: dict) -> list[str]:
    """A PDDL problem's facts from its ``optimal.json`` entry (none for the office)."""
    if "domain" not in info:
        return []
    if not info.get("determinisation"):
        reality = f"dynamics `{info.get('dynamics')}`"
    else:
        overlay = f"overlay `{info['dynamics']}`" if info.get("dynamics") else "no overlay"
        reality = (f"PPDDL: reality is the domain's probabilistic model ({overlay}; r_max "
                   f"{info.get('r_max'):g}, step limit {info.get('step_limit')}), the planner "
                   f"knows its {info['determinisation']} determinisation")
    if info.get("explored") == "online":
        states = [f"- explored online: each run found states as its episodes reached them "
                  f"(rows of the learners' tables), the knowledge's distances by the "
                  f"heuristic's estimates (from the start: {info.get('estimate_from_start')} "
                  f"actions); {info.get('actions')} ground actions"]
        if info.get("explored_because"):
            states.append(f"- why online: {info['explored_because']}")
    else:
        states = [f"- learner: {info.get('states')} states (every reachable planner state), "
                  f"{info.get('actions')} actions (ground actions)",
                  f"- shortest plan: {info.get('shortest_plan')} actions"]
    if 0 in (info.get("shortest_plan"), info.get("estimate_from_start")):
        states.append("- the goal holds in the initial state: every episode ends there "
                      "before its first action, with return 0 (mdpsim's rule)")
    return [f"- PDDL domain `{info.get('domain')}`, problem `{info.get('problem')}`, {reality}",
            *states,
            *(["- returns on the problem's own scale, as the IPPC scores them: its rewards "
               "minus its costs, the goal reward once at the goal, no penalty for a failed "
               "or late end"] if info.get("reward_scale") == "problem" else []), ""]


STEP_LIMIT_GAP = 0.1
"""The report says the step limit makes V* far below what the goal is worth when the
most probability of reaching the goal with no limit passes the most within the limit
by at least this."""


def goal_lines(info: dict) -> list[str]:
    """What V* means in probabilities (``optimal.json``'s ``goal_*`` facts, from
    :func:`~gdq_pddl.envs.solve.goal_chances`), and whether the step limit cuts the goal
    off; none where they were not computed."""
    if "goal_within_limit" not in info:
        return []
    limit, unlimited = info.get("step_limit"), info["goal_no_limit"]
    exact = "" if info.get("goal_no_limit_exact") else "at least "
    lines = [f"The goal: V*'s policy reaches it with probability "
             f"{info['goal_v_star_policy']:.3f} within the step limit of {limit} actions, "
             f"the best policy for the goal with {info['goal_within_limit']:.3f}; with no "
             f"step limit the goal can be reached with probability {exact}{unlimited:.3f} "
             "(the most any policy has, value iteration on the same true model)."]
    if unlimited - info["goal_within_limit"] >= STEP_LIMIT_GAP:
        lines.append(f"The step limit makes V* far below what the goal is worth: with no "
                     f"limit the goal is reached with probability {exact}{unlimited:.3f}, "
                     f"within {limit} actions at most {info['goal_within_limit']:.3f}; an "
                     "episode cut off by the limit counts as a failure (V*, the returns "
                     "and the success rates all count it so).")
    return lines


def write_task(w: Writer, exp: str, task: str) -> None:
    """One task of an uncovered experiment: its facts, the per-method table, the tests."""
    study, window = w.study, w.opts.window
    per_run, table = method_summary(study, exp, task)
    if table.empty:
        return
    w.add(f"### {exp}: task {task}", "", *_facts(optimal_entry(study.optimal, task)))
    v_star = study.v_star(exp, task)
    facts = [f"V* = {v_star:.2f} (optimal expected return per episode, value iteration "
             "on the true model)" if not math.isnan(v_star) else
             f"V*: {optimal_entry(study.optimal, task).get('v_star_note', 'not known')}"]
    facts += [f"{n} episodes per run, last 10% = the final {t}"
              for n, t in sorted(set(zip(table["episodes"], table["tail"], strict=True)))]
    w.add("; ".join(facts) + ".", "")
    chances = goal_lines(optimal_entry(study.optimal, task))
    if chances:
        w.add(*chances, "")
    best = table["mean"].idxmax() if table["mean"].notna().any() else None
    w.table([[f"**{m}**" if m == best else m, int(s.runs), f"{number(s['mean'])} ({number(s.se)})",
              f"{number(s['last'])} ({number(s.last_se)})", pct(s.success),
              milestone_str(first_positive(study.returns(exp, m, task), window))]
             for m, s in table.iterrows()],
            ["Method", "runs", "mean return (SE)", "last 10% (SE)", "success rate",
             f"MA{window} > 0 at episode"])
    variants = [v for v in w.variants(exp) if v in table.index]
    baselines = [b for b in study.baselines(exp) if b in table.index]
    if not variants or not baselines:
        w.add(f"No {'GDQ variant' if not variants else 'baseline'} ran on this task: "
              "nothing to compare.", "")
        return
    for variant in variants:
        for label, column in (("all episodes", "return"), ("last 10% of episodes", "last")):
            comps = [compare(per_run.loc[variant, column].to_numpy(),
                             per_run.loc[b, column].to_numpy(), variant, b, seed=w.opts.seed)
                     for b in baselines]
            w.add(f"- **{variant}**, {label}: {variant} {verdict_reason(comps)}")
            w.comparisons(comps)


def write_iqm(w: Writer, slices: list[tuple[str, str]]) -> None:
    """Over several (experiment, task) slices: per method, the interquartile mean of
    every run's mean return / V* with its stratified bootstrap 95% CI (nothing with
    fewer than 2 tasks of known positive V*)."""
    study = w.study
    slices = [(e, t) for e, t in slices if study.v_star(e, t) > 0]
    if len(slices) < 2:
        return
    w.add(say("iqm", tasks=[t for _, t in slices]), "")
    rows = []
    for m in registry.order({m for e, _ in slices for m in study.methods(e)}):
        scores = [run_means(study.returns(e, m, t)) / study.v_star(e, t) for e, t in slices]
        scores = [x for x in scores if x.size]
        point, low, high = iqm_ci(scores, seed=w.opts.seed)
        rows.append([m, len(scores), number(point), f"[{number(low)}, {number(high)}]"])
    w.table(rows, ["Method", "tasks", "IQM of return / V*", "95% interval"], "lrrl")
