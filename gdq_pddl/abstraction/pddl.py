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
    m = _nearest_other(graph, nxt[away], src[away])  # d'(s') = 1 + m if
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


def _nearest_other(graph: StateGraph, v: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The least ``d(w)`` over the successors ``w != s[i]`` of each ``v[i]`` (float; inf:
    none, or none with a distance), from each state's two nearest distinct successors.

    A state's edges are a contiguous run of ``edge_next`` (CSR), so its nearest successor
    is a minimum over its run (``np.minimum.reduceat``) of the key ``d(w) * n + w``, which
    orders by distance, then index; the second nearest is the same minimum with the
    nearest masked out. Linear in the edges, where a sort of them took seconds at 10^7."""
    v, s = np.asarray(v, dtype=np.int64), np.asarray(s, dtype=np.int64)
    if len(v) == 0:
        return np.zeros(0, dtype=np.float64)
    n = graph.n_states
    dist = graph.distances
    far = int(dist.max()) + 1  # no distance (-1) ranks after every distance
    nxt = graph.edge_next.astype(np.int64, copy=False)
    key = np.where(dist < 0, far, dist)[nxt] * n + nxt
    count = np.diff(graph.edge_ptr)
    starts = graph.edge_ptr[:-1][count > 0]  # goal states have no edges
    nearest: list[tuple[np.ndarray, np.ndarray]] = []
    for k in range(2):
        if k == 1:  # mask the nearest out: the second nearest distinct successor
            key[nxt == np.repeat(nearest[0][0], count)] = far * n + n
        best = np.full(n, far * n + n, dtype=np.int64)  # no successor: above every key
        if len(starts):
            best[count > 0] = np.minimum.reduceat(key, starts)
        w, d = np.divmod(best, n)[::-1]
        dw = d.astype(np.float64)
        dw[d >= far] = np.inf  # none, or a successor that cannot reach the goal
        nearest.append((np.where(d > far, -1, w), dw))
    (w0, d0), (_, d1) = nearest
    return np.where(w0[v] != s, d0[v], d1[v])


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
