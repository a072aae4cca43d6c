"""The abstraction interface and the plan table built through it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

import numpy as np

from gdq_pddl.pddl.offered import column_of
from gdq_pddl.planning.base import Plan, Planner, PlanningProblem, PlanResult, State, Status


class Abstraction(Protocol):
    """O and its inverse for one learner state/action space."""

    n_states: int
    n_actions: int

    def learner_state(self, state: State) -> int:
        """O on states: the learner state of a planner state."""
        ...

    def learner_action(self, action: str) -> int:
        """O on actions: the learner action of a ground planner action."""
        ...

    def planner_state(self, state: int) -> State:
        """O^-1 on states: the planner state to plan from for a learner state."""
        ...

    def goal(self, position_or_goal: str) -> State:
        """The planner goal for a task's goal."""
        ...


def plan_pairs(abstraction: Abstraction, plan: Plan) -> list[tuple[int, int]]:
    """The learner ``(state, action)`` pairs of a plan (raises AbstractionError if any fails)."""
    return [(abstraction.learner_state(s), abstraction.learner_action(a)) for s, a in plan.pairs()]


PlanArrays = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, bool]
"""``plan_ptr``, ``pair_ptr``, ``pair_state``, ``pair_action`` and whether a cap cut them."""


@dataclass(frozen=True, eq=False)
class PlanTable:
    """For every learner state, its plans to the goal: the first actions and lengths
    always, the plans themselves as learner ``(state, action)`` pairs on demand.

    ``first_actions[s, a]`` says whether some plan from ``s`` starts with ``a``
    (DARLING's allowed set); ``length[s]`` is the shortest plan length (-1: no plan).
    ``plans`` gives the plan arrays, or a function that enumerates them when first read
    (only the paper's GDQs walk plans): plans from state ``s`` are
    ``plan_ptr[s]:plan_ptr[s + 1]``, the pairs of plan ``k`` are
    ``pair_state[pair_ptr[k]:pair_ptr[k + 1]]`` and ``pair_action[...]``.
    ``layers`` (int64[E, 3], optional) lists the edges ``(s, a, s')`` of the
    shortest-path graph (``s'`` one step closer to the goal than ``s``; a table of
    shortest plans only): :meth:`start_pairs` reads them instead of the plans.
    ``capped``: a cap cut the plans (reading it enumerates them).
    """

    first_actions: np.ndarray
    length: np.ndarray
    plans: PlanArrays | Callable[[], PlanArrays]
    layers: np.ndarray | None = None

    @cached_property
    def _arrays(self) -> PlanArrays:
        return self.plans() if callable(self.plans) else self.plans

    plan_ptr = property(lambda self: self._arrays[0])
    pair_ptr = property(lambda self: self._arrays[1])
    pair_state = property(lambda self: self._arrays[2])
    pair_action = property(lambda self: self._arrays[3])
    capped = property(lambda self: self._arrays[4])

    @property
    def enumerated(self) -> bool:
        """Whether the plan arrays exist (were given, or read once)."""
        return not callable(self.plans) or "_arrays" in self.__dict__

    @property
    def n_states(self) -> int:
        return len(self.length)

    def allowed_actions(self, live: np.ndarray | None = None) -> np.ndarray:
        """DARLING's allowed set, a new bool array: ``first_actions``, and every action
        (every ``live`` column, if given) in the states without a plan."""
        allowed = np.array(self.first_actions, dtype=np.bool_, copy=True)
        none = ~allowed.any(axis=1)
        allowed[none] = True if live is None else live[none]
        return allowed

    def start_pairs(self, s0: int) -> np.ndarray:
        """bool[n_states, n_actions]: the pairs on some plan from ``s0`` (OptInit's)."""
        out = np.zeros_like(self.first_actions, dtype=np.bool_)
        if self.layers is not None:  # the shortest-path graph: breadth first from s0
            order = np.argsort(self.layers[:, 0], kind="stable")
            s, a, nxt = (self.layers[order, k] for k in range(3))
            ptr = np.searchsorted(s, np.arange(self.n_states + 1))
            seen = np.zeros(self.n_states, dtype=np.bool_)
            frontier = np.array([s0] if self.length[s0] > 0 else [], dtype=np.int64)
            seen[frontier] = True
            while len(frontier):
                lo, hi = ptr[frontier], ptr[frontier + 1]
                edges = np.repeat(lo - np.cumsum(hi - lo) + (hi - lo), hi - lo) + \
                    np.arange(int((hi - lo).sum()))
                out[s[edges], a[edges]] = True
                reached = np.unique(nxt[edges])
                frontier = reached[~seen[reached]]
                seen[frontier] = True
            return out
        for k in range(self.plan_ptr[s0], self.plan_ptr[s0 + 1]):
            lo, hi = self.pair_ptr[k], self.pair_ptr[k + 1]
            out[self.pair_state[lo:hi], self.pair_action[lo:hi]] = True
        return out

    def in_columns(self, offered: np.ndarray) -> PlanTable:
        """This table with each action ``a`` of a state ``s`` replaced by its column in
        ``offered`` (:attr:`~gdq_pddl.pddl.reachable.StateGraph.offered`: the learners'
        tables of a PDDL problem list each state's applicable ground actions)."""
        live = offered >= 0
        first = np.zeros(offered.shape, dtype=np.bool_)
        rows = np.nonzero(live)[0]
        first[live] = self.first_actions[rows, offered[live]]
        layers = self.layers
        if layers is not None:
            layers = np.stack([layers[:, 0], column_of(offered, layers[:, 0], layers[:, 1]),
                               layers[:, 2]], axis=1)

        def plans() -> PlanArrays:
            plan_ptr, pair_ptr, state, action, capped = self._arrays
            return plan_ptr, pair_ptr, state, column_of(offered, state, action), capped

        return PlanTable(first, self.length, plans if not self.enumerated else plans(), layers)

    def plans_from(self, state: int) -> list[list[tuple[int, int]]]:
        """The plans from ``state`` as lists of learner pairs (for inspection and tests)."""
        out = []
        for k in range(self.plan_ptr[state], self.plan_ptr[state + 1]):
            lo, hi = self.pair_ptr[k], self.pair_ptr[k + 1]
            out.append(list(zip(self.pair_state[lo:hi].tolist(),
                                self.pair_action[lo:hi].tolist(), strict=True)))
        return out


