"""Plain frozen types for a parsed PDDL domain and problem (STRIPS with typing)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass


@dataclass(frozen=True)
class Atom:
    """A predicate applied to terms (variables ``?x`` or object names)."""

    predicate: str
    args: tuple[str, ...]

    def __str__(self) -> str:
        return "(" + " ".join((self.predicate, *self.args)) + ")"


@dataclass(frozen=True)
class Literal:
    """An atom or its negation."""

    atom: Atom
    positive: bool = True


@dataclass(frozen=True)
class Action:
    """An action schema: typed parameters, a conjunctive precondition and effect."""

    name: str
    parameters: tuple[tuple[str, str], ...]
    precondition: tuple[Literal, ...]
    effect: tuple[Literal, ...]
    line: int = 0


@dataclass(frozen=True)
class Domain:
    """A parsed domain. ``types`` maps each type to its parent (``object`` -> None)."""

    name: str
    requirements: frozenset[str]
    types: Mapping[str, str | None]
    constants: Mapping[str, str]
    predicates: Mapping[str, tuple[str, ...]]
    actions: tuple[Action, ...]
    source: str = "<domain>"

    def fluent_predicates(self) -> frozenset[str]:
        """Predicates some action changes; the others are static."""
        return frozenset(lit.atom.predicate for a in self.actions for lit in a.effect)


@dataclass(frozen=True)
class Problem:
    """A parsed problem: typed objects (constants included), initial atoms, goal literals."""

    name: str
    domain: str
    objects: Mapping[str, str]
    init: frozenset[Atom]
    goal: tuple[Literal, ...]
    source: str = "<problem>"
