"""The ground effects of an action schema, before a problem's facts are indexed: each
outcome of a schema under one binding of its parameters as fact sets (:data:`Ground`),
its choices drawn side by side and equal effects merged (:func:`ground_outcomes`; a
STRIPS action's effect is its one outcome, :func:`outcomes_of`); and which of them the
planner's determinisation keeps and under what names (:data:`DETERMINISATIONS`,
:func:`kept_outcomes`, :func:`planner_names`, :func:`kept_ground`); what a ground action
costs whatever happens (:func:`action_cost`, its terms valued by :func:`term_value`).
The one grounder,
:func:`gdq_pddl.pddl.grounding.ground`, turns them into
:class:`~gdq_pddl.pddl.grounding.GroundOutcome` bitmasks.

Where an action's outcomes are independent draws too many to list, it is kept as its
parts (:mod:`gdq_pddl.pddl.factored`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl.factored import NOTHING, Factored, Ground, factor, merged, times
from gdq_pddl.pddl.model import Action, Atom, Choice, Domain, Junction, Literal, Outcome, Problem
from gdq_pddl.pddl.normalise import MAX_ATOMS, TRUE, extend, ground_dnf
from gdq_pddl.pddl.parser import MAX_OUTCOMES

DETERMINISATIONS = ("all-outcomes", "most-likely")
"""What the planner knows of a PPDDL domain (``docs/domains.md``): every outcome of an
action is a planner action, or only its most likely one; first: the default."""


def outcomes_of(action: Action) -> tuple[Outcome, ...]:
    """``action``'s outcomes; a STRIPS action's effect is its one outcome."""
    return action.outcomes or (Outcome(1.0, action.effect),)


def ground_outcomes(action: Action, args: tuple[str, ...], b: dict[str, str], objects,
                    static, fluent: frozenset[str], too_many, value,
                    source: str) -> list[tuple[int, float, Ground]] | Factored:
    """The ground outcomes of ``action`` under binding ``b``: ``(index of the outcome of
    the schema it comes from, probability, effect)``; one per schema outcome but where a
    :class:`~gdq_pddl.pddl.model.Choice` expands, refused past :data:`MAX_OUTCOMES`.
    Where every outcome of the schema has the same choices and the product of its parts
    is too large to list, the action is kept :class:`Factored` instead
    (:func:`~gdq_pddl.pddl.factored.factor`); refused still where one part alone passes
    :data:`MAX_OUTCOMES`."""
    def past(choice: Choice | None) -> PDDLError:
        where = f"the forall at line {choice.line} " if choice is not None else ""
        return PDDLError(source, (choice.line if choice else action.line) or None,
                         f"action {action.name}: {str(Atom(action.name, args))} has more than "
                         f"{MAX_OUTCOMES} outcomes once {where}is grounded over the "
                         "problem's objects (each binding of a forall of a probabilistic "
                         "effect is an independent draw: their outcomes multiply)")

    outs = outcomes_of(action)
    choices = outs[0].choices
    off = [_guarded_off(o, b, static) for o in outs]
    if choices and not all(off) and all(o.choices == choices for o in outs):
        out = _shared_choices(action, b, objects, static, fluent, too_many, value, past, off)
    else:
        out = [(k, p, g) for k, o in enumerate(outs)
               for p, g in _ground_outcome(o, b, objects, static, fluent, too_many, value,
                                           past)]
    if isinstance(out, list) and len(out) > MAX_OUTCOMES:
        raise past(None)
    return out


def _shared_choices(action: Action, b: dict[str, str], objects, static, fluent, too_many,
                    value, past: Callable[[Choice], PDDLError], off: list[bool]
                    ) -> list[tuple[int, float, Ground]] | Factored:
    """:func:`ground_outcomes` of an action whose schema outcomes all have the same
    choices (``off``: which of them set nothing under ``b``): each choice binding's draw
    made once; :class:`Factored` where :func:`~gdq_pddl.pddl.factored.factor` keeps it so
    (and no outcome is off), else listed exactly as :func:`_ground_outcome` lists each
    outcome (its own effect, then its choices' draws side by side, in order, equal
    effects merged)."""
    outs = outcomes_of(action)
    draws = []
    for choice in outs[0].choices:
        for bb in extend(b, choice.variables, objects, MAX_ATOMS, too_many):
            draws.append((choice, merged([g for inner in choice.outcomes for g in
                                           _ground_outcome(inner, bb, objects, static, fluent,
                                                           too_many, value, past)])))
    own = [_ground_outcome(o, b, objects, static, fluent, too_many, value, past)[0]
           for o in _without_choices(action)]
    kept = None if any(off) else factor(own, [d for _, d in draws])
    if kept is not None:
        return kept
    listed: list[tuple[int, float, Ground]] = []
    for k, (o, first) in enumerate(zip(outs, own, strict=True)):
        if off[k]:  # it sets nothing under b (as _ground_outcome skips its choices)
            listed.append((k, o.probability, NOTHING))
            continue
        out = [first]
        for choice, draw in draws:
            out = times(out, draw)
            if len(out) > MAX_OUTCOMES:
                raise past(choice)
        listed += [(k, p, g) for p, g in out]
    return listed


_STRIPPED: dict[int, tuple[Action, tuple[Outcome, ...]]] = {}


def _without_choices(action: Action) -> tuple[Outcome, ...]:
    """``action``'s outcomes without their choices (cached by identity: the guards of an
    outcome are cached by its identity too)."""
    hit = _STRIPPED.get(id(action))
    if hit is None or hit[0] is not action:
        hit = _STRIPPED[id(action)] = (action, tuple(replace(o, choices=())
                                                     for o in outcomes_of(action)))
    return hit[1]


def _ground_outcome(o: Outcome, b: dict[str, str], objects, static, fluent: frozenset[str],
                    too_many, value, past: Callable[[Choice], PDDLError],
                    ) -> list[tuple[float, Ground]]:
    """The distribution of outcome ``o`` (its probability included) under binding ``b``:
    its own effect, and side by side one draw per binding of each of its choices, equal
    effects merged (``value(term, binding)``: an amount; ``past(choice)``: the error past
    :data:`~gdq_pddl.pddl.parser.MAX_OUTCOMES` outcomes)."""
    def fact(lit: Literal, binding: Mapping[str, str]) -> str:
        return str(Atom(lit.atom.predicate, tuple(binding.get(x, x) for x in lit.atom.args)))

    if _guarded_off(o, b, static):  # it sets nothing under b: skip its choices' bindings
        return [(o.probability, NOTHING)]
    add = frozenset(fact(lit, b) for lit in o.effect
                    if lit.positive and lit.atom.predicate in fluent)
    dele = frozenset(fact(lit, b) for lit in o.effect
                     if not lit.positive and lit.atom.predicate in fluent)
    conds: dict[tuple, None] = {}
    for ce in o.conditional:
        for bb in extend(b, ce.variables, objects, MAX_ATOMS, too_many):
            when = TRUE if ce.condition is None else \
                ground_dnf(ce.condition, bb, objects, static, too_many)
            f = frozenset((fact(ce.literal, bb),))
            for cp, cn in when:  # in the order written: the planner's variants are named so
                conds[(cp, cn, f if ce.literal.positive else frozenset(),
                       frozenset() if ce.literal.positive else f)] = None
    reward, rewards = 0.0, []
    for rw in o.rewards:
        for bb in extend(b, rw.variables, objects, MAX_ATOMS, too_many):
            when = TRUE if rw.condition is None else \
                ground_dnf(rw.condition, bb, objects, static, too_many)
            amount = rw.sign * value(rw.amount, bb)
            if when == TRUE:
                reward += amount
            elif when:
                rewards.append((tuple(when), amount))
    out = [(o.probability, (add, dele, tuple(conds), reward, tuple(rewards), o.stuck))]
    for choice in o.choices:
        for bb in extend(b, choice.variables, objects, MAX_ATOMS, too_many):
            draw = merged([g for inner in choice.outcomes for g in _ground_outcome(
                inner, bb, objects, static, fluent, too_many, value, past)])
            out = times(out, draw)
            if len(out) > MAX_OUTCOMES:
                raise past(choice)
    return out


def _conjuncts(cond) -> tuple[Literal, ...]:
    """The literals ``cond`` requires at its top: itself, or those of (nested) ``and``s."""
    if isinstance(cond, Literal):
        return (cond,)
    if isinstance(cond, Junction) and cond.kind == "and":
        return tuple(lit for part in cond.parts for lit in _conjuncts(part))
    return ()


_GUARDS: dict[int, tuple[Outcome, frozenset[Literal]]] = {}


def _guards(o: Outcome) -> frozenset[Literal]:
    """Literals every effect of ``o`` is conditioned on (its every conditional effect's
    condition, through its choices' outcomes, requires each of them; no variable a forall
    inside binds), so that where one is false ``o`` sets nothing; empty where ``o`` has an
    unconditional effect, a reward or a failed trial (cached by identity)."""
    hit = _GUARDS.get(id(o))
    if hit is not None and hit[0] is o:
        return hit[1]
    if o.effect or o.rewards or o.stuck or not (o.conditional or o.choices):
        out: frozenset[Literal] = frozenset()
    else:
        sets = [frozenset(lit for lit in _conjuncts(ce.condition)
                          if not {v for v, _ in ce.variables} & set(lit.atom.args))
                for ce in o.conditional]
        for choice in o.choices:
            bound = {v for v, _ in choice.variables}
            sets += [frozenset(lit for lit in _guards(inner) if not bound & set(lit.atom.args))
                     for inner in choice.outcomes]
        out = frozenset.intersection(*sets)
    _GUARDS[id(o)] = (o, out)
    return out


def _guarded_off(o: Outcome, b: Mapping[str, str], static) -> bool:
    """Whether a literal of :func:`_guards` is false under ``b`` in every state (a static
    atom, or an equality): ``o`` then sets nothing, and grounding its choices' bindings
    one by one (IPPC boxworld's drive: 1,000 bindings of three nested foralls per ground
    action, all but one under a static ``when`` that fails) would find only that."""
    for lit in _guards(o):
        atom = Atom(lit.atom.predicate, tuple(b.get(a, a) for a in lit.atom.args))
        truth = atom.args[0] == atom.args[1] if atom.predicate == "=" else static(atom)
        if truth is not None and truth != lit.positive:
            return True
    return False


def kept_outcomes(action: Action, determinisation: str) -> tuple[int, ...]:
    """Indices of ``action``'s outcomes that are planner actions (a STRIPS action: 0);
    ``determinisation`` is checked by :func:`planner_names`."""
    if not action.outcomes:
        return (0,)
    useful = [k for k, o in enumerate(action.outcomes)
              if o.probability > 0 and not o.stuck and (o.effect or o.conditional or o.choices)]
    if determinisation == "all-outcomes":
        return tuple(useful)
    best = max(range(len(action.outcomes)), key=lambda k: (action.outcomes[k].probability, -k))
    return (best,) if best in useful else ()


def planner_names(domain: Domain, determinisation: str) -> dict[tuple[str, int], str]:
    """``(schema, outcome index) -> planner schema name`` of every kept outcome."""
    if determinisation not in DETERMINISATIONS:
        raise ValueError(f"unknown determinisation {determinisation!r} (known: "
                         f"{', '.join(DETERMINISATIONS)})")
    taken = {a.name for a in domain.actions}
    out: dict[tuple[str, int], str] = {}
    for action in domain.actions:
        kept = kept_outcomes(action, determinisation)
        for k in kept:
            name = action.name if len(kept) == 1 else f"{action.name}_o{k + 1}"
            if name != action.name and name in taken:
                raise PDDLError(domain.source, action.line, f"action {action.name}: its "
                                f"outcome {k + 1} would be the planner action {name}, which is "
                                "already an action of the domain; rename one of them")
            out[(action.name, k)] = name
    return out


def kept_ground(action: Action, outs: list[tuple[int, float, Ground]], outcomes: tuple,
                determinisation: str, names: dict[tuple[str, int], str]
                ) -> tuple[tuple[int, ...], tuple[str, ...]]:
    """The ground outcomes ``outs`` (:func:`ground_outcomes`; ``outcomes``: the same as
    :class:`~gdq_pddl.pddl.grounding.GroundOutcome`) the planner keeps and their
    planner schema names: those of :func:`kept_outcomes` where each schema outcome is one
    ground outcome; where a choice expands one into several, each that does something
    (``_c<j>`` after the schema outcome's name), or the most likely (named as the action)."""
    if len(outs) == len(outcomes_of(action)):
        known = kept_outcomes(action, determinisation)
        return known, tuple(names[(action.name, k)] for k in known)

    def useful(i: int) -> bool:
        o = outcomes[i]
        return o.probability > 0 and not o.stuck and bool(o.add or o.dele or o.conditional)

    if determinisation != "all-outcomes":
        best = max(range(len(outs)), key=lambda i: (outs[i][1], -i))
        return ((best,), (action.name,)) if useful(best) else ((), ())
    schema = kept_outcomes(action, determinisation)
    count = {k: sum(1 for kk, _, _ in outs if kk == k) for k in schema}
    known: list[int] = []
    kept: list[str] = []
    seen: dict[int, int] = {}
    for i, (k, _, _) in enumerate(outs):
        seen[k] = seen.get(k, 0) + 1
        if k in count and useful(i):
            known.append(i)
            kept.append(names[(action.name, k)] + (f"_c{seen[k]}" if count[k] > 1 else ""))
    return tuple(known), tuple(kept)


def term_value(term: float | Atom, binding: Mapping[str, str], domain: Domain, problem: Problem,
               action: Action, what: str) -> float:
    """A cost or reward term under ``binding``: a number, or a function term valued in
    the problem's ``:init`` (refused, naming it, where it has no value or a negative one)."""
    if not isinstance(term, Atom):
        return term
    key = str(Atom(term.predicate, tuple(binding.get(a, a) for a in term.args)))
    if key not in problem.values:
        raise PDDLError(problem.source, None, f"no value for {key} in :init ({what}, "
                        f"{domain.source}:{action.line})")
    value = problem.values[key]
    if value < 0:
        raise PDDLError(problem.source, None, f"{key} = {value:g} in :init: {what} must be "
                        ">= 0")
    return value


def action_cost(action: Action, args: tuple[str, ...], domain: Domain,
                problem: Problem) -> float | None:
    """:attr:`GroundOp.cost` of ``action`` with parameters ``args``: its terms outside every
    construct summed, 0 where it states costs only inside them, None where none at all."""
    if not action.states_cost():
        return None
    binding = dict(zip((p for p, _ in action.parameters), args, strict=True))
    name = str(Atom(action.name, args))
    return float(sum(term_value(term, binding, domain, problem, action, f"the cost of {name}")
                     for term in action.cost))
