"""A planner backend as untrusted input: what :func:`~gdq_pddl.planning.get_planner` hands out.

Any package can register a backend, so nothing a backend returns is used on trust.
:class:`CheckedPlanner` wraps one and

- turns its exceptions (other than :class:`~gdq_pddl.errors.GdqError`, which are already
  meant for the user, and ``MemoryError``) into one-line :class:`PlanningError` naming the
  planner;
- refuses a return value that is not a :class:`PlanResult` of the right shape;
- replays every plan on the knowledge (the problem's grounded task) before anyone prints
  or uses it: it must start at the query's start, every step must be an action of the
  task applicable where it is taken, every state must be the one its action leads to,
  the last state must be a goal state and no earlier one, and no plan may be longer than
  the tolerance allows. A bad plan is refused naming the planner, the plan and the step.
  A plugin's "no plan" is confirmed by the built-in complete search before it is used.
"""

from __future__ import annotations

import warnings
import weakref
from collections.abc import Mapping

from gdq_pddl.errors import GdqError, PlanningError
from gdq_pddl.planning.base import (
    Plan,
    Planner,
    PlanningProblem,
    PlanResult,
    Query,
    State,
    Status,
    length_bound,
)
from gdq_pddl.planning.graph import GraphPlanner

CHECKED = "checked"
"""The option that sets this wrapper's query keys apart from any backend's."""

MAX_SHOWN = 300
"""Characters of a plugin's exception message kept in the one-line error."""


def one_line(exc: BaseException) -> str:
    """``Type: message`` of ``exc`` on one line, cut to :data:`MAX_SHOWN` characters."""
    text = " ".join(f"{type(exc).__name__}: {exc}".split())
    return text if len(text) <= MAX_SHOWN else text[:MAX_SHOWN - 3] + "..."


class CheckedPlanner:
    """The backend ``backend`` registered as ``name``, every answer checked (see the module
    docstring). ``name``, ``all_plans`` and ``solve`` are those of a :class:`Planner`."""

    def __init__(self, name: str, backend: Planner) -> None:
        self.name = name
        self.backend = backend
        all_plans = getattr(backend, "all_plans", None)
        if not isinstance(all_plans, bool):
            raise PlanningError(f"planner {name!r}: all_plans must be True or False, got "
                                f"{all_plans!r}")
        self.all_plans = all_plans
        if not callable(getattr(backend, "solve", None)):
            raise PlanningError(f"planner {name!r}: {type(backend).__name__} has no solve "
                                "method")
        # answers checked already, per problem and query (a backend's cache hands back the
        # same PlanResult object: no need to replay it again)
        self._checked: weakref.WeakKeyDictionary[PlanningProblem, dict[tuple, PlanResult]] = \
            weakref.WeakKeyDictionary()

    def __repr__(self) -> str:
        return f"CheckedPlanner({self.name!r}, {self.backend!r})"

    def solve(self, problem: PlanningProblem, start: State | None = None,
              goal: State | None = None, tolerance: float = 0.0) -> PlanResult:
        """The backend's answer for the query, once it has been checked."""
        # the key's "checked" keeps it apart from the backend's own (nothing is cached
        # under it); errors of the query name the planner as the backend's would
        q = problem.query(self.name, start, goal, tolerance, CHECKED)
        try:
            result = self.backend.solve(problem, start, goal, tolerance)
        except (GdqError, MemoryError):
            raise
        except Exception as exc:
            raise PlanningError(f"planner {self.name!r} failed: {one_line(exc)}") from None
        seen = self._checked.setdefault(problem, {})
        if q.key not in seen or seen[q.key] is not result:
            check_result(self.name, problem, q, result, tolerance)
            if result.status is Status.NO_PLAN and self.name != GraphPlanner.name:
                _confirm_no_plan(self.name, problem, start, goal)
            seen[q.key] = result
        return result


def _confirm_no_plan(name: str, problem: PlanningProblem, start: State | None,
                     goal: State | None) -> None:
    """A backend's "no plan" is checked by the built-in complete search (A* with h_max,
    whose answer the problem caches): a plugin that misses a plan would otherwise make
    every method that reads plans learn as if the goal could not be reached."""
    with warnings.catch_warnings():  # "kept the first 1 of more plans": one is enough
        warnings.simplefilter("ignore", UserWarning)
        found = GraphPlanner(max_plans=1).solve(problem, start, goal)
    if found.plans:
        shown = " ".join(found.plans[0].actions[:3]) + \
            (" ..." if len(found.plans[0]) > 3 else "")
        raise PlanningError(f"planner {name!r} says there is no plan, but the built-in "
                            f"planner 'graph' finds one of {found.length} actions: {shown}")


