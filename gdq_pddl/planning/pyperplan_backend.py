"""One optimal plan from pyperplan (A* with h_max) through unified-planning, its states
replayed on the grounded task; with ``tolerance > 0`` still the one optimal plan."""

from __future__ import annotations

import time
from importlib.util import find_spec

from gdq_pddl.errors import PlanningError
from gdq_pddl.planning.base import PlanningProblem, PlanResult, State, Status, no_plan, replay
from gdq_pddl.planning.validate import up_action_name, up_problem

SEARCH = {"search": "astar", "heuristic": "hmax"}
"""unified-planning parameters of the pyperplan engine: an optimal (admissible) search."""


class PyperplanPlanner:
    """One shortest plan, found by pyperplan's A* search with the h_max heuristic."""

    name = "pyperplan"
    all_plans = False

    @classmethod
    def unusable_reason(cls) -> str | None:
        """Why pyperplan cannot run here (unified-planning or up-pyperplan missing), or None."""
        for module, dist in (("unified_planning", "unified-planning"),
                             ("up_pyperplan", "up-pyperplan")):
            if find_spec(module) is None:
                return f"the package {dist} is not installed (pip install {dist})"
        return None

    def solve(self, problem: PlanningProblem, start: State | None = None,
              goal: State | None = None, tolerance: float = 0.0) -> PlanResult:
        """One shortest plan from ``start`` (default: init) to ``goal`` (default: the goal)."""
        q = problem.query(self.name, start, goal, tolerance)
        if q.hit is not None:
            return q.hit
        key, t0 = q.key, q.started
        if q.goal is None:  # a goal no action can make true: no need to ask pyperplan
            return problem.remember(key, no_plan(self.name, t0))
        up = up_problem(problem, start, goal)
        result = self._run(up)
        # unified-planning: imported once it is known to be there (and for start-up time)
        from unified_planning.engines import PlanGenerationResultStatus as S

        if result.status in (S.UNSOLVABLE_PROVEN, S.UNSOLVABLE_INCOMPLETELY):
            return problem.remember(key, no_plan(self.name, t0))
        if result.status not in (S.SOLVED_SATISFICING, S.SOLVED_OPTIMALLY):
            raise PlanningError(f"pyperplan did not solve the problem: {result.status.name}")
        actions = tuple(up_action_name(a) for a in result.plan.actions)
        task = problem.task
        plan = replay(task, task.init if start is None else task.mask(start), actions)
        metrics = {"time_s": time.perf_counter() - t0, "plans": 1}
        engine_time = result.metrics.get("engine_internal_time") if result.metrics else None
        if engine_time is not None:
            metrics["engine_time_s"] = float(engine_time)
        return problem.remember(key, PlanResult(Status.SOLVED, (plan,), self.name, metrics))

    @staticmethod
    def _run(up):
        from unified_planning.shortcuts import OneshotPlanner  # optional: see unusable_reason

        try:
            with OneshotPlanner(name="pyperplan", params=SEARCH) as engine:
                return engine.solve(up)
        except Exception as exc:
            raise PlanningError(f"pyperplan failed: {type(exc).__name__}: {exc}") from None

