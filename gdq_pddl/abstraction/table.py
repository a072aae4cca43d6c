"""The abstraction interface and the plan table built through it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

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


@dataclass(frozen=True)
class PlanTable:
    """For every learner state, its plans to the goal as learner ``(state, action)`` pairs.

    Plans from state ``s`` are ``plan_ptr[s]:plan_ptr[s + 1]``; the pairs of plan ``k``
    are ``pair_state[pair_ptr[k]:pair_ptr[k + 1]]`` and ``pair_action[...]``.
    ``first_actions[s, a]`` says whether some plan from ``s`` starts with ``a``
    (DARLING's allowed set); ``has_plan[s]`` whether ``s`` has any plan.
    """

    plan_ptr: np.ndarray
    pair_ptr: np.ndarray
    pair_state: np.ndarray
    pair_action: np.ndarray
    first_actions: np.ndarray
    length: np.ndarray
    """Shortest plan length from each state (-1: no plan)."""
    capped: bool = False

    @property
    def n_states(self) -> int:
        return len(self.plan_ptr) - 1

    @property
    def has_plan(self) -> np.ndarray:
        return self.length >= 0

    def allowed_actions(self) -> np.ndarray:
        """DARLING's allowed set, a new bool array: ``first_actions``, and every action
        in the states without a plan."""
        allowed = np.array(self.first_actions, dtype=np.bool_, copy=True)
        allowed[~allowed.any(axis=1)] = True
        return allowed

    def plans_from(self, state: int) -> list[list[tuple[int, int]]]:
        """The plans from ``state`` as lists of learner pairs (for inspection and tests)."""
        out = []
        for k in range(self.plan_ptr[state], self.plan_ptr[state + 1]):
            lo, hi = self.pair_ptr[k], self.pair_ptr[k + 1]
            out.append(list(zip(self.pair_state[lo:hi].tolist(),
                                self.pair_action[lo:hi].tolist(), strict=True)))
        return out


def pack_plans(n_actions: int, plans: list[list[list[tuple[int, int]]]], length: np.ndarray,
               capped: bool) -> PlanTable:
    """The :class:`PlanTable` of ``plans[s]``, the plans from each learner state ``s`` as
    lists of learner ``(state, action)`` pairs (empty plans are left out)."""
    plan_ptr, pair_ptr = [0], [0]
    pair_s: list[int] = []
    pair_a: list[int] = []
    first = np.zeros((len(plans), n_actions), dtype=np.bool_)
    for s, state_plans in enumerate(plans):
        for pairs in state_plans:
            if not pairs:
                continue
            first[s, pairs[0][1]] = True
            pair_s += [p for p, _ in pairs]
            pair_a += [a for _, a in pairs]
            pair_ptr.append(len(pair_s))
        plan_ptr.append(len(pair_ptr) - 1)
    return PlanTable(np.array(plan_ptr, dtype=np.int64), np.array(pair_ptr, dtype=np.int64),
                     np.array(pair_s, dtype=np.int64), np.array(pair_a, dtype=np.int64),
                     first, length, capped)


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
