"""Analysis of the wrong-knowledge experiments (``gdq-pddl knowledge``): the measures.

An output folder of :func:`gdq_pddl.experiments.knowledge.knowledge_experiments` holds,
per case, two experiments on the same *real* world: ``<case>--accurate`` (knowledge built
from the real world) and ``<case>--wrong`` (from the case's knowledge world).
:func:`analyse` measures per case and method: **convergence** (per run, the first
episode at which the trailing :data:`WINDOW`-episode mean return reaches
:func:`threshold`, 85% of V* when V* > 0; the median over runs, unconverged runs
counting as later than any episode; docs/decisions.md says why first passage and why
85%); **the final greedy policy**, walked along likeliest outcomes in the real world,
its area route against the true optimal one and its exact expected return
(:func:`policy_value`); and along the true optimal route, whether an optimal action is
in DARLING's allowed set, GDQ's prior, its shortest plans and its 1.3x plans
(:func:`route_check`). :mod:`.knowledge_report` writes the figures and ``REPORT.md``.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gdq_pddl.analysis.stats import moving_average as rolling_mean
from gdq_pddl.analysis.study import Study
from gdq_pddl.envs.evaluate import likeliest_next, optimal_route, policy_value, walk_policy
from gdq_pddl.envs.model import compile_model
from gdq_pddl.envs.solve import solve_task
from gdq_pddl.experiments.knowledge import CASES, knowledge_world
from gdq_pddl.experiments.work import load_world_named, resolve_task
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import Task, World

WINDOW = 100
"""Moving-average window (episodes) of the convergence criterion."""
CURVE_WINDOW = 50
"""Moving-average window (episodes) of the learning curves."""
FRACTION = 0.85
"""Convergence threshold: V* - (1 - FRACTION) |V*|."""
FINAL = 100
"""Episodes at the end over which the final mean return is reported."""
ACCURATE, WRONG = "accurate", "wrong"


def threshold(v_star: float, fraction: float = FRACTION) -> float:
    """The return level a converged learner's moving average stays at or above."""
    return v_star - (1.0 - fraction) * abs(v_star)


def moving_average(returns: np.ndarray, window: int = WINDOW) -> np.ndarray:
    """Trailing means over full windows of ``window`` episodes (at most all of them);
    entry i covers episodes i+1 .. i+window (1-based). Works on [episodes] or
    [runs, episodes]."""
    w = min(window, np.shape(returns)[-1])
    return rolling_mean(returns, w)[..., w - 1:]


def convergence_episode(returns: np.ndarray, level: float, window: int = WINDOW) -> int | None:
    """First episode (1-based) at which the trailing ``window``-episode mean return is
    >= ``level``; None if it never is."""
    ma = moving_average(returns, window)
    hits = np.flatnonzero(ma >= level)
    return None if hits.size == 0 else int(hits[0]) + min(window, len(returns))


@dataclass(frozen=True)
class RouteStep:
    """One step of the true optimal route and what the knowledge allows there."""

    state: str
    optimal: tuple[str, ...]
    """Optimal actions (ties within 1e-9) at this step."""
    darling_allowed: bool
    in_shortest_plans: bool
    in_tolerant_plans: bool
    in_prior: bool = False
    """An optimal action is one the knowledge says can do something here (GDQ's prior
    model values it before it is tried)."""


def route_check(real: World, knowledge: World, task: Task,
                darling_tolerance: float = 0.3) -> list[RouteStep]:
    """Along the likeliest route of the true optimal policy in ``real``: are the optimal
    actions in DARLING's allowed set / in the plans / applicable in GDQ's prior model,
    with knowledge from ``knowledge``?"""
    ctx = office_task_context(knowledge, task, darling_tolerance=darling_tolerance)
    allowed = ctx.darling_plans.allowed_actions()
    shortest = ctx.plans.first_actions
    tolerant = ctx.darling_plans.first_actions
    model = compile_model(real)
    solution, fs = solve_task(real, task, model)
    spaces = LearnerSpaces(real)
    out: list[RouteStep] = []
    for t in range(model.step_limit):
        obs = int(model.obs_of[fs])
        q = solution.Q[t, fs]
        best = np.flatnonzero(q >= q.max() - 1e-9)
        out.append(RouteStep(
            state=spaces.state_name(obs),
            optimal=tuple(spaces.action_name(int(a)) for a in best),
            darling_allowed=bool(allowed[obs, best].any()),
            in_shortest_plans=bool(shortest[obs, best].any()),
            in_tolerant_plans=bool(tolerant[obs, best].any()),
            in_prior=bool(ctx.prior.applicable[obs, best].any())))
        nxt = likeliest_next(model, fs, int(solution.policy[t, fs]))
        if nxt is None or model.pos_of[nxt] == solution.goal_pos:
            break
        fs = nxt
    return out


