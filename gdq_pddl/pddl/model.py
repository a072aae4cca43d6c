"""Plain frozen types for a parsed PDDL domain and problem (STRIPS with typing, and the
PPDDL part gdq_pddl reads: probabilistic effects, action costs, a goal reward)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

STUCK = "stuck"
"""The 0-ary predicate whose becoming true is a failed trial (PPDDL domains)."""


@dataclass(frozen=True)
class Atom:
    """A predicate applied to terms (variables ``?x`` or object names)."""

    predicate: str
    args: tuple[str, ...]

    def __str__(self) -> str:
        return "(" + " ".join((self.predicate, *self.args)) + ")"

    @classmethod
    def parse(cls, text: str) -> Atom:
        """``"(at r1)"`` -> ``Atom("at", ("r1",))``, the inverse of ``str`` (ground atoms
        and action names: their names have no spaces or parentheses)."""
        name, *args = text.strip("()").split()
        return cls(name, tuple(args))


@dataclass(frozen=True)
class Literal:
    """An atom or its negation."""

    atom: Atom
    positive: bool = True


@dataclass(frozen=True)
class Junction:
    """``(and ...)`` or ``(or ...)`` of conditions (``kind``; the parser's ``"not"`` and
    ``"imply"`` never leave :func:`~gdq_pddl.pddl.normalise.nnf`)."""

    kind: str
    parts: tuple[Condition, ...]


@dataclass(frozen=True)
class Quantified:
    """``(forall (?x - t ...) body)`` or ``(exists ...)`` (``kind``)."""

    kind: str
    variables: tuple[tuple[str, str], ...]
    body: Condition


Condition = Literal | Junction | Quantified
"""A condition in negation normal form (:mod:`gdq_pddl.pddl.normalise` makes it so):
negation only on atoms, no ``imply``. Equality is the atom ``(= a b)``."""


@dataclass(frozen=True)
class CondEffect:
    """A literal an outcome sets for every binding of ``variables`` (``forall``) under
    which ``condition`` (``when``; None: always) holds where the action is taken."""

    variables: tuple[tuple[str, str], ...]
    condition: Condition | None
    literal: Literal


CostTerm = float | Atom
"""A number, or a function term such as ``(road-length ?from ?to)`` valued in the problem."""


@dataclass(frozen=True)
class Reward:
    """``sign * amount`` added to an outcome's reward (a reward: +1, a cost: -1), for every
    binding of ``variables`` under which ``condition`` (None: always) holds."""

    amount: CostTerm
    sign: float = 1.0
    variables: tuple[tuple[str, str], ...] = ()
    condition: Condition | None = None


@dataclass(frozen=True)
class Outcome:
    """One outcome of a probabilistic action: its probability, the literals it sets, and
    whether it is a failed trial (``stuck``) and its ``conditional`` or quantified effects."""

    probability: float
    effect: tuple[Literal, ...]
    stuck: bool = False
    conditional: tuple[CondEffect, ...] = ()
    rewards: tuple[Reward, ...] = ()
    """Rewards of the outcome or the state; a plain cost is the action's :attr:`Action.cost`."""
    choices: tuple[Choice, ...] = ()
    """Quantified probabilistic effects, drawn once per binding when grounded."""

    def literals(self) -> Iterator[Literal]:
        """Every literal the outcome may set: its own, its conditional effects' and those
        of its choices' outcomes."""
        yield from self.effect
        yield from (c.literal for c in self.conditional)
        for choice in self.choices:
            for o in choice.outcomes:
                yield from o.literals()


@dataclass(frozen=True)
class Choice:
    """``(forall (?x - t ...) EFFECT)`` whose ``EFFECT`` is probabilistic, read as PPDDL
    planners and MDPSim read it: once grounded, one independent draw from ``outcomes``
    (``EFFECT``'s distribution, in terms of ``variables``) per binding of ``variables``,
    as if the bindings' effects stood side by side. ``line``: where the forall is."""

    variables: tuple[tuple[str, str], ...]
    outcomes: tuple[Outcome, ...]
    line: int = 0


@dataclass(frozen=True)
class Action:
    """An action schema: typed parameters, a conjunctive precondition and effect. A PPDDL
    action has ``outcomes`` summing to 1 instead of an ``effect``. ``cost``: the terms its
    cost effects add up (empty: the domain states no cost)."""

    name: str
    parameters: tuple[tuple[str, str], ...]
    precondition: tuple[Literal, ...]
    effect: tuple[Literal, ...]
    line: int = 0
    outcomes: tuple[Outcome, ...] = ()
    cost: tuple[CostTerm, ...] = ()
    condition: Condition | None = None
    """The rest of the precondition beyond its literals (quantifiers, disjunction); such an
    action, or one with conditional effects, has ``outcomes`` even if deterministic."""

    def states_cost(self) -> bool:
        """Whether the action states a cost anywhere (``(increase (total-cost) X)`` or
        ``(decrease (reward) X)``): outside any construct (:attr:`cost`) or inside ``when``,
        ``forall`` or ``probabilistic`` (a :class:`Reward` of sign -1 of an outcome). One
        that states none costs the goal scale's default."""
        def inside(outcomes: tuple[Outcome, ...]) -> bool:
            return any(r.sign < 0 for o in outcomes for r in o.rewards) or any(
                inside(c.outcomes) for o in outcomes for c in o.choices)
        return bool(self.cost) or inside(self.outcomes)


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
    reward_effects: bool = False
    """Some effect changes ``(reward)`` (the IPPC's reward-oriented problems)."""

    @property
    def probabilistic(self) -> bool:
        """A PPDDL domain: it declares ``:probabilistic-effects`` or has such an effect."""
        return ":probabilistic-effects" in self.requirements or \
            any(a.outcomes for a in self.actions)

    def fluent_predicates(self) -> frozenset[str]:
        """Predicates some action (some outcome of it) changes; the others are static."""
        return frozenset(lit.atom.predicate for a in self.actions
                         for lits in (a.effect, *(o.literals() for o in a.outcomes))
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
    metric: str | None = None
    """``"maximize (reward)"`` or ``"minimize (total-cost)"``, if given."""
    goal_alternatives: tuple[tuple[Literal, ...], ...] = ()
    """A goal's alternatives once grounded, one of which must hold besides ``goal`` (the
    literals all share). Empty: ``goal`` alone."""
