"""O for a generic PDDL problem: the learner state *is* the reachable planner state, the
learner action the ground action (for a PPDDL domain, the ground action a determinised
outcome comes from). :func:`graph_plan_table` builds every state's plans at once from the
reachable state graph, with the ``graph`` planner's semantics: plans end where the goal
first holds, every loop-free plan of at most ``floor((1 + t) L)`` actions, at most
``max_plans`` per state, sorted by (length, action names).
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.abstraction.table import PlanTable, pack_plans
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
    """Plans from every reachable state (see the module docstring)."""
    check_real("tolerance", tolerance, 0.0, MAX_TOLERANCE)
    dist = graph.distances
    names = [op.name for op in graph.task.ops]
    edges = [graph.edges(s) for s in range(graph.n_states)]
    plans: list[list[list[tuple[int, int]]]] = []
    capped = False
    for s in range(graph.n_states):
        plans.append([])
        if dist[s] > 0:
            bound = length_bound(int(dist[s]), tolerance)
            plans[s], cut = _paths(s, edges, dist, bound, max_plans)
            capped |= cut
            plans[s].sort(key=lambda p: (len(p), tuple(names[a] for _, a in p)))
    return pack_plans(len(names), plans, dist.astype(np.int64, copy=True), capped)


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
