"""The problem reader: a ``(define (problem NAME) ...)`` for a parsed domain (its objects,
initial state and numeric values, goal, goal reward and metric), read with file:line
errors into :class:`~gdq_pddl.pddl.model.Problem`; the goal's quantifiers are expanded
over the problem's objects. One file may hold the domain and several problems
(:func:`problem_file`)."""

from __future__ import annotations

from pathlib import Path

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl.formulas import (
    COST_FLUENTS,
    bare_term,
    is_subtype,
    read_atom,
    read_condition,
    read_number,
    read_requirements,
    read_term,
)
from gdq_pddl.pddl.model import Atom, Domain, Literal, Problem
from gdq_pddl.pddl.normalise import MAX_ATOMS, MAX_DISJUNCTS, conjunction, ground_dnf, nnf
from gdq_pddl.pddl.sexpr import Node, Reader, read_pddl_text

_COST_TERMS = tuple(f"({f})" for f in COST_FLUENTS)
_PROBLEM_SECTIONS = (":domain", ":requirements", ":objects", ":init", ":goal", ":goal-reward",
                     ":metric")


def parse_problem(text: str, domain: Domain, source: str = "<problem>",
                  name: str | None = None) -> Problem:
    """Parse a problem for ``domain``; raise :class:`PDDLError` if it does not fit.
    ``name`` picks one of several problems in ``text`` (which may hold the domain too)."""
    r = Reader(text, source, domain)
    top, name, body = r.pick("problem", name)
    sec, _ = r.sections(body, _PROBLEM_SECTIONS, "problem")
    read_requirements(r, sec.get(":requirements"))
    if ":domain" not in sec:
        raise r.fail(top.line, "expected (:domain NAME)")
    dnode = sec[":domain"]
    dname = r.symbol(dnode.items[1], "a domain name") if len(dnode.items) == 2 else None
    if dname != domain.name:
        raise r.fail(dnode.line, f"problem is for domain {dname!r}, but the domain is "
                     f"{domain.name!r} ({domain.source})")
    objects = dict(domain.constants)
    if ":objects" in sec:
        for o, t, line in r.typed_list(sec[":objects"].items[1:], False, "object"):
            if o in objects:
                raise r.fail(line, f"object {o} is declared twice (as a constant of the "
                             f"domain, {domain.source})")
            objects[o] = t
    if ":init" not in sec:
        raise r.fail(top.line, "expected (:init ...), the initial state")
    init, values = [], {}
    given: dict[str, tuple[float, Node]] = {}  # function term -> its value, where given
    for node in sec[":init"].items[1:]:
        head = node.items[0].symbol if node.is_list and node.items else ""
        if head == "=":
            term, value = _init_value(r, node, objects)
            first, where = given.setdefault(term, (value, node))
            if first != value:  # the same value twice is the same fact twice: allowed
                raise r.fail(node.line, f"init: {term} is given two values, "
                             f"{where.items[2].symbol} (line {where.line}) and "
                             f"{node.items[2].symbol}; give it one")
            values[term] = 0.0 if term in _COST_TERMS else value
            continue
        if head == "probabilistic":
            raise r.fail(node.line, "init: a probabilistic initial state is not supported "
                         "(the learner starts in one state)")
        init.append(read_atom(r, node, objects, "init"))
    goal_reward = _goal_reward(r, sec[":goal-reward"]) if ":goal-reward" in sec else None
    metric = _metric(r, sec[":metric"]) if ":metric" in sec else None
    if ":goal" not in sec:
        raise r.fail(top.line, "expected (:goal ...)")
    gnode = sec[":goal"]
    if len(gnode.items) != 2:
        raise r.fail(gnode.line, f"expected (:goal FORMULA), one formula; found "
                     f"{len(gnode.items) - 1}")
    goal, alternatives = _goal(r, gnode.items[1], domain, objects, init)
    return Problem(name, domain.name, objects, frozenset(init), goal, source, values,
                   goal_reward, metric, alternatives)


