"""The ground effects of a PPDDL action, before a problem's facts are indexed: each
outcome of a schema under one binding of its parameters as fact sets (:data:`Ground`),
its choices drawn side by side and equal effects merged (:func:`ground_outcomes`); the
relaxed reachability over ground actions with such outcomes
(:func:`relaxed_reachability`); and a ground outcome as bitmasks over the facts
(:class:`GroundOutcome`), as reality's ops in :mod:`gdq_pddl.pddl.ppddl` carry it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

from gdq_pddl.errors import PDDLError
from gdq_pddl.limits import slow_progress
from gdq_pddl.pddl.model import Action, Atom, Choice, Junction, Literal, Outcome
from gdq_pddl.pddl.normalise import MAX_ATOMS, TRUE, extend, ground_dnf
from gdq_pddl.pddl.parser import MAX_OUTCOMES


@dataclass(frozen=True)
class GroundOutcome:
    """One outcome of a ground action: probability, add and delete masks, failed trial."""

    probability: float
    add: int
    dele: int
    stuck: bool = False
    conditional: tuple[tuple[int, int, int, int], ...] = ()
    """Conditional effects ``(must hold, must not hold, add, delete)`` (adds win)."""
    reward: float = 0.0
    """The reward the outcome always earns besides the action's cost."""
    rewards: tuple[tuple[tuple[tuple[int, int], ...], float], ...] = ()
    """``(alternatives (must hold, must not hold), amount)``: earned where one holds."""

    def gain(self, state: int) -> float:
        """The outcome's reward when the action is taken in ``state``."""
        return self.reward + sum(amount for alts, amount in self.rewards
                                 if any(state & p == p and not state & n for p, n in alts))

    def largest_gain(self) -> float:
        """The most :meth:`gain` can be in size in any state: every reward counted."""
        return abs(self.reward) + sum(abs(amount) for _, amount in self.rewards)

    def apply(self, state: int) -> int:
        add, dele = self.add, self.dele
        for pos, neg, a, d in self.conditional:
            if state & pos == pos and not state & neg:
                add, dele = add | a, dele | d
        return (state & ~dele) | add



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


def relaxed_reachability(raw: list, init: set[str]) -> tuple[set[str], list[bool]]:
    """Relaxed reachability (deletes ignored) from ``init``: the facts some sequence of
    ground actions may make true, and which ground actions may ever apply (a bar counts
    those past 2 s)."""
    reached, live = set(init), [False] * len(raw)
    changed = True
    with slow_progress("relaxed reachability", " actions", len(raw)) as bar:
        while changed:
            changed = False
            for i, (_, _, pre, outs) in enumerate(raw):
                if not live[i]:
                    if not any(p <= reached for p, _ in pre):
                        continue
                    live[i] = changed = True
                    bar.update()
                for _, _, (add, _, conds, *_) in outs:
                    new = add.union(*(a for cp, _, a, _ in conds if cp <= reached)) - reached
                    if new:
                        reached |= new
                        changed = True
    return reached, live
