"""An output folder of ``gdq-pddl knowledge`` read into one :class:`CaseResult` per case:
both experiments (accurate and wrong knowledge) of every method, measured with
:mod:`gdq_pddl.analysis.knowledge_measures`."""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gdq_pddl.analysis.knowledge_measures import (
    ACCURATE,
    CURVE_WINDOW,
    FINAL,
    WRONG,
    RouteStep,
    convergence_episode,
    median_episode,
    moving_average,
    policy_value,
    route_check,
    threshold,
)
from gdq_pddl.analysis.routes import optimal_route, walk_policy
from gdq_pddl.analysis.study import Study
from gdq_pddl.envs.model import compile_model
from gdq_pddl.envs.solve import solve_task
from gdq_pddl.experiments.knowledge import CASES, knowledge_world
from gdq_pddl.experiments.work import load_world_named, resolve_task
from gdq_pddl.world import Task


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
        return median_episode(self.convergence)


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
