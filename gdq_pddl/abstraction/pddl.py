"""O for a generic PDDL problem: the learner state *is* the reachable planner state, the
learner action the ground action (for a PPDDL domain, the ground action a determinised
outcome comes from). :func:`graph_plan_table` builds every state's plans at once from the
reachable state graph, with the ``graph`` planner's semantics: plans end where the goal
first holds, every loop-free plan of at most ``floor((1 + t) L)`` actions, at most
``max_plans`` per state, sorted by (length, action names).
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.abstraction.table import PlanTable, plan_arrays
from gdq_pddl.errors import AbstractionError
from gdq_pddl.limits import MAX_TOLERANCE, check_real
from gdq_pddl.pddl.ppddl import ProbabilisticTask
from gdq_pddl.pddl.reachable import StateGraph
from gdq_pddl.planning.base import State, length_bound


class PDDLAbstraction:
    """O between a grounded problem's reachable states/ground actions and indices."""

    def __init__(self, graph: StateGraph) -> None:
        self.graph = graph
        self.task = graph.task
        self.n_states = graph.n_states
        self.n_actions = len(graph.task.ops)
        self.origin = graph.task.origin if isinstance(graph.task, ProbabilisticTask) else {}
        """Planner action -> the learner's ground action (PPDDL; empty: the same names)."""

    def learner_state(self, state: State) -> int:
        """The index of a reachable planner state."""
        try:
            i = self.graph.index.get(self.task.mask(state))
        except KeyError as exc:
            raise AbstractionError(f"planner state {sorted(state)}: unknown atom "
                                   f"{exc.args[0]}") from None
        if i is None:
            raise AbstractionError(f"planner state {sorted(state)} is not reachable from the "
                                   "problem's initial state: it has no learner state")
        return i

    def learner_action(self, action: str) -> int:
        """The index of a ground action, e.g. ``"(move r1 r2)"``, or of the ground action
        a planner action of a PPDDL domain is an outcome of."""
        try:
            return self.graph.op_index[self.origin.get(action, action)]
        except KeyError:
            raise AbstractionError(f"planner action {action!r} is not a ground action of "
                                   "the problem") from None

    def planner_state(self, state: int) -> State:
        """The fluent atoms of learner state ``state``."""
        return self.task.atoms(self.graph.states[state])

    def goal(self, position_or_goal: str | None = None) -> State | None:
        """The problem's goal atoms; None (the problem's own goal) if it has negative
        literals, which a set of atoms cannot say."""
        if self.task.goal_neg:
            return None
        return self.task.atoms(self.task.goal_pos)


def graph_plan_table(graph: StateGraph, tolerance: float = 0.0,
                     max_plans: int = 10_000) -> PlanTable:
    """Plans from every reachable state (see the module docstring), kept as the graph's
    distance layers; the plans themselves are enumerated only when read.

    A pair ``(s, a)`` starts a plan iff an edge ``s -a-> s'`` (``s' != s``) has
    ``1 + d'(s') <= B(s)``, ``B(s) = floor((1 + tolerance) * d(s))`` and ``d'(s')`` the
    shortest length from ``s'`` to the goal that avoids ``s`` (a loop-free plan through
    ``s'`` is ``s`` then such a path). ``d'(s') = d(s')`` whenever ``d(s') <= d(s)`` (a
    path through ``s`` is longer); otherwise ``d'(s') = 1 + d(w)``, ``w`` the nearest
    successor of ``s'`` other than ``s``, if ``d(w) <= d(s)``, else a breadth-first
    search from ``s'`` that avoids ``s`` finds it (:func:`_avoiding`). With tolerance 0
    these are the edges one step closer to the goal: the shortest-path graph."""
    check_real("tolerance", tolerance, 0.0, MAX_TOLERANCE)
    dist = graph.distances
    n_ops = len(graph.task.ops)
    src = np.repeat(np.arange(graph.n_states), np.diff(graph.edge_ptr))
    op, nxt = graph.edge_op, graph.edge_next
    levels = np.unique(dist)
    bound = np.array([length_bound(int(d), tolerance) if d > 0 else -1 for d in levels],
                     dtype=np.int64)[np.searchsorted(levels, dist)]
    d2 = dist[nxt]
    ok = (nxt != src) & (d2 >= 0) & (1 + d2 <= bound[src])
    away = np.flatnonzero(ok & (d2 > dist[src]))
    m = _nearest_other(graph, src, nxt)(nxt[away], src[away])  # d'(s') = 1 + m if
    near = m <= dist[src[away]]  # m <= d(s): then no shortest path from there meets s
    ok[away[near]] = 2 + m[near] <= bound[src[away[near]]]
    d = dist.tolist()
    for e in away[~near].tolist():
        ok[e] = _avoiding(graph, d, int(nxt[e]), int(src[e]), int(bound[src[e]]) - 1)
    first = np.zeros((graph.n_states, n_ops), dtype=np.bool_)
    first[src[ok], op[ok]] = True
    layers = None
    if tolerance == 0.0:
        layers = np.stack([src[ok], op[ok], nxt[ok]], axis=1)
    names = [o.name for o in graph.task.ops]

    def enumerate_plans():
        edges = [graph.edges(s) for s in range(graph.n_states)]
        plans: list[list[list[tuple[int, int]]]] = []
        capped = False
        for s in range(graph.n_states):
            plans.append([])
            if dist[s] > 0:
                plans[s], cut = _paths(s, edges, dist, int(bound[s]), max_plans)
                capped |= cut
                plans[s].sort(key=lambda p: (len(p), tuple(names[a] for _, a in p)))
        return plan_arrays(plans, capped)

    return PlanTable(first, dist.astype(np.int64, copy=True), enumerate_plans, layers)