def plan_arrays(plans: list[list[list[tuple[int, int]]]], capped: bool) -> PlanArrays:
    """The plan arrays of ``plans[s]``, the plans from each learner state ``s`` as lists
    of learner ``(state, action)`` pairs (empty plans are left out)."""
    plan_ptr, pair_ptr = [0], [0]
    pair_s: list[int] = []
    pair_a: list[int] = []
    for state_plans in plans:
        for pairs in state_plans:
            if pairs:
                pair_s += [p for p, _ in pairs]
                pair_a += [a for _, a in pairs]
                pair_ptr.append(len(pair_s))
        plan_ptr.append(len(pair_ptr) - 1)
    return (np.array(plan_ptr, dtype=np.int64), np.array(pair_ptr, dtype=np.int64),
            np.array(pair_s, dtype=np.int64), np.array(pair_a, dtype=np.int64), capped)


def pack_plans(n_actions: int, plans: list[list[list[tuple[int, int]]]], length: np.ndarray,
               capped: bool) -> PlanTable:
    """The :class:`PlanTable` of ``plans[s]`` (see :func:`plan_arrays`)."""
    first = np.zeros((len(plans), n_actions), dtype=np.bool_)
    for s, state_plans in enumerate(plans):
        for pairs in state_plans:
            if pairs:
                first[s, pairs[0][1]] = True
    return PlanTable(first, length, plan_arrays(plans, capped))


def build_plan_table(abstraction: Abstraction, problem: PlanningProblem, planner: Planner,
                     goal: State, tolerance: float = 0.0,
                     states: list[int] | None = None) -> PlanTable:
    """Plan from every learner state (or those in ``states``) to ``goal``.

    A learner state the problem can never be in (an atom of it is unreachable from the
    problem's initial state: a room behind a locked door) has no plan."""
    which = range(abstraction.n_states) if states is None else states
    known = problem.task.fact_index.keys()
    results: dict[int, PlanResult] = {}
    for s in which:
        start = abstraction.planner_state(s)
        if start <= known:
            results[s] = planner.solve(problem, start, goal, tolerance)
    plans: list[list[list[tuple[int, int]]]] = []
    length = np.full(abstraction.n_states, -1, dtype=np.int64)
    capped = False
    for s in range(abstraction.n_states):
        result = results.get(s)
        plans.append([])
        if result is not None and result.status is Status.SOLVED:
            capped |= result.capped
            length[s] = result.length
            plans[s] = [plan_pairs(abstraction, plan) for plan in result.plans]
    return pack_plans(abstraction.n_actions, plans, length, capped)
