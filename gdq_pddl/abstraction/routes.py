"""Tolerant plans for large worlds: one plan per door route instead of every plan
(``docs/decisions.md``, "Generated buildings").

:func:`route_plan_table` keeps, from each learner state ``x`` (bound ``B = floor((1 +
tolerance) * L(x))``), every shortest plan and, per *route* (a sequence of *branch*
pairs, for the office every ``gothrough``, that no state repeats), one plan: shortest
*legs* (paths taking no branch pair) between the branch pairs and to the goal, if it has
at most ``B`` actions, never revisits a learner state, ends at the first goal state and
replays in the planner's semantics: a subset of the full tolerant set.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import shortest_path

from gdq_pddl.abstraction.table import Abstraction, PlanTable, pack_plans
from gdq_pddl.limits import MAX_TOLERANCE, check_real
from gdq_pddl.planning.base import PlanningProblem, length_bound

Edge = tuple[int, int, int, str]
"""A knowledge edge: learner state, learner action, next learner state, ground action."""


def knowledge_edges(abstraction: Abstraction, problem: PlanningProblem,
                    read: Callable[[int], int] | None = None) -> list[Edge]:
    """Every learner ``(s, a, s')`` the planner's knowledge allows, with its ground action
    (the first, in ground order, where two map to one pair)."""
    task = problem.task
    read = read or _reader(abstraction, task)
    edges: list[Edge] = []
    for s in range(abstraction.n_states):
        seen: set[int] = set()
        atoms = abstraction.planner_state(s)
        if not atoms <= task.fact_index.keys():
            continue  # a state the problem can never be in (behind a locked door)
        state = task.mask(atoms)
        for op, nxt in task.successors(state):
            a = abstraction.learner_action(op.name)
            if a in seen:
                continue
            seen.add(a)
            edges.append((s, a, read(nxt), op.name))
    edges.sort()
    return edges


def route_plan_table(abstraction: Abstraction, problem: PlanningProblem,
                     shortest: PlanTable, tolerance: float,
                     branch: Callable[[int], bool], max_routes: int = 1000) -> PlanTable:
    """Every shortest plan (``shortest``: the tolerance-0 table) plus one plan per route
    within the tolerance, from every learner state; ``branch(a)``: whether routes differ
    at learner action ``a``; past ``max_routes`` routes from a state, marked capped."""
    check_real("tolerance", tolerance, 0.0, MAX_TOLERANCE)
    n = abstraction.n_states
    read = _reader(abstraction, problem.task)
    edges = knowledge_edges(abstraction, problem, read)
    length = shortest.length
    by_pair = {(s, a): (s2, op) for s, a, s2, op in edges}
    inner = [(s, a, s2) for s, a, s2, _ in edges if not branch(a)]
    legs = _Legs(n, inner, np.flatnonzero(length == 0))
    branches = [(s, a, s2) for s, a, s2, _ in edges
                if branch(a) and length[s2] >= 0 and s2 != s]
    b_s = np.array([b[0] for b in branches], dtype=np.int64)
    b_rest = np.array([1 + length[b[2]] for b in branches], dtype=np.float64)
    replay = _Replay(problem, by_pair, length, read)
    plans: list[list[list[tuple[int, int]]]] = []
    capped = shortest.capped
    for x in range(n):
        own = shortest.plans_from(x)
        plans.append(own)
        if length[x] <= 0:
            continue
        bound = length_bound(int(length[x]), tolerance)
        seen = {tuple(p) for p in own}
        start = problem.task.mask(abstraction.planner_state(x))
        extra: list[list[tuple[int, int]]] = []
        for plan in _routes(x, bound, legs, branches, b_s, b_rest):
            key = tuple(plan)
            if key in seen or not replay.valid(plan, x, start):
                continue
            if len(extra) >= max_routes:
                capped = True
                break
            seen.add(key)
            extra.append(plan)
        plans[x] = own + sorted(extra, key=lambda p: (len(p), p))
    if capped and not shortest.capped:
        warnings.warn(f"route plans: more than {max_routes} routes from some state within "
                      f"tolerance {tolerance}; kept the first {max_routes}", stacklevel=2)
    return pack_plans(abstraction.n_actions, plans, length.copy(), capped)


class _Legs:
    """Shortest paths that take no branch action (within an area), between any states."""

    def __init__(self, n: int, inner: list[tuple[int, int, int]], goals: np.ndarray) -> None:
        src = np.array([e[0] for e in inner], dtype=np.int64)
        dst = np.array([e[2] for e in inner], dtype=np.int64)
        graph = csr_matrix((np.ones(len(inner)), (src, dst)), shape=(n, n))
        self.dist, self.pred = shortest_path(graph, method="D", unweighted=True,
                                             return_predecessors=True)
        self.step: dict[tuple[int, int], int] = {}
        for s, a, s2 in inner:  # sorted: the lowest action between two states
            self.step.setdefault((s, s2), a)
        if len(goals):
            to_goals = self.dist[:, goals]
            self.to_goal = to_goals.min(axis=1)
            self.nearest_goal = goals[to_goals.argmin(axis=1)]
        else:
            self.to_goal = np.full(n, np.inf)
            self.nearest_goal = np.full(n, -1)

    def path(self, x: int, s: int) -> list[tuple[int, int]]:
        """The learner pairs of the breadth-first shortest leg ``x -> s``."""
        states = [s]
        while states[-1] != x:
            states.append(int(self.pred[x, states[-1]]))
        states.reverse()
        return [(u, self.step[(u, v)]) for u, v in zip(states, states[1:], strict=False)]


def _routes(x: int, bound: int, legs: _Legs, branches: list[tuple[int, int, int]],
            b_s: np.ndarray, b_rest: np.ndarray):
    """Plans from ``x``, depth first: one per sequence of branch pairs joined by shortest
    legs, of at most ``bound`` actions (the replay checks the states they cross)."""
    route: list[tuple[int, int, int]] = []

    def plan() -> list[tuple[int, int]]:
        out, at = [], x
        for s, a, s2 in route:
            out += legs.path(at, s) + [(s, a)]
            at = s2
        return out + legs.path(at, int(legs.nearest_goal[at]))

    def walk(at: int, used: float, crossed: frozenset):
        if used + legs.to_goal[at] <= bound:
            yield plan()
        fits = np.flatnonzero(used + legs.dist[at, b_s] + b_rest <= bound)
        for i in fits.tolist():
            s, a, s2 = branches[i]
            if s2 in crossed or (s != at and s in crossed):
                continue
            route.append((s, a, s2))
            yield from walk(s2, used + legs.dist[at, s] + 1, crossed | {s, s2})
            route.pop()

    yield from walk(x, 0.0, frozenset({x}))


def _reader(abstraction: Abstraction, task) -> Callable[[int], int]:
    """Learner state of a grounded state bitmask (the abstraction's fast reader if any)."""
    fast = getattr(abstraction, "mask_reader", None)
    if fast is not None:
        return fast(task)
    return lambda mask: abstraction.learner_state(task.atoms(mask))


class _Replay:
    """Checks a learner-pair plan in the planner's semantics (see the module docstring)."""

    def __init__(self, problem: PlanningProblem, by_pair: dict, length: np.ndarray,
                 read: Callable[[int], int]) -> None:
        self.ops = {op.name: op for op in problem.task.ops}
        self.by_pair = by_pair
        self.length = length
        self.read = read

    def valid(self, plan: list[tuple[int, int]], x: int, start: int) -> bool:
        """Loop-free, ends at the first goal state, and replays in the planner's semantics."""
        if not plan or plan[0][0] != x:
            return False
        visited = {x}
        state = start
        for i, (s, a) in enumerate(plan):
            s2, name = self.by_pair[(s, a)]
            op = self.ops[name]
            if not op.applicable(state):
                return False
            state = op.apply(state)
            if self.read(state) != s2:
                return False
            if i + 1 < len(plan) and plan[i + 1][0] != s2:
                return False
            if s2 in visited or (self.length[s2] == 0) != (i + 1 == len(plan)):
                return False
            visited.add(s2)
        return True
