"""The checks and defaults of a PDDL instance's inputs
(:class:`~gdq_pddl.envs.pddl_env.PDDLInstance`): reality read from a dynamics or world
file, the determinisation's name, a PPDDL problem's default r_max and step limit, and the
refusals of a goal no episode could reach, of a step limit below the shortest plan and of
a true model in which the goal is out of reach (each naming the file, and the key of a
setting).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace

from gdq_pddl.dynamics import CostDist, Dynamics, parse_dynamics
from gdq_pddl.envs.solve import reality_distances
from gdq_pddl.envs.step import ModelArrays
from gdq_pddl.errors import PDDLError, PlanningError, WorldError
from gdq_pddl.limits import MAX_NUMBER
from gdq_pddl.pddl.model import Atom, Problem
from gdq_pddl.pddl.ppddl import DETERMINISATIONS
from gdq_pddl.pddl.reachable import StateGraph
from gdq_pddl.planning.base import PlanningProblem
from gdq_pddl.world import parse_world

DEFAULT_R_MAX, MIN_STEP_LIMIT, STEP_LIMIT_FACTOR = 20.0, 20, 2.5
"""A PPDDL problem's r_max and step limit when neither the problem nor an overlay says."""


def parse_reality(text: str, planning: PlanningProblem, source: str = "<string>") -> Dynamics:
    """The dynamics of ``planning`` from the TOML ``text`` of a dynamics file (an overlay
    for a PPDDL domain) or of a world file (reality for ``domains/office.pddl``)."""
    domain, problem = planning.source_domain, planning.problem
    try:
        is_world = "world" in tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        is_world = False  # parse_dynamics says what is wrong
    if not is_world:
        return parse_dynamics(text, domain, problem, source, overlay=domain.probabilistic)
    world = parse_world(text, source)
    dynamics = world.dynamics()
    missing = sorted(set(dynamics.actions) - {a.name for a in domain.actions})
    missing += sorted(d.name for d in world.doors if d.name not in problem.objects)
    if domain.probabilistic or missing:
        raise WorldError(source, "world", f"a world file is the reality of "
                         f"domains/office.pddl and its problems; {domain.source} and "
                         f"{problem.source} have no {', '.join(missing) or 'place for it'}"
                         if missing else f"a world file gives outcomes, and the PPDDL "
                         f"domain {domain.source} gives its own: give an overlay")
    return dynamics


def check_determinisation(determinisation: str) -> str:
    """``determinisation``, refused (:class:`PlanningError`) unless one of
    :data:`~gdq_pddl.pddl.ppddl.DETERMINISATIONS`."""
    if determinisation not in DETERMINISATIONS:
        raise PlanningError(f"unknown determinisation {determinisation!r} (known: "
                            f"{', '.join(DETERMINISATIONS)})")
    return determinisation


def default_step_limit(graph: StateGraph) -> int:
    """``max(20, ceil(2.5 L))``, L the fewest actions from the initial state to the goal in
    reality (breadth first over every outcome; 20 if no outcome ever reaches it)."""
    goal_depth = graph.depth[graph.is_goal]  # the graph's BFS levels are reality's
    if len(goal_depth):
        return max(MIN_STEP_LIMIT, math.ceil(STEP_LIMIT_FACTOR * int(goal_depth.min())))
    return MIN_STEP_LIMIT


def check_goal(problem: PlanningProblem, graph: StateGraph) -> None:
    """Refuse (:class:`PlanningError`) a goal that is empty, holds in the initial state or
    cannot be reached: no episode could teach the learner anything."""
    source = problem.problem.source
    if not problem.problem.goal and not problem.problem.goal_alternatives:
        raise PlanningError(f"{source}: the goal is empty: it holds in every state, so "
                            "there is nothing to learn; give a goal")
    if not graph.is_goal.any():
        domain = problem.source_domain
        never, both = never_true(problem), contradiction(problem.problem)
        actions, reached = (f"no outcome of positive probability of {domain.source}",
                            f"that the outcomes of {domain.source} reach") \
            if domain.probabilistic else ("no action", "reachable")
        why = (f"it asks for {both}, which can never both hold" if both else
               f"{never} can never hold ({actions} makes it true, and the initial state "
               "does not have it)" if never else
               f"none of the {graph.n_states} states {reached} from the initial state "
               "satisfies it")
        raise PlanningError(f"{source}: no plan: the goal cannot be reached from the "
                            f"initial state: {why}")


def limit_key(problem: PlanningProblem, dynamics: Dynamics) -> tuple[str, str]:
    """The file and key that give the step limit (or the problem file and the default)."""
    if dynamics.source and (not problem.source_domain.probabilistic
                            or "step_limit" in dynamics.stated):
        return dynamics.source, "dynamics.step_limit"
    return problem.problem.source, (f"the default step limit max({MIN_STEP_LIMIT}, ceil("
                                    f"{STEP_LIMIT_FACTOR:g} x the fewest actions to the goal))")


