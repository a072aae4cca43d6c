"""``REPORT.md``: the paper's hypotheses tested on an experiment output folder.

Every verdict is computed from the data by :func:`gdq_pddl.analysis.stats.verdict` (GDQ
against each baseline, one number per run, Welch's t-test and a bootstrap CI); nothing
is hard-coded. Experiments missing from the folder (a ``--quick`` run without switches
or robot) are skipped with a note.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gdq_pddl.analysis.data import ROBOT_EXPERIMENT, TASKS_EXPERIMENT, is_gdq, order_methods
from gdq_pddl.analysis.figures import FigureOptions, make_figures, slug
from gdq_pddl.analysis.routes import BEST_ROUTE_C
from gdq_pddl.analysis.stats import (
    ALPHA,
    HOLDS,
    Comparison,
    compare,
    convergence_episode,
    first_positive,
    mean_se,
    route_indicator,
    run_means,
    settles,
    verdict,
    verdict_reason,
)
from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.tables import area_table, make_tables, run_area_totals, to_markdown


@dataclass(frozen=True)
class ReportOptions:
    """Windows and thresholds of the report's statistics."""

    window: int = 50
    """Moving-average window (episodes) for milestones and curves."""
    early_window: int = 500
    """Hypothesis I also compares the mean return over the first this many episodes."""
    final_window: int = 250
    """Learning as a fraction of V*: mean return over the last this many episodes."""
    switch_window: int = 250
    """Hypothesis III: mean return over the first this many episodes after the switch."""
    route_window: int = 50
    route_share: float = 0.5
    """Task C convergence: from which episode at least this share of the last
    ``route_window`` episodes follow the best route successfully, to the end."""
    robot_window: int = 5
    robot_share: float = 0.6
    """Robot convergence: the same with a short window (30 trials)."""
    seed: int = 20240501


FIGURE_DIR, TABLE_DIR = "figures", "tables"


def _fmt(x: float, digits: int = 3) -> str:
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}g}"


def _route_str(areas: Sequence[int]) -> str:
    return "->".join(map(str, areas)) if areas else "(none)"