def check_result(name: str, problem: PlanningProblem, q: Query, result: object,
                 tolerance: float) -> None:
    """Raise :class:`PlanningError` naming planner ``name`` if ``result`` is not a right
    answer to the query ``q`` (resolved by :meth:`PlanningProblem.query`)."""
    where = f"planner {name!r}"
    if not isinstance(result, PlanResult):
        raise PlanningError(f"{where} returned {type(result).__name__} where a PlanResult "
                            "was expected")
    if not isinstance(result.status, Status):
        raise PlanningError(f"{where}: status {result.status!r} is not Status.SOLVED or "
                            "Status.NO_PLAN")
    if not isinstance(result.plans, tuple) or \
            not all(isinstance(p, Plan) for p in result.plans):
        raise PlanningError(f"{where}: plans must be a tuple of Plan, got "
                            f"{type(result.plans).__name__}")
    if not isinstance(result.metrics, Mapping):
        raise PlanningError(f"{where}: metrics must be a mapping, got "
                            f"{type(result.metrics).__name__}")
    if result.status is Status.NO_PLAN:
        if result.plans:
            raise PlanningError(f"{where} says no plan but returned {len(result.plans)}")
        return
    if not result.plans:
        raise PlanningError(f"{where} says solved but returned no plan")
    for i, plan in enumerate(result.plans, 1):
        check_plan(f"{where}, plan {i} of {len(result.plans)}", problem, q, plan)
    bound = length_bound(result.length or 0, tolerance)
    longest = max(result.plans, key=len)
    if len(longest) > bound:
        raise PlanningError(f"{where}: a plan of {len(longest)} actions is longer than "
                            f"tolerance {tolerance:g} allows ({bound}, the shortest plan "
                            f"returned has {result.length})")


def check_plan(where: str, problem: PlanningProblem, q: Query, plan: Plan) -> None:
    """Replay ``plan`` on the problem's grounded task from the query's start; raise
    :class:`PlanningError` (``where``: the planner and the plan) at its first fault."""
    task, ops = problem.task, problem.ops_by_name
    actions, states = plan.actions, plan.states
    if not isinstance(actions, tuple) or not all(isinstance(a, str) for a in actions):
        raise PlanningError(f"{where}: actions must be a tuple of strings")
    if not isinstance(states, tuple) or len(states) != len(actions) + 1 or \
            not all(isinstance(s, frozenset) for s in states):
        raise PlanningError(f"{where}: states must be a tuple of {len(actions) + 1} frozensets "
                            f"of atoms (one more than its {len(actions)} actions)")
    state = q.start
    _same(where, task, states[0], state, "its first state is not the query's start")
    for k, action in enumerate(actions, 1):
        step = f"{where}, step {k} {action}"
        if q.goal is not None and task.is_goal(state, q.goal):
            raise PlanningError(f"{step}: the goal already holds before this step (a plan "
                                "ends where the goal first holds)")
        op = ops.get(action)
        if op is None:
            raise PlanningError(f"{step}: not an action of the problem's grounded task")
        if not op.applicable(state):
            missing = sorted(task.atoms(op.pre & ~state))
            present = sorted(task.atoms(op.neg & state))
            why = f"{missing[0]} does not hold" if missing else f"{present[0]} holds"
            raise PlanningError(f"{step}: not applicable ({why})")
        state = op.apply(state)
        _same(step, task, states[k], state, "the state after it is not the one it leads to")
    if q.goal is None or not task.is_goal(state, q.goal):
        pos, neg = q.goal or (0, 0)
        missing = sorted(task.atoms(pos & ~state)) + \
            [f"(not {a})" for a in sorted(task.atoms(neg & state))]
        why = f": {missing[0]} does not hold" if missing else \
            ": the goal can never hold" if q.goal is None else ""
        raise PlanningError(f"{where}: stops short of the goal after {len(actions)} "
                            f"step(s){why}")


def _same(where: str, task, atoms: frozenset, state: int, message: str) -> None:
    try:
        same = task.mask(atoms) == state
    except KeyError as exc:
        raise PlanningError(f"{where}: unknown atom {exc.args[0]} in a state") from None
    except TypeError:
        raise PlanningError(f"{where}: a state holds something other than atoms") from None
    if not same:
        raise PlanningError(f"{where}: {message}")
