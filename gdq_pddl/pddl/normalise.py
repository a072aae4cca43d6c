"""Conditions normalised in one place, so that grounding never sees PDDL syntax: negation
normal form (:func:`nnf`), plain conjunctions (:func:`conjunction`), and ground
disjunctive normal form for one binding (:func:`ground_dnf`); and the bindings of an
action's parameters that meet its static preconditions (:func:`action_bindings`, over
the objects and static atoms :func:`index_problem` indexes)."""

from __future__ import annotations

import itertools
import math
from collections import defaultdict
from collections.abc import Callable, Iterable, Iterator, Mapping

from gdq_pddl.pddl.formulas import is_subtype
from gdq_pddl.pddl.model import (
    Action,
    Atom,
    Condition,
    Domain,
    Junction,
    Literal,
    Problem,
    Quantified,
)

MAX_DISJUNCTS = 4096
"""Most alternatives one ground condition may expand into."""
MAX_ATOMS = 1_000_000
"""Most atoms one ground condition may expand into (nested quantifiers multiply)."""

Disjunct = tuple[frozenset[str], frozenset[str]]
"""A conjunction of ground fluent literals: the atoms that must hold, those that must not."""
TRUE: list[Disjunct] = [(frozenset(), frozenset())]
FALSE: list[Disjunct] = []


def nnf(cond: Condition, positive: bool = True) -> Condition:
    """``cond`` (or its negation) with negations on atoms only and no ``imply``."""
    if isinstance(cond, Literal):
        return cond if positive else Literal(cond.atom, not cond.positive)
    if isinstance(cond, Quantified):
        kind = cond.kind if positive else {"forall": "exists", "exists": "forall"}[cond.kind]
        return Quantified(kind, cond.variables, nnf(cond.body, positive))
    if cond.kind == "not":
        return nnf(cond.parts[0], not positive)
    if cond.kind == "imply":  # a -> b  ==  (not a) or b
        return nnf(Junction("or", (Junction("not", (cond.parts[0],)), cond.parts[1])),
                   positive)
    kind = cond.kind if positive else {"and": "or", "or": "and"}[cond.kind]
    return Junction(kind, tuple(nnf(p, positive) for p in cond.parts))


def conjunction(cond: Condition) -> tuple[Literal, ...] | None:
    """The literals of ``cond`` in order if it is (nested ``and`` of) literals, else None."""
    if isinstance(cond, Literal):
        return (cond,)
    if isinstance(cond, Junction) and cond.kind == "and":
        out: list[Literal] = []
        for part in cond.parts:
            lits = conjunction(part)
            if lits is None:
                return None
            out += lits
        return tuple(out)
    return None


_SEEN: list = [None, {}]
"""The ``static`` of the problem being grounded (compared by identity), and the ground
alternatives of each quantified condition under each binding found so far for it
(:func:`forget` empties it)."""


def forget() -> None:
    """Drop what :func:`ground_dnf` keeps of the problem grounded last."""
    _SEEN[:] = [None, {}]


def ground_dnf(cond: Condition, binding: Mapping[str, str],
               objects: Callable[[str], list[str]], static: Callable[[Atom], bool | None],
               too_many: Callable[[], Exception],
               budget: list[int] | None = None) -> list[Disjunct]:
    """``cond`` (NNF) under ``binding`` as alternatives of fluent literals (``[]``: never
    holds; :data:`TRUE`: always). ``objects(type)``: the objects of a type; ``static(atom)``:
    the truth of an atom no action changes (None: a fluent); ``too_many()``: the error past
    :data:`MAX_DISJUNCTS` alternatives or ``budget`` (:data:`MAX_ATOMS`) atoms."""
    if budget is None:
        budget = [MAX_ATOMS]
    if isinstance(cond, Literal):
        budget[0] -= 1
        if budget[0] < 0:
            raise too_many()
        atom = Atom(cond.atom.predicate, tuple(binding.get(a, a) for a in cond.atom.args))
        truth = atom.args[0] == atom.args[1] if atom.predicate == "=" else static(atom)
        if truth is not None:
            return TRUE if truth == cond.positive else FALSE
        fact = frozenset((str(atom),))
        return [(fact, frozenset())] if cond.positive else [(frozenset(), fact)]
    # the parts one at a time: a conjunction stops at a part that never holds, a
    # disjunction at one that always does (sysadmin's exists over pairs of computers: a
    # static (conn ?c ?d) false for most ?c spares the rest)
    if isinstance(cond, Quantified):  # once a binding (an effect may repeat a condition)
        if _SEEN[0] is not static:
            _SEEN[:] = [static, {}]
        key = (id(cond), tuple(binding.items()))
        hit = _SEEN[1].get(key)
        if hit is not None and hit[0] is cond:
            return hit[1]
        parts = (ground_dnf(cond.body, b, objects, static, too_many, budget)
                 for b in extend(binding, cond.variables, objects, budget[0], too_many))
        out = _all(parts, too_many) if cond.kind == "forall" else _any(parts, too_many)
        _SEEN[1][key] = (cond, out)
        return out
    parts = (ground_dnf(p, binding, objects, static, too_many, budget) for p in cond.parts)
    return _all(parts, too_many) if cond.kind == "and" else _any(parts, too_many)


