"""The ground effects of an action schema, before a problem's facts are indexed: each
outcome of a schema under one binding of its parameters as fact sets (:data:`Ground`),
its choices drawn side by side and equal effects merged (:func:`ground_outcomes`; a
STRIPS action's effect is its one outcome, :func:`outcomes_of`); and which of them the
planner's determinisation keeps and under what names (:data:`DETERMINISATIONS`,
:func:`kept_outcomes`, :func:`planner_names`, :func:`kept_ground`). The one grounder,
:func:`gdq_pddl.pddl.grounding.ground`, turns them into
:class:`~gdq_pddl.pddl.grounding.GroundOutcome` bitmasks.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl.model import Action, Atom, Choice, Domain, Junction, Literal, Outcome
from gdq_pddl.pddl.normalise import MAX_ATOMS, TRUE, extend, ground_dnf
from gdq_pddl.pddl.parser import MAX_OUTCOMES

DETERMINISATIONS = ("all-outcomes", "most-likely")
"""What the planner knows of a PPDDL domain (``docs/domains.md``): every outcome of an
action is a planner action, or only its most likely one; first: the default."""


def outcomes_of(action: Action) -> tuple[Outcome, ...]:
    """``action``'s outcomes; a STRIPS action's effect is its one outcome."""
    return action.outcomes or (Outcome(1.0, action.effect),)


Ground = tuple[frozenset[str], frozenset[str], tuple[tuple, ...], float, tuple, bool]
"""A ground outcome's effect as fact sets: adds, deletes, conditional effects ``(must hold,
must not hold, adds, deletes)``, the reward it always earns, its conditional rewards
``(alternatives, amount)`` and whether it is a failed trial; equal ones are one outcome."""
def ground_outcomes(action: Action, args: tuple[str, ...], b: dict[str, str], objects,
                     static, fluent: frozenset[str], too_many, value,
                     source: str) -> list[tuple[int, float, Ground]]:
    """The ground outcomes of ``action`` under binding ``b``: ``(index of the outcome of
    the schema it comes from, probability, effect)``; one per schema outcome but where a
    :class:`~gdq_pddl.pddl.model.Choice` expands, refused past :data:`MAX_OUTCOMES`."""
    def past(choice: Choice | None) -> PDDLError:
        where = f"the forall at line {choice.line} " if choice is not None else ""
        return PDDLError(source, (choice.line if choice else action.line) or None,
                         f"action {action.name}: {str(Atom(action.name, args))} has more than "
                         f"{MAX_OUTCOMES} outcomes once {where}is grounded over the "
                         "problem's objects (each binding of a forall of a probabilistic "
                         "effect is an independent draw: their outcomes multiply)")

    out = [(k, p, g) for k, o in enumerate(outcomes_of(action))
           for p, g in _ground_outcome(o, b, objects, static, fluent, too_many, value, past)]
    if len(out) > MAX_OUTCOMES:
        raise past(None)
    return out


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
        return [(o.probability, (frozenset(), frozenset(), (), 0.0, (), False))]
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
            draw = _merged([g for inner in choice.outcomes for g in _ground_outcome(
                inner, bb, objects, static, fluent, too_many, value, past)])
            out = _merged([(p * q, _both(x, y)) for p, x in out for q, y in draw])
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


def _both(x: Ground, y: Ground) -> Ground:
    """Two effects side by side (a failed trial has no other effect)."""
    if x[5] or y[5]:
        return (frozenset(), frozenset(), (), x[3] + y[3], x[4] + y[4], True)
    return (x[0] | y[0], x[1] | y[1], tuple(dict.fromkeys(x[2] + y[2])), x[3] + y[3],
            x[4] + y[4], False)


def _merged(dist: list[tuple[float, Ground]]) -> list[tuple[float, Ground]]:
    """``dist`` with equal effects one outcome (first appearance first)."""
    out: dict[Ground, float] = {}
    for p, g in dist:
        out[g] = out.get(g, 0.0) + p
    return [(p, g) for g, p in out.items()]


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