def _nearest_other(graph: StateGraph, src: np.ndarray, nxt: np.ndarray):
    """``f(v, s)``: the least ``d(w)`` over the successors ``w != s`` of each ``v`` (inf:
    none), from each state's two nearest distinct successors."""
    dist = graph.distances.astype(np.float64)
    dist[dist < 0] = np.inf
    n = graph.n_states
    order = np.lexsort((nxt, dist[nxt], src))
    s_, w_ = src[order], nxt[order]
    best = [np.full(n, -1, dtype=np.int64), np.full(n, -1, dtype=np.int64)]
    for k in range(2):
        keep = np.ones(len(s_), dtype=np.bool_) if k == 0 else w_ != best[0][s_]
        first = np.flatnonzero(keep)
        first = first[np.r_[True, s_[first][1:] != s_[first][:-1]]] if len(first) else first
        best[k][s_[first]] = w_[first]
    d_of = np.append(dist, np.inf)  # index -1: no such successor

    def nearest(v: np.ndarray, s: np.ndarray) -> np.ndarray:
        w = np.where(best[0][v] != s, best[0][v], best[1][v])
        return d_of[w]

    return nearest


def _avoiding(graph: StateGraph, dist: list[int], start: int, avoid: int,
              budget: int) -> bool:
    """Whether a path from ``start`` to the goal of at most ``budget`` actions avoids
    ``avoid``: breadth first from ``start`` without ``avoid``, a state ``v`` reached in
    ``k`` actions closing with its shortest ``d(v)`` if ``d(v) <= d(avoid)`` (then no
    shortest path from ``v`` crosses ``avoid``), and dropped if ``k + d(v) > budget``."""
    limit = dist[avoid]
    seen = {start, avoid}
    frontier = [start]
    for k in range(budget + 1):
        if any(dist[v] <= limit for v in frontier):
            return True
        nxt = []
        for v in frontier:
            for w in graph.edge_next[graph.edge_ptr[v]:graph.edge_ptr[v + 1]].tolist():
                if w not in seen:
                    seen.add(w)
                    if 0 <= dist[w] <= budget - k - 1:
                        nxt.append(w)
        frontier = nxt
    return False


def _paths(start: int, edges: list[list[tuple[int, int]]], dist: np.ndarray, bound: int,
           max_plans: int) -> tuple[list[list[tuple[int, int]]], bool]:
    """Loop-free plans ``[(state, op), ...]`` from ``start`` to a goal within ``bound``."""
    out: list[list[tuple[int, int]]] = []
    path: list[tuple[int, int]] = []
    on_path = {start}

    def walk(node: int) -> bool:
        for op, nxt in edges[node]:
            d = dist[nxt]
            if d < 0 or nxt in on_path or len(path) + 1 + d > bound:
                continue
            path.append((node, op))
            if d == 0:
                if len(out) >= max_plans:
                    return True
                out.append(list(path))
            else:
                on_path.add(nxt)
                if walk(nxt):
                    return True
                on_path.discard(nxt)
            path.pop()
        return False

    return out, walk(start)
