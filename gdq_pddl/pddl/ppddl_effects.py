"""The ground effects of an action schema, before a problem's facts are indexed: each
outcome of a schema under one binding of its parameters as fact sets (:data:`Ground`),
its choices drawn side by side and equal effects merged (:func:`ground_outcomes`; a
STRIPS action's effect is its one outcome, :func:`outcomes_of`); and which of them the
planner's determinisation keeps and under what names (:data:`DETERMINISATIONS`,
:func:`kept_outcomes`, :func:`planner_names`, :func:`kept_ground`). The one grounder,
:func:`gdq_pddl.pddl.grounding.ground`, turns them into
:class:`~gdq_pddl.pddl.grounding.GroundOutcome` bitmasks.

**Factored effects.** Each binding of a ``forall`` of a probabilistic effect is an
independent draw, so a ground action's outcomes are the product of its draws: IPPC-2008
sysadmin-slp's ``reboot`` has ``2 x 4^(n-1)`` on ``n`` computers. Where every outcome
of the schema has the same choices (the action is its own outcomes *times* independent
draws, not a mixture of products) and the product of the parts' sizes passes
:data:`FACTORED_ABOVE` (4096), the action is kept :class:`Factored`: its own outcomes
and one part per draw, never multiplied out. Otherwise they are listed, as they always
were. The rule reads the product, not the listing after equal effects merge: finding
the merged size means listing up to 4096 of them, seconds an action (``_merged`` over
fact sets); so an action whose draws merge to at most 4096 outcomes while their product
passes it (draws with equal effects, such as rewards that add up) was listed before and
is factored now, and its problem runs online. None of the public problems that ran
before is such a one (their grounded actions are the same: ``docs/decisions.md``).
Reality draws one outcome of each part of a factored action
(:func:`~gdq_pddl.pddl.grounding.sample_parts`), as the competition's simulator samples
each binding. The knowledge cannot list the product either, so its determinisation is
**each part's outcomes taken one at a time** (:func:`factored_kept`): the outcome of
every part at its most likely outcome, then, for each part, each of its other outcomes
with every other part at its most likely: ``1 + sum(|part| - 1)`` outcomes, growing with
the sum of the parts, not their product. Why this one (``docs/decisions.md``): the
delete relaxation over it is the delete relaxation over every outcome of the product
(each outcome of each part adds its facts in some listed outcome, under the same
precondition and conditions), so h_max, h_add and h_FF, which online exploration and its
V* bound read, are what the listed product would give; its first outcome is the
product's most likely combination of draws (the most likely draw of each independent
part), what ``most-likely`` keeps; and it is the part-by-part reading the issue cites
from the competition's determinising planners. What it leaves out are the combinations in which
two or more parts leave their most likely outcome at once: a replanning learner meets
them as they happen.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl.model import Action, Atom, Choice, Domain, Junction, Literal, Outcome
from gdq_pddl.pddl.normalise import MAX_ATOMS, TRUE, extend, ground_dnf
from gdq_pddl.pddl.parser import MAX_OUTCOMES

FACTORED_ABOVE = MAX_OUTCOMES
"""A ground action whose independent parts' product has more outcomes than this is kept
as its parts (:class:`Factored`), never listed; at most this many, it is listed as it
always was (the module docstring)."""

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
@dataclass(frozen=True)
class Factored:
    """A ground action's effect as independent parts whose product it is: ``parts[0]``
    the action's own outcomes (its top-level distribution, without its choices), then one
    part per binding of each of its choices (:class:`~gdq_pddl.pddl.model.Choice`), each
    a distribution ``(probability, effect)`` summing to 1, equal effects merged; parts
    with one outcome are folded into ``parts[0]``. Reality draws one outcome from every
    part, independently, and applies them side by side."""

    parts: tuple[tuple[tuple[float, Ground], ...], ...]


def ground_outcomes(action: Action, args: tuple[str, ...], b: dict[str, str], objects,
                    static, fluent: frozenset[str], too_many, value,
                    source: str) -> list[tuple[int, float, Ground]] | Factored:
    """The ground outcomes of ``action`` under binding ``b``: ``(index of the outcome of
    the schema it comes from, probability, effect)``; one per schema outcome but where a
    :class:`~gdq_pddl.pddl.model.Choice` expands, refused past :data:`MAX_OUTCOMES`.
    Where every outcome of the schema has the same choices and the product of its parts
    passes :data:`FACTORED_ABOVE`, the action is kept :class:`Factored` instead (the
    module docstring); refused still where one part alone passes :data:`MAX_OUTCOMES`."""
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
    made once; :class:`Factored` where the product of the parts passes
    :data:`FACTORED_ABOVE` (and no outcome is off), else listed exactly as
    :func:`_ground_outcome` lists each outcome (its own effect, then its choices' draws
    side by side, in order, equal effects merged)."""
    outs = outcomes_of(action)
    draws = []
    for choice in outs[0].choices:
        for bb in extend(b, choice.variables, objects, MAX_ATOMS, too_many):
            draws.append((choice, _merged([g for inner in choice.outcomes for g in
                                           _ground_outcome(inner, bb, objects, static, fluent,
                                                           too_many, value, past)])))
    own = [_ground_outcome(o, b, objects, static, fluent, too_many, value, past)[0]
           for o in _without_choices(action)]
    if not any(off) and len(_merged(own)) * math.prod(len(d) for _, d in draws) \
            > FACTORED_ABOVE:
        parts: list[list[tuple[float, Ground]]] = [_merged(own)]
        for _, draw in draws:
            if len(draw) == 1:  # for sure: beside the action's own outcomes
                parts[0] = _times(parts[0], draw)
            else:
                parts.append(draw)
        return Factored(tuple(tuple(part) for part in parts))
    listed: list[tuple[int, float, Ground]] = []
    for k, (o, first) in enumerate(zip(outs, own, strict=True)):
        if off[k]:  # it sets nothing under b (as _ground_outcome skips its choices)
            listed.append((k, o.probability, (frozenset(), frozenset(), (), 0.0, (), False)))
            continue
        out = [first]
        for choice, draw in draws:
            out = _times(out, draw)
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
            out = _times(out, draw)
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


