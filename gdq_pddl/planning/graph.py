"""The default planner: all shortest plans (or all loop-free plans within a length
tolerance) of any STRIPS + typing problem.

A* with h_max finds the shortest length ``L``; a breadth-first search then keeps the
states with ``depth + h_max <= floor((1 + t) L)`` (h_max is admissible: no plan is lost)
as a :class:`networkx.DiGraph`; a plan ends where the goal first holds.
"""

from __future__ import annotations

import heapq
import itertools
import math
from functools import cache
from typing import TYPE_CHECKING

from gdq_pddl.planning.base import (
    Plan,
    PlanningProblem,
    PlanResult,
    State,
    length_bound,
    no_plan,
)
from gdq_pddl.planning.heuristic import INFINITE, hmax_for

if TYPE_CHECKING:
    import networkx as nx

_SINK = -1


class GraphPlanner:
    """All shortest plans (or all plans within a length tolerance) by graph search."""

    name = "graph"
    all_plans = True

    def __init__(self, max_plans: int = 10_000) -> None:
        self.max_plans = max_plans
        self._generated = 0  # states whose h_max the last query computed

    @classmethod
    def unusable_reason(cls) -> str | None:
        """Always usable: it needs nothing beyond the package's own dependencies."""
        return None

    def solve(self, problem: PlanningProblem, start: State | None = None,
              goal: State | None = None, tolerance: float = 0.0) -> PlanResult:
        """Plans from ``start`` (default: the problem's init) to ``goal`` (default: its goal)."""
        q = problem.query(self.name, start, goal, tolerance, self.max_plans)
        if q.hit is not None:
            return q.hit
        key, t0, task, s0, gmask = q.key, q.started, problem.task, q.start, q.goal
        if gmask is None:
            return problem.remember(key, no_plan(self.name, t0, states=0))
        graph, goals, depth = self._explore(problem, s0, gmask, tolerance)
        if not goals:
            return problem.remember(key, no_plan(self.name, t0,
                                                 states=graph.number_of_nodes()))
        if tolerance == 0:
            import networkx as nx  # start-up time: loaded only when a plan is searched

            paths = nx.all_shortest_paths(graph, s0, _SINK)
        else:
            paths = _bounded_paths(graph, s0, length_bound(depth, tolerance))
        plans, capped = self._expand(task, graph, paths)
        return problem.solved(q, self.name, plans, capped, tolerance, self.max_plans,
                              states=graph.number_of_nodes() - 1, generated=self._generated)

    def _explore(self, problem: PlanningProblem, s0: int, goal: tuple[int, int],
                 tolerance: float) -> tuple[nx.DiGraph, list[int], int]:
        """The part of the state graph that plans within the tolerance can use (see the
        module docstring), its goal states and the shortest length."""
        task = problem.task
        import networkx as nx  # start-up time: loaded only when a plan is searched

        hmax = hmax_for(task)
        h = cache(lambda s: hmax(s, goal[0]))
        graph = nx.DiGraph()
        graph.add_node(s0)
        shortest = shortest_length(task, s0, goal, h)
        if shortest is None:
            return graph, [], 0
        bound = length_bound(shortest, tolerance)
        depth_of = {s0: 0}
        layer, depth, goals = [s0], 0, [s0] if task.is_goal(s0, goal) else []
        while layer and depth < bound:
            nxt = []
            for s in layer:
                if task.is_goal(s, goal):
                    continue
                for op, t in task.successors(s):
                    d = depth_of.get(t)
                    if d is None:
                        hv = h(t)
                        if hv == INFINITE or depth + 1 + hv > bound:
                            depth_of[t] = -1  # pruned: no plan within the bound uses it
                            continue
                        depth_of[t] = depth + 1
                        nxt.append(t)
                        if task.is_goal(t, goal):
                            goals.append(t)
                    elif d < 0:
                        continue
                    if graph.has_edge(s, t):
                        graph[s][t]["actions"].append(op.name)
                    else:
                        graph.add_edge(s, t, actions=[op.name])
            layer, depth = nxt, depth + 1
        for g in goals:
            graph.add_edge(g, _SINK, actions=[])
        self._generated = h.cache_info().currsize
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


def shortest_length(task, s0: int, goal: tuple[int, int], h=lambda s: 0) -> int | None:
    """Length of a shortest plan from ``s0`` by A* with the consistent heuristic ``h``
    (default 0: a breadth-first search), or None when there is none."""
    h0 = h(s0)
    if h0 == INFINITE:
        return None
    g_of = {s0: 0}
    heap = [(h0, 0, s0)]  # (f, -g, state): ties go to the deeper state
    while heap:
        _f, neg_g, s = heapq.heappop(heap)
        g = -neg_g
        if g > g_of[s]:
            continue
        if task.is_goal(s, goal):
            return g
        for _op, t in task.successors(s):
            if g + 1 < g_of.get(t, math.inf):
                ht = h(t)
                if ht == INFINITE:
                    continue
                g_of[t] = g + 1
                heapq.heappush(heap, (g + 1 + ht, -g - 1, t))
    return None


def _bounded_paths(graph: nx.DiGraph, source: int, bound: int):
    """Loop-free paths ``source -> ... -> sink`` with at most ``bound`` actions."""
    import networkx as nx  # start-up time: loaded only when a plan is searched

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

