"""All shortest plans by answer-set programming (clingo, optional), over the grounded task.

The grounded task becomes ASP facts; the :data:`ENCODING` takes one action per step and
forbids repeated states and an early goal. Multi-shot solving grows the horizon to the
shortest length ``L``, then enumerates every answer set (one per plan) up to
``floor((1 + t) L)``; a breadth-first pass first settles whether any plan exists.
"""

from __future__ import annotations

from typing import Any

from gdq_pddl.errors import PlanningError
from gdq_pddl.pddl.grounding import set_bits
from gdq_pddl.planning.base import (
    Plan,
    PlanningProblem,
    PlanResult,
    State,
    length_bound,
    no_plan,
)
from gdq_pddl.planning.graph import shortest_length

ENCODING = """
#program base.
holds(F, 0) :- init(F).
goal_at(0) :- not unmet(0).
unmet(0) :- goal(F), not holds(F, 0).
unmet(0) :- goal_neg(F), holds(F, 0).

#program step(t).
1 { occ(O, t) : op(O) } 1.
:- occ(O, t), pre(O, F), not holds(F, t - 1).
:- occ(O, t), neg(O, F), holds(F, t - 1).
holds(F, t) :- occ(O, t), add(O, F).
holds(F, t) :- holds(F, t - 1), not deleted(F, t).
deleted(F, t) :- occ(O, t), del(O, F).
goal_at(t) :- not unmet(t).
unmet(t) :- goal(F), not holds(F, t).
unmet(t) :- goal_neg(F), holds(F, t).
% a plan ends where the goal first holds
:- goal_at(t - 1).
% no state repeats an earlier one
differs(T, t) :- holds(F, t), not holds(F, T), T = 0..t - 1.
differs(T, t) :- holds(F, T), not holds(F, t), fact(F), T = 0..t - 1.
:- not differs(T, t), T = 0..t - 1.

#program check(t).
#external query(t).
:- query(t), not goal_at(t).

#show occ/2.
"""
"""The planning encoding: ``base``, then ``step(t)`` and ``check(t)`` for each horizon."""

NOT_INSTALLED = "the optional package clingo is not installed (pip install gdq_pddl[clingo])"


class ClingoPlanner:
    """All shortest plans (or all loop-free plans within a tolerance) with clingo."""

    name = "clingo"
    all_plans = True

    def __init__(self, max_plans: int = 10_000) -> None:
        self.max_plans = max_plans

    @classmethod
    def unusable_reason(cls) -> str | None:
        """Why clingo cannot run here (it is not installed), or None when it can."""
        try:
            # optional dependency
            import clingo  # noqa: F401
        except ImportError:
            return NOT_INSTALLED
        return None

    def solve(self, problem: PlanningProblem, start: State | None = None,
              goal: State | None = None, tolerance: float = 0.0) -> PlanResult:
        """Plans from ``start`` (default: the problem's init) to ``goal`` (default: its goal)."""
        q = problem.query(self.name, start, goal, tolerance, self.max_plans)
        if q.hit is not None:
            return q.hit
        key, t0, task, s0, gmask = q.key, q.started, problem.task, q.start, q.goal
        distance = None if gmask is None else shortest_length(task, s0, gmask)
        if distance is None:
            return problem.remember(key, no_plan(self.name, t0))
        found, shortest, horizons, capped = self._search(task, s0, gmask, distance, tolerance)
        return problem.solved(q, self.name, (_replay(task, s0, ops) for ops in found), capped,
                              tolerance, self.max_plans, horizons=horizons, length=shortest)

    def _search(self, task, s0: int, goal: tuple[int, int], distance: int,
                tolerance: float) -> tuple[list[tuple[int, ...]], int, int, bool]:
        """Plans (operator indices) up to the bound, ``L``, the horizons solved, capped."""
        clingo = _clingo()
        ctl = clingo.Control(["--models=0", "--warn=none"], logger=lambda code, msg: None)
        ctl.add("base", [], _facts(task, s0, goal))
        ctl.add("base", [], ENCODING)
        found: list[tuple[int, ...]] = []
        capped = False

        def on_model(model: Any) -> bool:
            nonlocal capped
            if len(found) >= self.max_plans:
                capped = True
                return False
            occ = sorted((s.arguments[1].number, s.arguments[0].number)
                         for s in model.symbols(shown=True))
            found.append(tuple(op for _, op in occ))
            return True

        try:
            ctl.ground([("base", []), ("check", [clingo.Number(0)])])
            horizon, shortest, bound = 0, 0, None
            while True:
                query = clingo.Function("query", [clingo.Number(horizon)])
                ctl.assign_external(query, True)
                ctl.solve(on_model=on_model)
                ctl.release_external(query)
                if found and bound is None:
                    bound = length_bound(horizon, tolerance)
                    shortest = horizon
                if capped or (bound is not None and horizon >= bound):
                    return found, shortest, horizon + 1, capped
                if bound is None and horizon >= distance:
                    raise PlanningError(f"clingo found no plan of {distance} steps, but the "
                                        "grounded task has one: the encoding is wrong")
                horizon += 1
                n = clingo.Number(horizon)
                ctl.ground([("step", [n]), ("check", [n])])
        except RuntimeError as exc:
            raise PlanningError(f"clingo failed: {exc}") from None


def _clingo() -> Any:
    try:
        import clingo  # optional dependency: only this backend needs it
    except ImportError:
        raise PlanningError(f"planner 'clingo' is not usable here: {NOT_INSTALLED}") from None
    return clingo


def _facts(task, s0: int, goal: tuple[int, int]) -> str:
    """The grounded task and the query as ASP facts over fact and operator numbers."""
    out = [f"fact(0..{len(task.facts) - 1})."] if task.facts else []
    if task.ops:
        out.append(f"op(0..{len(task.ops) - 1}).")
    for i, op in enumerate(task.ops):
        for pred, mask in (("pre", op.pre), ("neg", op.neg), ("add", op.add),
                           ("del", op.dele)):
            out.extend(f"{pred}({i},{b})." for b in set_bits(mask))
    out.extend(f"init({b})." for b in set_bits(s0))
    out.extend(f"goal({b})." for b in set_bits(goal[0]))
    out.extend(f"goal_neg({b})." for b in set_bits(goal[1]))
    return "\n".join(out)


def _replay(task, s0: int, ops: tuple[int, ...]) -> Plan:
    states = [s0]
    for i in ops:
        states.append(task.ops[i].apply(states[-1]))
    return Plan(tuple(task.ops[i].name for i in ops), tuple(task.atoms(s) for s in states))