def _times(dist: list[tuple[float, Ground]], draw: list[tuple[float, Ground]]
           ) -> list[tuple[float, Ground]]:
    """``dist`` and the independent ``draw`` side by side: their product, equal effects
    merged (in the order ``dist``'s outcomes, then ``draw``'s, list them)."""
    return _merged([(p * q, _both(x, y)) for p, x in dist for q, y in draw])


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


def factored_kept(factored: Factored, determinisation: str, name: str
                  ) -> tuple[list[tuple[float, Ground]], tuple[int, ...], tuple[str, ...]]:
    """What a :class:`Factored` ground action lists (never its parts' product): the
    outcome of every part's most likely outcome together, first, then each outcome of one
    part with every other part at its most likely (*one part at a time*: 1 plus the sum of
    the parts' other outcomes, equal effects once, each with the probability of the
    first combination that gives it); the ones the planner's ``determinisation`` keeps
    (all-outcomes: every one that does something; most-likely: the first), and their
    planner schema names (``name``, or ``name_f<i>`` where several are kept)."""
    parts = factored.parts
    best = [max(range(len(part)), key=lambda i, part=part: (part[i][0], -i)) for part in parts]

    def join(a: tuple[float, Ground], b: tuple[float, Ground]) -> tuple[float, Ground]:
        return a[0] * b[0], _both(a[1], b[1])

    nothing: tuple[float, Ground] = (1.0, (frozenset(), frozenset(), (), 0.0, (), False))
    prefix = [nothing]
    for part, i in zip(parts, best, strict=True):
        prefix.append(join(prefix[-1], part[i]))
    suffix = [nothing] * (len(parts) + 1)
    for j in range(len(parts) - 1, -1, -1):
        suffix[j] = join(parts[j][best[j]], suffix[j + 1])
    listed: dict[Ground, float] = {prefix[-1][1]: prefix[-1][0]}
    for j, part in enumerate(parts):
        for i, outcome in enumerate(part):
            if i != best[j] and outcome[0] > 0:
                p, g = join(join(prefix[j], outcome), suffix[j + 1])
                listed.setdefault(g, p)
    outcomes = [(p, g) for g, p in listed.items()]

    def useful(i: int) -> bool:
        p, g = outcomes[i]
        return p > 0 and not g[5] and bool(g[0] or g[1] or g[2])

    if determinisation == "all-outcomes":
        known = tuple(i for i in range(len(outcomes)) if useful(i))
    else:
        known = (0,) if useful(0) else ()
    names = (name,) if len(known) == 1 else tuple(f"{name}_f{i}" for i in known)
    return outcomes, known, names
