"""An example planner plugin for gdq_pddl: one shortest plan by breadth-first search.

It searches the problem's grounded task (``problem.task``: int bitmask states, ground
operators with ``successors``), so it works for any STRIPS problem gdq_pddl can parse.
It ignores ``tolerance`` and returns one shortest plan, which is within any tolerance.
"""

from __future__ import annotations

import time
from collections import deque

from gdq_pddl.planning import Plan, PlanningProblem, PlanResult, State, Status


class ToyPlanner:
    """One shortest plan, by breadth-first search over the grounded state space."""

    name = "toy"
    all_plans = False  # True only if solve returns *every* shortest plan

    @classmethod
    def unusable_reason(cls) -> str | None:
        """Why this backend cannot run here (say, a missing package), or None."""
        return None

    def solve(self, problem: PlanningProblem, start: State | None = None,
              goal: State | None = None, tolerance: float = 0.0) -> PlanResult:
        """A shortest plan from ``start`` (default: init) to ``goal`` (default: the goal)."""
        # checks the tolerance and start atoms, resolves start and goal to bitmasks of the
        # grounded task (goal None: it can never hold) and looks up the result cache
        q = problem.query(self.name, start, goal, tolerance)
        if q.hit is not None:
            return q.hit
        key, task = q.key, problem.task
        path = None if q.goal is None else _bfs(task, q.start, q.goal)
        metrics = {"time_s": time.perf_counter() - q.started}
        if path is None:
            return problem.remember(key, PlanResult(Status.NO_PLAN, (), self.name, metrics))
        states, actions = path
        plan = Plan(tuple(actions), tuple(task.atoms(s) for s in states))
        return problem.remember(key, PlanResult(Status.SOLVED, (plan,), self.name, metrics))


def _bfs(task, s0: int, goal: tuple[int, int]) -> tuple[list[int], list[str]] | None:
    """States and action names of a shortest path to a goal state, or None if none."""
    parent: dict[int, tuple[int, str] | None] = {s0: None}
    queue = deque([s0])
    while queue:
        s = queue.popleft()
        if task.is_goal(s, goal):
            states, actions = [s], []
            while parent[s] is not None:
                s, action = parent[s]
                states.append(s)
                actions.append(action)
            return states[::-1], actions[::-1]
        for op, t in task.successors(s):
            if t not in parent:
                parent[t] = (s, op.name)
                queue.append(t)
    return None
