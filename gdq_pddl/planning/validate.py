"""Check plans with unified-planning's plan validator (:func:`validate_plan`), and the
bridge to unified-planning the pyperplan backend shares (:func:`up_problem`: parsed once
per problem, cloned per query)."""

from __future__ import annotations

import weakref
from typing import TYPE_CHECKING, Any

from gdq_pddl.errors import PlanningError
from gdq_pddl.pddl.model import Atom
from gdq_pddl.planning.base import Plan, PlanningProblem, State, replay

if TYPE_CHECKING:
    from unified_planning.model import Problem as UPProblem

_PARSED: weakref.WeakKeyDictionary[PlanningProblem, UPProblem] = weakref.WeakKeyDictionary()


def _up() -> Any:
    """Import unified-planning with its credits banner switched off."""
    try:  # imported on first use: start-up time, and a clear error if it is missing
        import unified_planning.shortcuts as shortcuts
    except ImportError as exc:  # a declared dependency, but say so clearly if it is missing
        raise PlanningError(f"unified-planning cannot be imported: {exc} "
                            "(pip install unified-planning up-pyperplan)") from None
    shortcuts.get_environment().credits_stream = None
    return shortcuts


def base_up_problem(problem: PlanningProblem) -> UPProblem:
    """``problem`` as a unified-planning problem (parsed once per problem, then reused)."""
    hit = _PARSED.get(problem)
    if hit is not None:
        return hit
    if problem.text_gap or problem.task.incomplete:
        raise PlanningError(problem.text_gap or problem.task.incomplete)
    if not problem.domain_text:
        raise PlanningError("unified-planning needs the domain as PDDL text: build the "
                            "problem with PlanningProblem.from_texts or from_files")
    _up()
    from unified_planning.io import PDDLReader  # start-up time: after _up(), see there

    # the original text keeps goal literals the writer drops (negative or static ones)
    text = problem.problem_text or problem.problem_pddl()
    try:
        parsed = PDDLReader().parse_problem_string(problem.domain_text, text)
    except Exception as exc:
        raise PlanningError(f"unified-planning cannot read the problem "
                            f"{problem.problem.name}: {type(exc).__name__}: {exc}") from None
    _PARSED[problem] = parsed
    return parsed


def _atom(up: UPProblem, atom: str) -> Any:
    parsed = Atom.parse(atom)
    try:
        return up.fluent(parsed.predicate)(*(up.object(a) for a in parsed.args))
    except Exception:
        raise PlanningError(f"unified-planning does not know the atom {atom}") from None


def up_problem(problem: PlanningProblem, start: State | None = None,
               goal: State | None = None) -> UPProblem:
    """A unified-planning problem for one query: ``start`` (fluent atoms) to ``goal``."""
    base = base_up_problem(problem)
    if start is None and goal is None:
        return base
    up = base.clone()
    if start is not None:
        unknown = set(start) - problem.task.fact_index.keys()
        if unknown:
            raise PlanningError(f"unknown or unreachable atom {min(unknown)} in a start state")
        for fact in problem.task.facts:
            up.set_initial_value(_atom(up, fact), fact in start)
    if goal is not None:
        up.clear_goals()
        for atom in sorted(goal):
            up.add_goal(_atom(up, atom))
    return up


def up_action_name(instance: Any) -> str:
    """A unified-planning action instance as our action name, ``"(approach p0 p2 d1)"``."""
    args = (str(p.object().name) if p.is_object_exp() else str(p)
            for p in instance.actual_parameters)
    return "(" + " ".join((instance.action.name, *args)) + ")"


def _up_plan(up: UPProblem, actions: tuple[str, ...]) -> Any:
    from unified_planning.plans import ActionInstance, SequentialPlan  # start-up time: _up()

    steps = []
    for i, action in enumerate(actions):
        parsed = Atom.parse(action)
        try:
            steps.append(ActionInstance(up.action(parsed.predicate),
                                        tuple(up.object(a) for a in parsed.args)))
        except Exception as exc:
            raise PlanningError(f"step {i + 1} of the plan, {action}, is not an action of "
                                f"domain {up.name}: {exc}") from None
    return SequentialPlan(steps)


def validate_plan(problem: PlanningProblem, plan: Plan, start: State | None = None,
                  goal: State | None = None) -> None:
    """Raise :class:`PlanningError` unless unified-planning's validator accepts ``plan``
    from ``start`` (default: its first state) to ``goal`` (default: the problem's) and
    its states are the ones its actions lead through."""
    if len(plan.states) != len(plan.actions) + 1:
        raise PlanningError(f"a plan of {len(plan.actions)} actions must have "
                            f"{len(plan.actions) + 1} states, not {len(plan.states)}")
    if start is None:
        start = plan.states[0]
    elif frozenset(start) != plan.states[0]:
        raise PlanningError("the plan does not start in the given start state")
    up = up_problem(problem, start, goal)
    _up()  # unified-planning on first use (start-up time), then its validator
    from unified_planning.engines.plan_validator import SequentialPlanValidator
    from unified_planning.engines.results import ValidationResultStatus  # start-up time

    try:
        result = SequentialPlanValidator().validate(up, _up_plan(up, plan.actions))
    except PlanningError:
        raise
    except Exception as exc:
        raise PlanningError(f"unified-planning's plan validator failed: "
                            f"{type(exc).__name__}: {exc}") from None
    if result.status != ValidationResultStatus.VALID:
        why = result.reason.name.lower().replace("_", " ") if result.reason else "invalid"
        bad = result.inapplicable_action
        where = f" at {up_action_name(bad)}" if bad is not None else ""
        raise PlanningError(f"plan rejected by unified-planning's validator ({why}{where}): "
                            f"{' '.join(plan.actions) or '(empty plan)'}")
    # the plan's states must be the ones its actions lead through on the grounded task
    replayed = replay(problem.task, problem.task.mask(plan.states[0]), plan.actions).states
    for i, (state, action) in enumerate(zip(plan.states[1:], plan.actions, strict=True)):
        if state != replayed[i + 1]:
            raise PlanningError(f"state {i + 1} of the plan is not the state {action} leads "
                                "to")
