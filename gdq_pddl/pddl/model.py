"""Plain frozen types for a parsed PDDL domain and problem (STRIPS with typing, and the
PPDDL part gdq_pddl reads: probabilistic effects, action costs, a goal reward)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field


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
class Outcome:
    """One outcome of a probabilistic action: its probability and the literals it makes
    true or false. ``stuck``: the outcome makes ``(stuck)`` true, a failed trial."""

    probability: float
    effect: tuple[Literal, ...]
    stuck: bool = False


CostTerm = float | Atom
"""A number, or a function term such as ``(road-length ?from ?to)`` valued in the problem."""


@dataclass(frozen=True)
class Action:
    """An action schema: typed parameters, a conjunctive precondition and effect.

    A PPDDL action has ``outcomes`` (its effect flattened into a distribution that sums
    to 1, the leftover probability as an outcome with no effect; ``effect`` is then
    empty); a STRIPS action has none. ``cost`` lists the terms its
    ``(increase (total-cost) X)`` / ``(decrease (reward) X)`` effects add up, or is
    empty when the domain states no cost.
    """

    name: str
    parameters: tuple[tuple[str, str], ...]
    precondition: tuple[Literal, ...]
    effect: tuple[Literal, ...]
    line: int = 0
    outcomes: tuple[Outcome, ...] = ()
    cost: tuple[CostTerm, ...] = ()


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
    functions: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    """Declared numeric functions (``:functions``) and their parameter types."""

    @property
    def probabilistic(self) -> bool:
        """A PPDDL domain: it declares ``:probabilistic-effects`` or has such an effect."""
        return ":probabilistic-effects" in self.requirements or \
            any(a.outcomes for a in self.actions)

    def fluent_predicates(self) -> frozenset[str]:
        """Predicates some action (some outcome of it) changes; the others are static."""
        return frozenset(lit.atom.predicate for a in self.actions
                         for lits in (a.effect, *(o.effect for o in a.outcomes))
                         for lit in lits)


@dataclass(frozen=True)
class Problem:
    """A parsed problem: typed objects (constants included), initial atoms, goal literals."""

    name: str
    domain: str
    objects: Mapping[str, str]
    init: frozenset[Atom]
    goal: tuple[Literal, ...]
    source: str = "<problem>"
    values: Mapping[str, float] = field(default_factory=dict)
    """Function values of ``:init`` (``(= (road-length a b) 3)``), keyed ``"(road-length a b)"``."""
    goal_reward: float | None = None
    """PPDDL's ``(:goal-reward N)``, if given."""