@dataclass
class MethodResult:
    """One method in one experiment (accurate or wrong knowledge) of a case."""

    runs: int
    episodes: int
    convergence: list[int | None]
    final_return: float
    """Mean return over the last :data:`FINAL` episodes and all runs."""
    on_route: int
    """Runs whose final greedy policy follows the optimal area route to the goal."""
    policy_values: list[float]
    routes: list[tuple[int, ...]]
    curve: np.ndarray
    """Mean over runs of the trailing moving average (episode numbers CURVE_WINDOW..n)."""

    @property
    def converged(self) -> int:
        return sum(e is not None for e in self.convergence)

    @property
    def median(self) -> float:
        """Median over runs, unconverged runs as +inf (inf: most runs never converged)."""
        if not self.convergence:
            return float("nan")
        return float(np.median([np.inf if e is None else e for e in self.convergence]))


@dataclass
class CaseResult:
    name: str
    description: str
    real: str
    knowledge: str
    task: Task
    v_star: float
    optimal_positions: tuple[str, ...]
    optimal_areas: tuple[int, ...]
    methods: list[str]
    results: dict[str, dict[str, MethodResult]]
    """``{ACCURATE|WRONG: {method: MethodResult}}``."""
    checks: dict[str, list[RouteStep]]
    """``{ACCURATE|WRONG: route check}``."""

    def paired(self) -> Iterator[tuple[str, MethodResult, MethodResult]]:
        """``(method, accurate, wrong)`` for each method with results in both experiments,
        in method order."""
        for m in self.methods:
            a, w = self.results[ACCURATE].get(m), self.results[WRONG].get(m)
            if a is not None and w is not None:
                yield m, a, w


def _experiments(out: Path) -> dict[str, dict]:
    cfg = json.loads((out / "config.json").read_text(encoding="utf-8"))
    return {e["name"]: e for e in cfg.get("experiments", [])}


def analyse(out: str | Path) -> list[CaseResult]:
    """Measure every case of an output folder of ``gdq-pddl knowledge``."""
    out = Path(out)
    exps = _experiments(out)
    study = Study.open(out)
    described = {c.name: c.description for c in CASES}
    names = sorted({n.rsplit("--", 1)[0] for n in exps if n.endswith(("--accurate", "--wrong"))},
                   key=lambda n: (list(described).index(n) if n in described else 99, n))
    cases = []
    for name in names:
        acc, wrong = exps.get(f"{name}--{ACCURATE}"), exps.get(f"{name}--{WRONG}")
        if acc is None or wrong is None:
            continue
        real = load_world_named(wrong["world"])
        kworld = knowledge_world(real, wrong.get("knowledge"))
        task = resolve_task(real, wrong["schedule"][0][0])
        route = optimal_route(real, task)
        model = compile_model(real)
        solution, s0 = solve_task(real, task, model)
        v_star = float(solution.V[0, s0])
        level = threshold(v_star)
        results: dict[str, dict[str, MethodResult]] = {}
        methods = [m for m in wrong["methods"] if m in acc["methods"]]
        for kind, exp in ((ACCURATE, acc), (WRONG, wrong)):
            results[kind] = {}
            for m in methods:
                returns = study.returns(exp["name"], m)
                if returns.size == 0:
                    continue
                pols = [study.policy(exp["name"], m, task.name, r) for r in range(len(returns))]
                walks = [walk_policy(real, p, task.start, task.goal) for p in pols if p]
                results[kind][m] = MethodResult(
                    runs=len(returns), episodes=returns.shape[1],
                    convergence=[convergence_episode(row, level) for row in returns],
                    final_return=float(np.mean(returns[:, -FINAL:])),
                    on_route=sum(w.reached_goal and w.areas(real) == route.areas(real)
                                 for w in walks),
                    policy_values=[policy_value(real, task, p, model) for p in pols if p],
                    routes=[w.areas(real) if w.reached_goal else () for w in walks],
                    curve=moving_average(returns, CURVE_WINDOW).mean(axis=0))
        checks = {ACCURATE: route_check(real, real, task),
                  WRONG: route_check(real, kworld, task)}
        cases.append(CaseResult(
            name=name, description=described.get(name, ""), real=wrong["world"],
            knowledge=str(wrong.get("knowledge") or wrong["world"]), task=task, v_star=v_star,
            optimal_positions=route.positions, optimal_areas=route.areas(real),
            methods=methods, results=results, checks=checks))
    return cases
