"""Conditions normalised in one place, so that grounding never sees PDDL syntax: negation
normal form (:func:`nnf`), plain conjunctions (:func:`conjunction`), and ground
disjunctive normal form for one binding (:func:`ground_dnf`)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Mapping

from gdq_pddl.pddl.model import Atom, Condition, Junction, Literal, Quantified

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
    if isinstance(cond, Quantified):
        parts = [ground_dnf(cond.body, b, objects, static, too_many, budget)
                 for b in extend(binding, cond.variables, objects, budget[0], too_many)]
        return _all(parts, too_many) if cond.kind == "forall" else _any(parts, too_many)
    parts = [ground_dnf(p, binding, objects, static, too_many, budget) for p in cond.parts]
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


def _any(parts: list[list[Disjunct]], too_many: Callable[[], Exception]) -> list[Disjunct]:
    out: dict[Disjunct, None] = {}
    for part in parts:
        if part == TRUE:
            return TRUE
        out.update(dict.fromkeys(part))
        if len(out) > MAX_DISJUNCTS:
            raise too_many()
    return list(out)


def _all(parts: list[list[Disjunct]], too_many: Callable[[], Exception]) -> list[Disjunct]:
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