def check_step_limit(problem: PlanningProblem, graph: StateGraph, dynamics: Dynamics) -> None:
    """Refuse a step limit below the shortest plan (a :class:`WorldError`)."""
    shortest = int(graph.distances[0])
    if shortest > dynamics.step_limit:
        raise WorldError(*limit_key(problem, dynamics),
                         f"{dynamics.step_limit} is less than the shortest plan of "
                         f"{problem.problem.source} ({shortest} actions): no episode can "
                         "reach the goal")


def check_reality(problem: PlanningProblem, graph: StateGraph, dynamics: Dynamics,
                  model: ModelArrays) -> None:
    """Refuse a true model in which no episode can reach the goal: never (a
    :class:`PlanningError`) or not within the step limit (a :class:`WorldError`)."""
    fewest = reality_distances(model)[graph.is_goal].min(initial=math.inf)
    if fewest <= dynamics.step_limit:
        return
    source = problem.problem.source
    plan = int(graph.distances[0])
    if math.isinf(fewest):
        raise PlanningError(f"{dynamics.source}: the goal of {source} cannot be reached in "
                            f"reality: the knowledge has plans (the shortest: {plan} "
                            "actions), but under this dynamics file no sequence of actions "
                            "from the initial state reaches it with positive probability "
                            f"(success = 0: {', '.join(never_working(dynamics))}); give "
                            "those actions a success > 0")
    raise WorldError(*limit_key(problem, dynamics),
                     f"{dynamics.step_limit} is less than the fewest actions that can reach "
                     f"the goal of {source} in reality ({int(fewest)} actions; "
                     + (f"the knowledge's shortest plan has {plan}" if plan >= 0 else
                        "the knowledge has no plan") + "): no episode can reach the goal")


def never_working(dynamics: Dynamics) -> list[str]:
    """The dynamics file's ``success = 0`` keys (an object's where its schema's differs)."""
    out = [f"actions.{s}" for s, o in dynamics.actions.items() if o.success == 0]
    out += [f"actions.{s}.objects.{obj}" for s, per in dynamics.objects.items()
            for obj, o in per.items()
            if o.success == 0 and dynamics.actions[s].success != 0]
    return out


def never_true(problem: PlanningProblem) -> str:
    """The first goal literal of ``problem`` that can never hold ("" if none)."""
    task, domain = problem.learner_task, problem.source_domain
    for lit in problem.problem.goal:
        atom, args = str(lit.atom), lit.atom.args
        if lit.atom.predicate == "=":
            never = (args[0] == args[1]) != lit.positive
        elif lit.atom.predicate not in domain.fluent_predicates():
            never = (atom in task.statics) != lit.positive
        else:
            never = lit.positive and atom not in task.fact_index
        if never:
            return atom if lit.positive else f"(not {atom})"
    return ""


def contradiction(problem: Problem) -> str:
    """The first atom the goal asks for with its negation, as ``"A and (not A)"``."""
    goal = set(problem.goal)
    for lit in problem.goal:
        if lit.positive and replace(lit, positive=False) in goal:
            return f"{lit.atom} and (not {lit.atom})"
    return ""


NORMAL_SPREAD = 10.0
"""Standard deviations past its mean that :func:`check_step_rewards` counts a normal cost
as drawing at most."""


def check_step_rewards(problem: PlanningProblem, costs: list[CostDist], r_max: float,
                       own: bool) -> None:
    """Refuse, naming the domain file, its action and the bound, a problem one step of
    which can pay more than :data:`~gdq_pddl.limits.MAX_NUMBER` in size: an outcome's
    rewards and costs (each within it, all counted: :meth:`~gdq_pddl.pddl.grounding.
    GroundOutcome.largest_gain`; of a factored action, its parts' largest added up), the
    action's cost (``costs``: one per ground action; a
    uniform one's larger end, a normal one's mean plus :data:`NORMAL_SPREAD` deviations)
    and, on the problem's own scale (``own``), the goal reward ``r_max`` the step that
    reaches the goal adds. What the learners take (each reward within that bound) holds
    then wherever the states are found, enumerated or online."""
    domain = problem.source_domain
    for op, cost in zip(problem.learner_task.ops, costs, strict=True):
        top = max(abs(cost.a), abs(cost.b)) if cost.kind == "uniform" else \
            abs(cost.a) + NORMAL_SPREAD * abs(cost.b) if cost.kind == "normal" else abs(cost.a)
        earned = sum(max(o.largest_gain() for o in part) for part in op.parts) \
            if op.factored else max((o.largest_gain() for o in op.outcomes), default=0.0)
        goal = r_max if own else 0.0
        if earned + top + goal > MAX_NUMBER:
            schema = Atom.parse(op.name).predicate
            line = next((a.line for a in domain.actions if a.name == schema), None)
            raise PDDLError(domain.source, line or None, f"action {schema}: one step of "
                            f"{op.name} can pay {earned + top + goal:g} in size (its outcomes' "
                            f"rewards and costs {earned:g}, its cost {top:g}"
                            + (f", the goal reward {goal:g}" if own else "") + f"), past "
                            f"{MAX_NUMBER:g}: the rewards and costs of one step, added up, "
                            f"must be at most {MAX_NUMBER:g} in size (docs/domains.md)")
