"""The default planner: all shortest plans from the grounded state graph.

It grounds the problem once (:mod:`gdq_pddl.pddl.grounding`), then for each query
builds, breadth first and only as deep as the query needs, the reachable state graph
as a :class:`networkx.DiGraph` (goal states are not expanded: a plan ends where the goal
first holds). With ``tolerance == 0`` it returns every shortest plan (networkx's
``all_shortest_paths`` to a sink joined to every goal state); with ``tolerance = t`` it
returns every loop-free plan of at most ``floor((1 + t) * L)`` actions, where ``L`` is
the shortest length, by a depth-first search pruned with each state's distance to the
goal. Works for any STRIPS + typing problem, not only the office.
"""

from __future__ import annotations

import itertools
import math
import time
import warnings

import networkx as nx

from gdq_pddl.errors import PlanningError
from gdq_pddl.planning.base import Plan, PlanningProblem, PlanResult, State, Status

_SINK = -1


class GraphPlanner:
    """All shortest plans (or all plans within a length tolerance) by graph search."""

    name = "graph"
    all_plans = True

    def __init__(self, max_plans: int = 10_000) -> None:
        self.max_plans = max_plans

    @classmethod
    def unusable_reason(cls) -> str | None:
        """Always usable: it needs nothing beyond the package's own dependencies."""
        return None

    def solve(self, problem: PlanningProblem, start: State | None = None,
              goal: State | None = None, tolerance: float = 0.0) -> PlanResult:
        """Plans from ``start`` (default: the problem's init) to ``goal`` (default: its goal)."""
        if tolerance < 0:
            raise PlanningError(f"tolerance must be >= 0, got {tolerance}")
        key = (self.name, start, goal, tolerance, self.max_plans)
        hit = problem.cached(key)
        if hit is not None:
            return hit
        t0 = time.perf_counter()
        task = problem.task
        s0 = task.init if start is None else _mask(problem, start)
        if goal is None:
            gmask = (task.goal_pos, task.goal_neg)
        elif set(goal) <= task.fact_index.keys():
            gmask = (_mask(problem, goal), 0)
        else:  # a fluent atom no action ever makes true
            return problem.remember(key, self._none(t0, 0))
        if goal is None and not task.goal_possible:
            return problem.remember(key, self._none(t0, 0))
        graph, goals, depth = self._explore(problem, s0, gmask, tolerance)
        if not goals:
            return problem.remember(key, self._none(t0, graph.number_of_nodes()))
        if tolerance == 0:
            paths = nx.all_shortest_paths(graph, s0, _SINK)
        else:
            paths = _bounded_paths(graph, s0, math.floor((1 + tolerance) * depth + 1e-9))
        plans, capped = self._expand(task, graph, paths)
        if capped:
            warnings.warn(f"graph planner: more than {self.max_plans} plans within tolerance "
                          f"{tolerance}; kept the first {self.max_plans}", stacklevel=2)
        plans.sort(key=lambda p: (len(p), p.actions))
        metrics = {"time_s": time.perf_counter() - t0, "states": graph.number_of_nodes() - 1,
                   "plans": len(plans)}
        return problem.remember(key, PlanResult(Status.SOLVED, tuple(plans), self.name,
                                                metrics, capped))

    def _none(self, t0: float, states: int) -> PlanResult:
        return PlanResult(Status.NO_PLAN, (), self.name,
                          {"time_s": time.perf_counter() - t0, "states": states, "plans": 0})

    def _explore(self, problem: PlanningProblem, s0: int, goal: tuple[int, int],
                 tolerance: float) -> tuple[nx.DiGraph, list[int], int]:
        """BFS from ``s0``: to the first goal layer, or deeper within the tolerance."""
        task = problem.task
        graph = nx.DiGraph()
        graph.add_node(s0)
        depth_of = {s0: 0}
        layer, depth, goals, bound = [s0], 0, [], None
        if task.is_goal(s0, goal):
            goals, bound = [s0], 0
        while layer and (bound is None or depth < bound):
            nxt = []
            for s in layer:
                if task.is_goal(s, goal):
                    continue
                for op, t in task.successors(s):
                    if t not in depth_of:
                        depth_of[t] = depth + 1
                        nxt.append(t)
                        if task.is_goal(t, goal):
                            goals.append(t)
                    if graph.has_edge(s, t):
                        graph[s][t]["actions"].append(op.name)
                    else:
                        graph.add_edge(s, t, actions=[op.name])
            layer, depth = nxt, depth + 1
            if goals and bound is None:
                bound = math.floor((1 + tolerance) * depth + 1e-9)
        for g in goals:
            graph.add_edge(g, _SINK, actions=[])
        shortest = min((depth_of[g] for g in goals), default=0)
        return graph, goals, shortest

    def _expand(self, task, graph: nx.DiGraph, paths) -> tuple[list[Plan], bool]:
        """Turn state paths into plans, one per choice of action on each edge."""
        plans: list[Plan] = []
        for path in paths:
            states = path[:-1]
            choices = [graph[a][b]["actions"] for a, b in itertools.pairwise(states)]
            atoms = tuple(task.atoms(s) for s in states)
            for actions in itertools.product(*choices):
                if len(plans) >= self.max_plans:
                    return plans, True
                plans.append(Plan(tuple(actions), atoms))
        return plans, False


def _bounded_paths(graph: nx.DiGraph, source: int, bound: int):
    """Loop-free paths ``source -> ... -> sink`` with at most ``bound`` actions."""
    to_sink = nx.single_source_shortest_path_length(graph.reverse(copy=False), _SINK)
    path, on_path = [source], {source}

    def walk(node: int):
        for nxt in graph.successors(node):
            if nxt == _SINK:
                yield [*path, _SINK]
                continue
            # actions so far (len(path) - 1) + this edge + actions left (to_sink - 1)
            if nxt in on_path or nxt not in to_sink or len(path) + to_sink[nxt] - 1 > bound:
                continue
            path.append(nxt)
            on_path.add(nxt)
            yield from walk(nxt)
            path.pop()
            on_path.discard(nxt)

    yield from walk(source)


def _mask(problem: PlanningProblem, atoms: State) -> int:
    try:
        return problem.task.mask(atoms)
    except KeyError as exc:
        known = ", ".join(problem.task.facts[:8])
        raise PlanningError(f"unknown or unreachable atom {exc.args[0]} in a start or goal "
                            f"state (fluent atoms look like: {known}, ...)") from None