def extend(binding: Mapping[str, str], variables: tuple[tuple[str, str], ...],
           objects: Callable[[str], list[str]], limit: int,
           too_many: Callable[[], Exception]) -> Iterator[dict[str, str]]:
    """``binding`` extended by every assignment of objects to the typed ``variables``;
    ``too_many()`` is raised up front if there are more than ``limit``."""
    domains = [objects(t) for _, t in variables]
    if math.prod(len(d) for d in domains) > limit:
        raise too_many()
    for values in itertools.product(*domains):
        yield {**binding, **dict(zip((v for v, _ in variables), values, strict=True))}


def _any(parts: Iterable[list[Disjunct]], too_many: Callable[[], Exception]) -> list[Disjunct]:
    out: dict[Disjunct, None] = {}
    for part in parts:
        if part == TRUE:
            return TRUE
        out.update(dict.fromkeys(part))
        if len(out) > MAX_DISJUNCTS:
            raise too_many()
    return list(out)


def _all(parts: Iterable[list[Disjunct]], too_many: Callable[[], Exception]) -> list[Disjunct]:
    out = TRUE
    for part in parts:
        if not part:
            return FALSE
        nxt: dict[Disjunct, None] = {}
        for pos, neg in out:
            for p, n in part:
                both = (pos | p, neg | n)
                if not both[0] & both[1]:  # a contradiction never holds
                    nxt[both] = None
        if len(nxt) > MAX_DISJUNCTS:
            raise too_many()
        out = list(nxt)
        if not out:
            return FALSE
    return out


def index_problem(domain: Domain, problem: Problem) -> tuple[
        frozenset[str], dict[str, set[tuple[str, ...]]], dict[str, list[str]],
        dict[str, frozenset[str]]]:
    """The fluent predicates, the static atoms' arguments by predicate, and the objects
    of each type (sorted, and as a set): what :func:`action_bindings` reads."""
    fluent = domain.fluent_predicates()
    static_tuples: dict[str, set[tuple[str, ...]]] = defaultdict(set)
    for a in problem.init:
        if a.predicate not in fluent:
            static_tuples[a.predicate].add(a.args)
    by_type = {t: sorted(o for o, ot in problem.objects.items() if is_subtype(domain.types, ot, t))
               for t in domain.types}
    return fluent, static_tuples, by_type, {t: frozenset(o) for t, o in by_type.items()}


def action_bindings(action: Action, static_tuples: dict[str, set[tuple[str, ...]]],
                    by_type: dict[str, list[str]], typed: dict[str, frozenset[str]],
                    fluent: frozenset[str]):
    """Yield every parameter binding that satisfies the static preconditions."""
    params = dict(action.parameters)
    fixed = [lit for lit in action.precondition if lit.atom.predicate not in fluent]
    equalities = [lit for lit in fixed if lit.atom.predicate == "="]
    statics = [lit.atom for lit in fixed if lit.positive and lit.atom.predicate != "="]
    neg_statics = [lit.atom for lit in fixed if not lit.positive and lit.atom.predicate != "="]
    bindings: list[dict[str, str]] = [{}]
    todo = list(statics)
    while todo and bindings:
        bound = bindings[0].keys()
        atom = max(todo, key=lambda a: (sum(1 for x in a.args if x in bound or x[0] != "?"),
                                        -len(static_tuples.get(a.predicate, ()))))
        todo.remove(atom)
        known = tuple(i for i, x in enumerate(atom.args) if x in bound or x[0] != "?")
        index: dict[tuple[str, ...], list[tuple[str, ...]]] = defaultdict(list)
        # sorted: set order follows Python's per-process string hashing, and the order of
        # ground actions (a PDDL env's action indices) must not
        for tup in sorted(static_tuples.get(atom.predicate, ())):
            index[tuple(tup[i] for i in known)].append(tup)
        nxt = []
        for b in bindings:
            for tup in index.get(tuple(b.get(atom.args[i], atom.args[i]) for i in known), ()):
                nb = dict(b)
                if all(x[0] != "?" or nb.setdefault(x, v) == v
                       for x, v in zip(atom.args, tup, strict=True)):
                    nxt.append(nb)
        bindings = nxt
    for b in bindings:
        free = [p for p in params if p not in b]
        for values in itertools.product(*(by_type.get(params[p], ()) for p in free)):
            full = dict(b, **dict(zip(free, values, strict=True)))
            if (all(full[p] in typed.get(t, ()) for p, t in params.items())
                    and not any(tuple(full.get(x, x) for x in a.args)
                                in static_tuples.get(a.predicate, ()) for a in neg_statics)
                    and all((full.get(e.atom.args[0], e.atom.args[0])
                             == full.get(e.atom.args[1], e.atom.args[1])) == e.positive
                            for e in equalities)):
                yield full