def _goal(r: Reader, node: Node, domain: Domain, objects: dict[str, str], init: list[Atom],
          ) -> tuple[tuple[Literal, ...], tuple[tuple[Literal, ...], ...]]:
    """The goal as the literals all its alternatives share, and the alternatives (none:
    a conjunction), quantifiers expanded and atoms no action changes decided."""
    cond = nnf(read_condition(r, node, objects, "goal"))
    lits = conjunction(cond)
    if lits is not None:
        return lits, ()

    def of_type(t: str) -> list[str]:
        return sorted(o for o, ot in objects.items() if is_subtype(domain.types, ot, t))

    def too_many() -> PDDLError:
        return r.fail(node.line, f"goal: more than {MAX_DISJUNCTS} alternatives or "
                      f"{MAX_ATOMS} atoms once its quantifiers are expanded")

    fluent = domain.fluent_predicates()
    static = frozenset(a for a in init if a.predicate not in fluent)
    try:
        dnf: list | None = ground_dnf(cond, {}, of_type, lambda a: None, too_many)
    except PDDLError:  # e.g. (forall (?b) (exists (?c) (and (destination ?b ?c) ...)))
        dnf = None
    if dnf is None or len(dnf) > 1:  # decide what no action changes, and look again
        dnf = ground_dnf(cond, {}, of_type, lambda a: None if a.predicate in fluent else
                         a in static, too_many)
    if not dnf:
        raise r.fail(node.line, "goal: it can never hold (false for the problem's objects)")

    def literals(pos: frozenset[str], neg: frozenset[str]) -> tuple[Literal, ...]:
        return tuple(Literal(Atom.parse(f), True) for f in sorted(pos)) + \
            tuple(Literal(Atom.parse(f), False) for f in sorted(neg))

    common = literals(frozenset.intersection(*(p for p, _ in dnf)),
                      frozenset.intersection(*(n for _, n in dnf)))
    return common, (tuple(literals(p, n) for p, n in dnf) if len(dnf) > 1 else ())


def _init_value(r: Reader, node: Node, objects: dict[str, str]) -> tuple[str, float]:
    """``(= (f a b) 3)`` in ``:init`` -> ``("(f a b)", 3.0)``."""
    items = r.lst(node, "(= TERM NUMBER)")
    term = bare_term(items[1]) if len(items) == 3 else None
    head = term.items if term is not None and term.is_list else None
    if not head or head[0].is_list:
        raise r.fail(node.line, f"init: expected (= (FUNCTION ARGS...) NUMBER), found "
                     f"{node.text()}")
    fname = head[0].symbol
    if fname in COST_FLUENTS:  # (= (total-cost) 0): where the sum starts; not needed
        term = f"({fname})"
    elif fname not in r.functions:
        raise r.fail(node.line, f"init: unknown function {fname!r} (declared: "
                     f"{', '.join(sorted(r.functions)) or 'none'})")
    else:
        term = str(read_term(r, Node(node.line, head), fname, r.functions[fname], objects, "init"))
    value = read_number(r, items[2], f"init: {term}")
    if value is None:
        raise r.fail(items[2].line, f"init: expected a number for {term}, found "
                     f"{items[2].text()}")
    return term, float(value)


def _goal_reward(r: Reader, node: Node) -> float:
    items = r.lst(node, "(:goal-reward N)")
    value = read_number(r, items[1], ":goal-reward") if len(items) == 2 else None
    if value is None or value <= 0:
        raise r.fail(node.line, f"expected (:goal-reward N) with N > 0, found {node.text()}")
    return float(value)


def _metric(r: Reader, node: Node) -> str:
    """The metric, one of those that keep the task (maximise the reward, minimise costs)."""
    items = r.lst(node, "(:metric maximize (reward))")
    text = Node(node.line, (*items[:2], *map(bare_term, items[2:3]), *items[3:])).text()
    if text not in ("(:metric minimize (total-cost))", "(:metric maximize (reward))"):
        raise r.fail(node.line, f"{node.text()} is not supported: the metrics read are (:metric "
                     "maximize (reward)) and (:metric minimize (total-cost)) "
                     "(docs/domains.md, \"Rewards\")")
    return text[len("(:metric "):-1]


def read_problem(path: str | Path, domain: Domain, name: str | None = None) -> Problem:
    """Read and parse a problem file for ``domain`` (``name``: which one of several)."""
    return parse_problem(read_pddl_text(path), domain, str(path), name)


def problem_file(path: str | Path) -> tuple[str | Path, str | None]:
    """``FILE:NAME`` -> ``(FILE, NAME)``: one problem of a file that holds several; a path
    that exists, or whose part before the last ``:`` does not, is a path."""
    text = str(path)
    head, sep, name = text.rpartition(":")
    if not sep or Path(text).exists() or not Path(head).is_file():
        return path, None
    if not name.strip():
        raise PDDLError(text, None, f"the problem name after {head}: is empty; give "
                        f"{head}:NAME, NAME one of the file's problems, or {head} alone for "
                        "a file that holds one problem")
    return head, name