class _Writer:
    """Accumulates Markdown lines and the hypothesis verdict summary."""

    def __init__(self, study: Study, opts: ReportOptions, out_dir: Path) -> None:
        self.study, self.opts, self.out_dir = study, opts, out_dir
        self.lines: list[str] = []
        self.summary: dict[tuple[str, str], _Case] = {}  # (hypothesis, case) -> verdicts
        self.notes: list[str] = []

    def add(self, *lines: str) -> None:
        self.lines.extend(lines)

    def figure(self, stem: str, caption: str) -> None:
        path = self.out_dir / FIGURE_DIR / f"{stem}.png"
        if path.exists():
            self.add(f"![{caption}]({FIGURE_DIR}/{stem}.png)", "")

    def comparisons(self, comps: Sequence[Comparison], unit: str = "") -> None:
        for c in comps:
            self.add(f"  - {c.describe(unit)}")
        self.add("")

    def verdict_line(self, hypothesis: str, case: str, comps: Sequence[Comparison],
                     basis: str, variant: str = "GDQ") -> str:
        """Record ``variant``'s verdict on a case and write its bullet (the paper's GDQ
        under the case name, a variant as ``case, variant``)."""
        v = verdict(comps)
        reason = verdict_reason(comps)
        entry = self.summary.setdefault((hypothesis, case), _Case(hypothesis, case, basis))
        entry.verdicts[variant] = v
        entry.reasons[variant] = reason
        label = case if variant == "GDQ" else f"{case}, {variant}"
        self.add(f"- **{label}: {v}**: {variant} {reason} ({basis})")
        return v

    def variants(self, experiment: str) -> list[str]:
        """GDQ and its variants present in ``experiment`` (the paper's GDQ first)."""
        return [m for m in self.study.methods(experiment) if is_gdq(m)]

    # --- sections -------------------------------------------------------------------

    def header(self) -> None:
        cfg, ep = self.study.config, self.study.episodes
        self.add("# Experiment report", "",
                 f"Output folder: `{self.out_dir}`; {len(ep)} episodes in `episodes.csv`; "
                 f"experiments: {', '.join(ep.experiments) or 'none'}.", "")
        if cfg.experiments:
            self.add("| experiment | world | schedule (task x episodes) | methods | runs | seed |",
                     "|---|---|---|---|--:|--:|")
            for e in cfg.experiments:
                sched = e.get("schedule") or []
                sched_txt = ", ".join(f"{t} x {n}" for t, n in sched
                                      if isinstance(sched, list)) or "?"
                self.add(f"| {e.get('name', '?')} | {e.get('world', cfg.world or 'office')} | "
                         f"{sched_txt} | {', '.join(e.get('methods') or cfg.methods) or '?'} "
                         f"| {e.get('runs', cfg.runs if cfg.runs is not None else '?')} | "
                         f"{e.get('seed', cfg.seed if cfg.seed is not None else '?')} |")
            self.add("")
        else:
            facts = [f"world `{cfg.world or 'office (built in)'}`"]
            if cfg.seed is not None:
                facts.append(f"seed {cfg.seed}")
            if cfg.runs is not None:
                facts.append(f"{cfg.runs} runs")
            if cfg.episodes is not None:
                facts.append(f"{cfg.episodes} episodes per run")
            if cfg.methods:
                facts.append("methods " + ", ".join(cfg.methods))
            self.add("Configuration: " + "; ".join(facts) + ".", "")
        if cfg.versions:
            self.add("Versions: " + ", ".join(f"{k} {v}" for k, v in cfg.versions.items()),
                     "")
        self.add(
            "**Method.** The unit of analysis is the run. For each comparison every run "
            "contributes one number; each GDQ variant (`GDQ`, the paper's algorithm; "
            "`GDQ-code`, the authors' released code) is compared on its own with each "
            "baseline (every method but GDQ and its variants) by Welch's t-test "
            "(two-sided) and a percentile bootstrap "
            f"95% CI of the difference in means (10,000 resamples, seed {self.opts.seed}). "
            f"A difference counts when the CI excludes 0 and p < {ALPHA} (with fewer than 2 "
            "runs per method nothing counts). Verdict per case and variant: **holds** = "
            "the variant significantly better than every baseline; **does not hold** = "
            "significantly "
            "worse than at least one, or better than none; **mixed** = otherwise. "
            "Milestones use a trailing moving average over full windows of "
            f"{self.opts.window} episodes (defined from episode {self.opts.window} on).", "")

    def ground_truth(self) -> None:
        study = self.study
        self.add("## Ground truth: V* and relevant areas", "")
        if not study.has(TASKS_EXPERIMENT):
            self.add("_The tasks experiment is missing: skipped._", "")
            return
        self.add("V* is the optimal expected return per episode from value iteration on the "
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
            self.add(f"| {task} | {t.start} -> {t.goal} | {tr.v_star:.2f} | "
                     f"{', '.join(map(str, tr.relevant_areas))} | "
                     f"{', '.join(map(str, tr.irrelevant_areas)) or 'none'} | "
                     f"{', '.join(map(str, tr.irrelevant_areas_paper)) or 'none'} | "
                     f"{_route_str(tr.optimal_route_areas)} |")
        self.add("")
        ep = study.episodes
        methods = ep.methods(TASKS_EXPERIMENT)
        fw = self.opts.final_window
        self.add(f"Learning as a fraction of V*: mean return over all episodes / V* "
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
            self.add(f"| {task} | " + " | ".join(cells) + " |")
        self.add("")
        self.figure("fraction_of_vstar", "return as a fraction of V*")

    def hypothesis_1(self) -> None:
        study, opts = self.study, self.opts
        self.add("## Hypothesis I: GDQ collects more reward (tasks A-D)", "")
        if not study.has(TASKS_EXPERIMENT):
            self.note("Hypothesis I", "the tasks experiment (A-D) is missing")
            return
        self.figure("learning_curves", "learning curves, tasks A-D")
        ep = study.episodes
        self.add("Statistic: per-run mean return over all episodes of the task (the "
                 "cumulative reward of a run divided by its episodes).", "")
        for task in ep.tasks(TASKS_EXPERIMENT):
            variants = [v for v in self.variants(TASKS_EXPERIMENT)
                        if study.returns(TASKS_EXPERIMENT, v, task).size]
            if "GDQ" not in variants:
                self.add(f"- {task}: no GDQ runs; skipped.")
            for variant in variants:
                gdq = study.returns(TASKS_EXPERIMENT, variant, task)
                comps, early = [], []
                for b in study.baselines(TASKS_EXPERIMENT):
                    base = study.returns(TASKS_EXPERIMENT, b, task)
                    if base.size == 0:
                        continue
                    comps.append(compare(run_means(gdq), run_means(base), variant, b,
                                         seed=opts.seed))
                    early.append(compare(run_means(gdq, 0, opts.early_window),
                                         run_means(base, 0, opts.early_window), variant, b,
                                         seed=opts.seed))
                self.verdict_line("I", f"Task {task}", comps,
                                  "Welch + bootstrap on per-run mean return", variant)
                self.comparisons(comps)
                if opts.early_window < gdq.shape[1]:
                    self.add(f"  First {opts.early_window} episodes only (verdict "
                             f"{verdict(early)}: {variant} {verdict_reason(early)}):")
                    self.comparisons(early)
        self.milestones()

    def milestones(self) -> None:
        study, w = self.study, self.opts.window
        ep = study.episodes
        methods = ep.methods(TASKS_EXPERIMENT)
        self.add(f"Episode at which the {w}-episode moving average of return first turns "
                 "positive: on the mean curve over runs; in brackets the mean over the "
                 "runs that reach it and how many do.", "",
                 "| Task | " + " | ".join(methods) + " |", "|---|" + "--:|" * len(methods))
        for task in ep.tasks(TASKS_EXPERIMENT):
            cells = []
            for m in methods:
                r = study.returns(TASKS_EXPERIMENT, m, task)
                ms = first_positive(r, w)
                cells.append(f"{_fmt(ms.on_mean_curve, 5)} ({_fmt(ms.mean_of_reached, 4)}; "
                             f"{ms.reached}/{len(ms.per_run)})")
            self.add(f"| {task} | " + " | ".join(cells) + " |")
        self.add("")

    def hypothesis_2(self) -> None:
        study = self.study
        self.add("## Hypothesis II: GDQ avoids irrelevant areas", "")
        if not study.has(TASKS_EXPERIMENT):
            self.note("Hypothesis II", "the tasks experiment (A-D) is missing")
            return
        table = area_table(study)
        self.add("Area visits summed over a run, mean (SE) over runs; bold: fewest visits "
                 "among the methods in an area irrelevant by either definition. "
                 f"(Also in `{TABLE_DIR}/area_visits.md`, `.tex`, `.csv`.)", "",
                 to_markdown(table))
        self.add("Statistic: per run, the visits to the task's irrelevant areas summed over "
                 "the run (fewer is better), for the paper's and for the computed set.", "")
        areas = study.episodes.areas
        for task in study.episodes.tasks(TASKS_EXPERIMENT):
            totals = {v: run_area_totals(study, v, task)
                      for v in self.variants(TASKS_EXPERIMENT)}
            totals = {v: t for v, t in totals.items() if t.shape[0]}
            if "GDQ" not in totals:
                self.add(f"- {task}: no GDQ runs; skipped.")
            for label, irr in (("paper", table.irrelevant_paper[task]),
                               ("computed", table.irrelevant_computed[task])):
                cols = [areas.index(a) for a in irr if a in areas]
                case = f"Task {task}, {label} irrelevant areas {{{', '.join(map(str, irr))}}}"
                if not cols:
                    if totals:
                        self.add(f"- {case}: no irrelevant areas; nothing to test.", "")
                    continue
                for variant, gdq in totals.items():
                    comps = []
                    for b in study.baselines(TASKS_EXPERIMENT):
                        base = run_area_totals(study, b, task)
                        if base.shape[0]:
                            comps.append(compare(gdq[:, cols].sum(axis=1),
                                                 base[:, cols].sum(axis=1), variant, b,
                                                 higher_is_better=False, seed=self.opts.seed))
                    self.verdict_line("II", case, comps,
                                      "Welch + bootstrap on per-run visits to those areas",
                                      variant)
                    fewest = sum(row.bold[areas.index(a)] for row in table.rows
                                 if row.task == task and row.method == variant for a in irr
                                 if a in areas)
                    self.add(f"  {variant} has the fewest visits in {fewest} of {len(cols)} "
                             "of these areas.")
                    self.comparisons(comps, " visits")
        for task in study.episodes.tasks(TASKS_EXPERIMENT):
            self.figure(f"heatmap_{slug(task)}", f"area visits, task {task}")

    def hypothesis_3(self) -> None:
        study, opts = self.study, self.opts
        self.add("## Hypothesis III: GDQ adapts faster to a goal change", "")
        exps = study.switch_experiments
        if not exps:
            self.note("Hypothesis III", "no switch experiment (switch-C-D, switch-C-E)")
            return
        self.figure("switch_curves", "goal change")
        n = opts.switch_window
        self.add(f"Statistic: per-run mean return over the first {n} episodes after the "
                 "switch (all of them if fewer). "
                 "Recovery: the episode after the switch (1 = first episode of the "
                 f"new task) at which the {opts.window}-episode moving average of the new "
                 "task's returns first turns positive, on the mean curve (in brackets: mean "
                 "over runs that reach it, and how many).", "")
        ep = study.episodes
        for exp in exps:
            tasks = ep.tasks(exp)
            if len(tasks) < 2:
                self.add(f"- {exp}: only task {', '.join(tasks)} in the data; skipped.", "")
                continue
            new = tasks[-1]
            variants = [v for v in self.variants(exp) if study.returns(exp, v, new).size]
            if "GDQ" not in variants:
                self.add(f"- {exp}: no GDQ runs; skipped.", "")
            for variant in variants:
                gdq = study.returns(exp, variant, new)
                comps = []
                for b in study.baselines(exp):
                    base = study.returns(exp, b, new)
                    if base.size:
                        comps.append(compare(run_means(gdq, 0, n), run_means(base, 0, n),
                                             variant, b, seed=opts.seed))
                self.verdict_line("III", f"{exp} ({' -> '.join(tasks)}, switch at episode "
                                  f"{study.switch_episode(exp)})", comps,
                                  f"Welch + bootstrap on per-run mean return, first {n} "
                                  "episodes after the switch", variant)
                self.comparisons(comps)
            if not variants:
                continue
            parts = []
            for m in ep.methods(exp):
                ms = first_positive(study.returns(exp, m, new), opts.window)
                parts.append(f"{m} {_fmt(ms.on_mean_curve, 5)} "
                             f"({_fmt(ms.mean_of_reached, 4)}; {ms.reached}/{len(ms.per_run)})")
            self.add("  Recovery episode: " + "; ".join(parts) + ".", "")

    def route_c(self) -> None:
        study, opts = self.study, self.opts
        self.add("## Task C: route finding", "")
        exp = TASKS_EXPERIMENT
        if not study.has(exp) or "C" not in study.episodes.tasks(exp):
            self.note("Task C routes", "Task C is not in the tasks experiment")
            return
        world = study.world(exp)
        best = study.truth(exp, "C").optimal_route_areas
        self.add(f"The paper's best route is areas {_route_str(BEST_ROUTE_C)}; the true "
                 f"optimal policy's likeliest route is {_route_str(best)}. A run's final "
                 "greedy policy is walked from the start along each action's likeliest "
                 "outcome (at most 30 steps). Convergence (behavioural, from `episodes.csv`): "
                 f"the episode from which at least {opts.route_share:.0%} of the last "
                 f"{opts.route_window} episodes succeed while visiting exactly the areas of "
                 f"{_route_str(BEST_ROUTE_C)}, to the end of the run.", "")
        self.figure("routes_C", "Task C greedy routes")
        have_policies = study.policies is not None
        if not have_policies:
            self.add("_No `policies.csv`: final greedy routes are not available._", "")
        self.add(f"| Method | final route {_route_str(BEST_ROUTE_C)} | most common final route "
                 "| converged runs | convergence episode (mean) |", "|---|--:|---|--:|--:|")
        ep = study.episodes
        for m in ep.methods(exp):
            summary = study.route_summary(exp, m, "C") if have_policies else None
            share, common = "–", "–"
            if summary is not None:
                on = summary.on_route(world, BEST_ROUTE_C)
                share = f"{on}/{summary.runs} ({on / summary.runs:.0%})"
                k = summary.count
                common = (f"{_route_str(summary.areas)} ({summary.end}, {k} "
                          f"run{'s' if k != 1 else ''})")
            conv = convergence_episode(ep.area_visits(exp, m, "C"),
                                       ep.matrix("success", exp, m, "C"), BEST_ROUTE_C,
                                       ep.areas, opts.route_window, opts.route_share)
            reached = [c for c in conv if not math.isnan(c)]
            mean_conv = _fmt(float(np.mean(reached)), 5) if reached else "never"
            self.add(f"| {m} | {share} | {common} | {len(reached)}/{len(conv)} | "
                     f"{mean_conv} |")
        self.add("")
        gdq = convergence_episode(ep.area_visits(exp, "GDQ", "C"),
                                  ep.matrix("success", exp, "GDQ", "C"), BEST_ROUTE_C,
                                  ep.areas, opts.route_window, opts.route_share)
        if gdq:
            self.add("GDQ's convergence episode per run: "
                     + ", ".join(_fmt(c, 5) if not math.isnan(c) else "never" for c in gdq)
                     + ".", "")

    def variant_table(self) -> None:
        study = self.study
        self.add("## The paper's GDQ vs the authors'-code variant (GDQ-code)", "")
        exp = TASKS_EXPERIMENT
        methods = study.methods(exp) if study.has(exp) else []
        if "GDQ" not in methods or "GDQ-code" not in methods:
            self.note("GDQ vs GDQ-code", "the tasks experiment lacks GDQ or GDQ-code")
            return
        self.add("Mean return per episode over all episodes, mean (SE) over runs; the "
                 "difference is GDQ - GDQ-code.", "",
                 "| Task | GDQ | GDQ-code | difference (95% CI) | Welch p |",
                 "|---|--:|--:|--:|--:|")
        for task in study.episodes.tasks(exp):
            a = run_means(study.returns(exp, "GDQ", task))
            b = run_means(study.returns(exp, "GDQ-code", task))
            if a.size == 0 or b.size == 0:
                continue
            c = compare(a, b, "GDQ", "GDQ-code", seed=self.opts.seed)
            (ma, sa), (mb, sb) = mean_se(a), mean_se(b)
            self.add(f"| {task} | {ma:.2f} ({sa:.2f}) | {mb:.2f} ({sb:.2f}) | "
                     f"{c.diff:+.2f} [{c.ci_low:+.2f}, {c.ci_high:+.2f}] | {_fmt(c.p)} |")
        self.add("")

    def why_gdq_fails(self) -> None:
        """Measured evidence for the paper GDQ's failure: its Q values right after OptInit
        and how its episodes end."""
        study = self.study
        exp = TASKS_EXPERIMENT
        self.add("## Why the paper's GDQ fails here", "")
        if not study.has(exp) or not {"GDQ", "GDQ-code"} & set(study.methods(exp)):
            self.note("Why the paper's GDQ fails", "the tasks experiment has no GDQ runs")
            return
        tasks = study.episodes.tasks(exp)
        task = "C" if "C" in tasks else tasks[0]
        init = optinit_values(study, exp, task)
        r_max, gamma = init.r_max, init.gamma
        bound = r_max / (1 - gamma)
        self.add(f"Q values at the start state of Task {task} right after OptInit, measured "
                 "by building each learner as the experiment did (before any episode); "
                 f"R_max = {r_max:g}, gamma = {gamma:g}, so R_max / (1 - gamma) = "
                 f"{bound:.4g} and gamma R_max / (1 - gamma) = {gamma * bound:.4g}.", "",
                 "| Variant | Q(s0, greedy action) | median Q(s0, ·) | actions at s0 |",
                 "|---|--:|--:|--:|")
        for method, (greedy, median, n) in init.values.items():
            self.add(f"| {method} | {greedy:.4g} | {median:.4g} | {n} |")
        self.add("")
        ep = study.episodes
        limit = study.world(exp).step_limit
        methods = study.methods(exp)
        self.add(f"How episodes end (tasks {', '.join(tasks)}, all episodes of all runs): the "
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
            self.add(f"| {m} | {timeout:.1%} | {float(np.mean(success > 0)):.1%} | "
                     f"{float(np.mean(ep.values['return'][rows])):.2f} |")
        self.add("")
        paper = init.values.get("GDQ")
        if paper is not None:
            timeout = shares.get("GDQ", math.nan)
            self.add(
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
                f"{_pct(timeout)} of the paper GDQ's episodes end at the step limit without "
                f"the goal, against {_pct(shares.get('GDQ-code', math.nan))} for GDQ-code, "
                "whose OptInit gives R_max only to the plan pairs (no policy iteration), so "
                "its values start no higher than what the goal pays.", "")

    def robot(self) -> None:
        study, opts = self.study, self.opts
        self.add("## Robot protocol (simulated)", "")
        exp = ROBOT_EXPERIMENT
        if not study.has(exp):
            self.note("Robot protocol", "the robot experiment is missing")
            return
        ep = study.episodes
        tasks = ep.tasks(exp)
        task = tasks[-1]
        world = study.world(exp)
        truth = study.truth(exp, task)
        self.figure("robot_returns", "robot protocol, return per trial")
        self.figure(f"routes_robot_{slug(task)}", "robot greedy routes")
        self.figure(f"heatmap_robot_{slug(task)}", "robot area visits")
        self.add(f"Task {task} in `{world.name}`; V* = {truth.v_star:.1f}; optimal route "
                 f"(areas) {_route_str(truth.optimal_route_areas)}. A trial *follows the "
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
            self.add(f"| {m} | {n} | {np.nanmean(ret):.1f} | {succ_runs}/{n} | "
                     f"{_fmt(float(np.mean(firsts)), 3) if firsts else 'none'} | {conv_txt} | "
                     f"{final} |")
        self.add("")
        if "Dyna-Q" in ep.methods(exp):
            success = ep.matrix("success", exp, "Dyna-Q", task)
            k = int(np.sum(np.nansum(success, axis=1) > 0))
            self.add(f"Dyna-Q reached the goal at least once within {success.shape[1]} trials "
                     f"in {k} of {success.shape[0]} runs"
                     + (" (the paper: no meaningful solution in 30 trials)." if k == 0
                        else " (the paper reports no meaningful solution in 30 trials)."), "")

    def note(self, what: str, why: str) -> None:
        self.notes.append(f"{what}: skipped, {why}.")
        self.add(f"_Skipped: {why}._", "")

    def verdict_counts(self) -> str:
        """``paper GDQ: k of n cases hold; authors'-code GDQ: j of m cases hold``."""
        variants = self._summary_variants()
        if not variants:
            return "No verdicts (no GDQ runs in the data)."
        parts = []
        for v in variants:
            cases = [c for c in self.summary.values() if v in c.verdicts]
            held = sum(c.verdicts[v] == HOLDS for c in cases)
            parts.append(f"{VARIANT_NAMES.get(v, v)} (`{v}`): {held} of {len(cases)} cases hold")
        return "; ".join(parts) + "."

    def _summary_variants(self) -> list[str]:
        found = {v for c in self.summary.values() for v in c.verdicts}
        return order_methods(found)

    def render(self) -> str:
        variants = self._summary_variants() or ["GDQ"]
        summary = ["## Verdicts", "",
                   "| Hypothesis | Case | " + " | ".join(
                       f"{v} ({VARIANT_NAMES[v]})" if v in VARIANT_NAMES else v
                       for v in variants) + " | Basis |",
                   "|---|---|" + "---|" * len(variants) + "---|"]
        for c in self.summary.values():
            cells = [f"**{c.verdicts[v]}**" if v in c.verdicts else "–" for v in variants]
            reasons = "; ".join(f"{v} {c.reasons[v]}" for v in variants if v in c.reasons)
            summary.append(f"| {c.hypothesis} | {c.case} | " + " | ".join(cells)
                           + f" | {c.basis}: {reasons} |")
        if not self.summary:
            summary.append("| – | – | " + "no data | " * len(variants) + "– |")
        summary += ["", self.verdict_counts(), ""]
        if self.notes:
            summary += ["Skipped parts:", "", *[f"- {n}" for n in self.notes], ""]
        # header is the first block up to the method paragraph; put the summary after it
        head_end = next(i for i, line in enumerate(self.lines)
                        if line.startswith("**Method.**")) + 2
        top = [f"**Summary.** {self.verdict_counts()}", ""]
        return "\n".join(self.lines[:2] + top + self.lines[2:head_end] + summary
                         + self.lines[head_end:]) + "\n"


VARIANT_NAMES = {"GDQ": "paper GDQ", "GDQ-code": "authors'-code GDQ"}
"""How the verdict summary names the GDQ variants."""


@dataclass
class _Case:
    """One hypothesis case: each GDQ variant's verdict and reason."""

    hypothesis: str
    case: str
    basis: str
    verdicts: dict[str, str] = field(default_factory=dict)
    reasons: dict[str, str] = field(default_factory=dict)


def _pct(x: float) -> str:
    return "n/a" if math.isnan(x) else f"{x:.1%}"


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
    """Build ``GDQ`` and ``GDQ-code`` for ``task`` with the experiment's hyperparameters
    and planner (as the runner does) and read Q(s0, ·) before any episode."""
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
    for method in ("GDQ", "GDQ-code"):
        learner = make_learner(method, ctx, hyper)
        q = learner.q[ctx.s0]
        greedy = int(learner.greedy_policy()[ctx.s0])
        values[method] = (float(q[greedy]), float(np.median(q)), int(q.size))
    return OptInitValues(task, float(ctx.r_max), hyper.gamma, hyper.alpha, values)


def write_report(out_dir: str | Path, opts: ReportOptions = ReportOptions(),
                 study: Study | None = None) -> Path:
    """Write ``REPORT.md`` in ``out_dir`` (embedding figures already in ``out_dir/figures``)."""
    out = Path(out_dir)
    study = study or Study.open(out)
    w = _Writer(study, opts, out)
    w.header()
    w.ground_truth()
    w.hypothesis_1()
    w.hypothesis_2()
    w.hypothesis_3()
    w.route_c()
    w.variant_table()
    w.why_gdq_fails()
    w.robot()
    path = out / "REPORT.md"
    path.write_text(w.render(), encoding="utf-8")
    return path


def make_all(out_dir: str | Path, opts: ReportOptions = ReportOptions(),
             figure_opts: FigureOptions | None = None) -> list[Path]:
    """Figures, tables and ``REPORT.md`` for one output folder; returns every written path."""
    out = Path(out_dir)
    study = Study.open(out)
    fopts = figure_opts or FigureOptions(window=opts.window)
    paths = make_figures(out, fopts, study)
    paths += make_tables(out, study)
    paths.append(write_report(out, opts, study))
    return paths
