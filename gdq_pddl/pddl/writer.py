"""Write PDDL text: the STRIPS domain and problem of a PPDDL domain's determinisation
(what a planner of that determinisation reads). A grounded problem with another start
state or goal is written by :meth:`gdq_pddl.planning.PlanningProblem.problem_pddl`."""

from __future__ import annotations

from gdq_pddl.pddl.model import Domain, Literal, Problem


def write_domain(domain: Domain) -> str:
    """PDDL text of a STRIPS domain (the planner's determinisation of a PPDDL domain)."""
    pre = [lit for a in domain.actions for lit in a.precondition]
    types = [t for t in domain.types if t != "object"]
    reqs = set(domain.requirements) | {":strips"} | {req for req, used in (
        (":negative-preconditions", any(not lit.positive and lit.atom.predicate != "="
                                        for lit in pre)),
        (":equality", any(lit.atom.predicate == "=" for lit in pre)),
        (":typing", bool(types))) if used}
    lines = [f"(define (domain {domain.name})", f"  (:requirements {' '.join(sorted(reqs))})"]
    if types:
        lines.append("  (:types " + " ".join(f"{t} - {domain.types[t]}" for t in types) + ")")
    if domain.constants:
        lines.append("  (:constants " + " ".join(f"{c} - {t}" for c, t in
                                                 domain.constants.items()) + ")")
    lines.append("  (:predicates")
    for name, arg_types in domain.predicates.items():
        params = " ".join(f"?x{i} - {t}" for i, t in enumerate(arg_types))
        lines.append(f"    ({name}{' ' + params if params else ''})")
    lines.append("  )")
    for a in domain.actions:
        params = " ".join(f"{p} - {t}" for p, t in a.parameters)
        lines += [f"  (:action {a.name}", f"    :parameters ({params})",
                  f"    :precondition (and {_literals(a.precondition)})",
                  f"    :effect (and {_literals(a.effect)}))"]
    return "\n".join(lines) + ")\n"


def write_parsed_problem(problem: Problem, domain: Domain) -> str:
    """PDDL text of a parsed problem without its numeric parts (function values, goal
    reward, metric): what a planner of the domain's determinisation reads."""
    objects = "\n".join(f"    {o} - {t}" for o, t in problem.objects.items()
                        if o not in domain.constants)
    init = "\n".join(f"    {a}" for a in sorted(problem.init, key=str))
    return (f"(define (problem {problem.name})\n  (:domain {problem.domain})\n"
            f"  (:objects\n{objects})\n  (:init\n{init})\n"
            f"  (:goal (and {_literals(problem.goal)})))\n")


def untold(domain: Domain, problem: Problem) -> str:
    """Why the STRIPS text of ``domain``'s determinisation cannot carry it, so that the
    backends that read text cannot be used; "" if it can."""
    found = {"conditional or quantified effects": [a.name for a in domain.actions if any(
                 o.conditional or o.choices for o in a.outcomes)],
             "a disjunctive or quantified precondition": [a.name for a in domain.actions
                                                          if a.condition is not None]}
    parts = [f"{what} ({', '.join(names)})" for what, names in found.items() if names]
    if problem.goal_alternatives:
        parts.append(f"a goal with alternatives ({problem.source})")
    if not parts:
        return ""
    return (f"{domain.source} has {'; '.join(parts)}, which the STRIPS text read by "
            "pyperplan and unified-planning's plan validator cannot carry; the graph and "
            "clingo planners read the grounded task: use one of them")


def _literals(lits: tuple[Literal, ...]) -> str:
    return " ".join(str(lit.atom) if lit.positive else f"(not {lit.atom})" for lit in lits)
