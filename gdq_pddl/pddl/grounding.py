"""The one grounder and the ground effect: a typed PDDL or PPDDL problem grounded into
bitmask operators (states: ``int`` bitmasks over the fluent facts).

:class:`GroundOutcome` is what one outcome of a ground action does: adds, deletes,
conditional effects, the rewards and costs inside effects. :class:`GroundOp` is a ground
action: a precondition and its outcomes (a STRIPS action: one unconditional outcome of
probability 1, :meth:`GroundOp.strips`). Every consumer reads these: the true model
(:mod:`gdq_pddl.pddl.outcomes`), the enumeration and the online store
(:mod:`gdq_pddl.pddl.wordrows`, :mod:`gdq_pddl.pddl.lazy`), the planner's
determinisation (:mod:`gdq_pddl.pddl.ppddl`) and the relaxed forms
(:mod:`gdq_pddl.planning.heuristic`).

:func:`ground` is the one route from a parsed domain and problem to them: conditions
normalised once (:func:`~gdq_pddl.pddl.normalise.ground_dnf`), each schema's outcomes
expanded per binding (:func:`~gdq_pddl.pddl.ppddl_effects.ground_outcomes`); parameters
are bound by joining the static preconditions against the initial state, most
constrained first (:func:`~gdq_pddl.pddl.normalise.action_bindings`), and ground
actions unreachable with deletes ignored are dropped.
"""

from __future__ import annotations

import itertools
import math
from collections import Counter, defaultdict
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property

from gdq_pddl.errors import PDDLError
from gdq_pddl.limits import slow_progress
from gdq_pddl.pddl.factored import Factored, Ground, factored_kept
from gdq_pddl.pddl.model import Action, Atom, Domain, Junction, Problem
from gdq_pddl.pddl.normalise import (
    MAX_ATOMS,
    MAX_DISJUNCTS,
    action_bindings,
    forget,
    ground_dnf,
    index_problem,
)
from gdq_pddl.pddl.ppddl_effects import (
    DETERMINISATIONS,
    action_cost,
    ground_outcomes,
    kept_ground,
    planner_names,
    term_value,
)


@dataclass(frozen=True)
class GroundOutcome:
    """What one outcome of a ground action does: its probability, add and delete masks,
    whether it is a failed trial, its conditional effects and what it earns."""

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

    def moves(self) -> bool:
        """Whether the outcome may change a state (it adds, deletes or has a conditional
        effect)."""
        return bool(self.add or self.dele or self.conditional)

    def apply(self, state: int) -> int:
        """The state after the outcome (adds win)."""
        add, dele = self.add, self.dele
        for pos, neg, a, d in self.conditional:
            if state & pos == pos and not state & neg:
                add, dele = add | a, dele | d
        return (state & ~dele) | add


@dataclass(frozen=True)
class GroundOp:
    """A ground action: its name, precondition and outcomes. ``known``: the outcomes the
    planner's determinisation keeps (a STRIPS action: its one). The outcomes are a flat
    distribution (a ``forall`` of probabilistic effects is their product, listed), but
    for a *factored* action (:attr:`parts` not empty), whose product is too large to
    list: reality draws one outcome of each part, and :attr:`outcomes` lists only what
    the determinisation reads (each part's outcomes one at a time:
    :func:`~gdq_pddl.pddl.factored.factored_kept`), not reality's distribution."""

    name: str
    pre: int
    neg: int
    outcomes: tuple[GroundOutcome, ...]
    known: tuple[int, ...] = (0,)
    alternatives: tuple[tuple[int, int], ...] = ()
    """A disjunctive precondition: ``(must hold, must not hold)`` pairs, one of which must
    be met besides ``pre``/``neg`` (what all share); empty: ``pre``/``neg`` alone."""
    cost: float | None = field(default=None, kw_only=True)
    """What the action costs whatever happens (the costs it writes outside every
    ``when``, ``forall`` and ``probabilistic``, function terms valued: :func:`action_cost`);
    costs and rewards inside them are its outcomes' (:class:`GroundOutcome`). None: it
    states no cost anywhere (the goal scale's default applies)."""
    parts: tuple[tuple[GroundOutcome, ...], ...] = field(default=(), kw_only=True)
    """A factored action's independent parts (each a distribution summing to 1; the first:
    its own outcomes, then one per binding of a forall of probabilistic effects):
    reality's outcome is one outcome of each, drawn independently, side by side
    (:func:`~gdq_pddl.pddl.factored.combine`). Empty: :attr:`outcomes` is reality's distribution."""

    @property
    def factored(self) -> bool:
        """Whether reality's outcomes are :attr:`parts`' product, not :attr:`outcomes`."""
        return bool(self.parts)

    def product_size(self) -> int:
        """How many outcomes listing reality's distribution would take at most (the
        product of the parts' sizes; :attr:`outcomes`' for an action not factored)."""
        return math.prod(len(part) for part in self.parts) if self.parts \
            else len(self.outcomes)

    @classmethod
    def strips(cls, name: str, pre: int, neg: int, add: int, dele: int,
               cost: float | None = None) -> GroundOp:
        """The STRIPS action: one unconditional outcome, for sure."""
        return cls(name, pre, neg, (GroundOutcome(1.0, add, dele),), cost=cost)

    @cached_property
    def _single(self) -> GroundOutcome:
        if len(self.outcomes) != 1 or self.outcomes[0].conditional or self.parts:
            raise TypeError(f"{self.name} has no single unconditional effect (see its "
                            "outcomes)")
        return self.outcomes[0]

    @property
    def add(self) -> int:
        """A STRIPS action's adds (a TypeError for any other)."""
        return self._single.add

    @property
    def dele(self) -> int:
        """A STRIPS action's deletes (a TypeError for any other)."""
        return self._single.dele

    def applicable(self, state: int) -> bool:
        """Whether ``pre``/``neg`` hold in ``state`` (not the :attr:`alternatives`)."""
        return state & self.pre == self.pre and not state & self.neg

    def holds(self, state: int) -> bool:
        """Whether the precondition holds in ``state``."""
        return self.applicable(state) and (not self.alternatives or any(
            state & p == p and not state & n for p, n in self.alternatives))

    def apply(self, state: int) -> int:
        """A STRIPS action's successor of ``state`` (a TypeError for any other)."""
        return self._single.apply(state)


@dataclass(frozen=True)
class GroundTask:
    """A grounded problem. States are int bitmasks over :attr:`facts`."""

    facts: tuple[str, ...]
    ops: tuple[GroundOp, ...]
    init: int
    goal_pos: int
    goal_neg: int
    goal_possible: bool
    statics: frozenset[str]
    fact_index: dict[str, int] = field(repr=False, default_factory=dict)
    goal_alternatives: tuple[tuple[int, int], ...] = ()
    """A goal with alternatives: ``(must hold, must not hold)`` masks, one of which must
    be met besides ``goal_pos``/``goal_neg`` (the part they share). Empty: none."""
    incomplete: str = ""
    """Why some ground actions have no planner action here (a PPDDL action whose
    conditional effects need too many STRIPS variants); planners asked a query on such a
    task refuse with it. Empty: every ground action is here."""
    disjunctive: bool = False
    """Some op has a disjunctive precondition (:attr:`GroundOp.alternatives`)."""

    @cached_property
    def ops_by_fact(self) -> dict[int, tuple[GroundOp, ...]]:
        """Operators keyed by one positive precondition bit (or -1 for none)."""
        out: dict[int, list[GroundOp]] = defaultdict(list)
        counts = Counter(bit for op in self.ops for bit in set_bits(op.pre))
        for op in self.ops:
            out[min(set_bits(op.pre), key=counts.__getitem__, default=-1)].append(op)
        return {k: tuple(v) for k, v in out.items()}

    def applicable(self, state: int) -> list[GroundOp]:
        """Every operator whose precondition holds in ``state``."""
        table = self.ops_by_fact
        ops = [op for key in (-1, *set_bits(state)) for op in table.get(key, ())
               if state & op.pre == op.pre and not state & op.neg]
        return [op for op in ops if op.holds(state)] if self.disjunctive else ops

    def successors(self, state: int) -> list[tuple[GroundOp, int]]:
        """``(op, next state)`` for every operator applicable in ``state`` and outcome the
        planner knows (:attr:`GroundOp.known`), each distinct state once per op."""
        out = []
        for op in self.applicable(state):
            if len(op.known) == 1:  # most: one outcome known (every STRIPS action)
                o = op.outcomes[op.known[0]]
                out.append((op, o.apply(state) if o.conditional
                            else (state & ~o.dele) | o.add))
            else:
                out += [(op, t) for t in dict.fromkeys(op.outcomes[k].apply(state)
                                                       for k in op.known)]
        return out

    def outcome_states(self, state: int) -> list[int]:
        """Every state reality may reach from ``state`` (failed trials aside); a
        TypeError where a factored action applies (its outcomes are never listed)."""
        ops = self.applicable(state)
        factored = next((op.name for op in ops if op.factored), None)
        if factored is not None:
            raise TypeError(f"{factored} is factored: its outcomes are drawn, never listed")
        return [o.apply(state) for op in ops
                for o in op.outcomes if o.probability > 0 and not o.stuck]

    @cached_property
    def factored(self) -> tuple[str, ...]:
        """The names of the factored ground actions (:attr:`GroundOp.parts`)."""
        return tuple(op.name for op in self.ops if op.factored)

    def is_goal(self, state: int, goal: tuple[int, int] | None = None) -> bool:
        """Whether ``goal`` (default: the problem's) holds in ``state``; never, for a
        problem goal that can never hold (:attr:`goal_possible`)."""
        if goal is not None:
            return state & goal[0] == goal[0] and not state & goal[1]
        return self.goal_possible and state & self.goal_pos == self.goal_pos \
            and not state & self.goal_neg and (not self.goal_alternatives or any(
                state & p == p and not state & n for p, n in self.goal_alternatives))

    def atoms(self, state: int) -> frozenset[str]:
        """The fluent atoms true in ``state``."""
        return frozenset(self.facts[b] for b in set_bits(state))

    def mask(self, atoms: frozenset[str] | set[str]) -> int:
        """Bitmask of fluent atoms; raises KeyError naming an unknown atom."""
        return sum(1 << self.fact_index[a] for a in set(atoms))


def set_bits(mask: int):
    """The indices of the bits set in ``mask``, lowest first."""
    while mask:
        low = mask & -mask
        yield low.bit_length() - 1
        mask ^= low


def ground(domain: Domain, problem: Problem,
           determinisation: str = DETERMINISATIONS[0]) -> GroundTask:
    """Ground ``problem``: every ground action with all its outcomes, ``known`` the
    outcomes ``determinisation`` keeps (:func:`ground_kept`; the module docstring)."""
    return ground_kept(domain, problem, determinisation)[0]


def ground_kept(domain: Domain, problem: Problem, determinisation: str = DETERMINISATIONS[0]
                ) -> tuple[GroundTask, list[tuple[str, ...]]]:
    """The one grounder: the task of every ground action of ``problem`` (all its outcomes;
    ``known``: those the planner's ``determinisation`` keeps), and for each ground action
    the planner schema names of its kept outcomes
    (:func:`~gdq_pddl.pddl.ppddl_effects.kept_ground`).

    Ground actions come in the order their bindings are found, but for a domain without
    quantified or disjunctive conditions, conditional effects or rewards inside effects
    (a *plain* one: every STRIPS domain), whose come in the order relaxed reachability
    finds them, outcome by outcome (:func:`relaxed_reachability`): the order, and so the
    action numbers, each has always had."""
    names = planner_names(domain, determinisation)
    fluent, static_tuples, by_type, typed = index_problem(domain, problem)
    statics = frozenset(str(a) for a in problem.init if a.predicate not in fluent)

    def objects(t: str) -> list[str]:
        return by_type.get(t, [])

    def static(atom: Atom) -> bool | None:
        return None if atom.predicate in fluent else str(atom) in statics

    plain = not any(a.condition is not None or any(o.conditional or o.rewards or o.choices
                                                   for o in a.outcomes)
                    for a in domain.actions)
    raw = []
    factored: dict[int, Factored] = {}  # by index in raw
    with slow_progress("grounding", " actions") as bar:
        for action in domain.actions:
            def too_many(action: Action = action) -> PDDLError:
                return PDDLError(domain.source, action.line or None, f"action {action.name}: a "
                                 f"condition or forall effect grows past {MAX_DISJUNCTS} "
                                 f"alternatives or {MAX_ATOMS} atoms once grounded over the "
                                 "problem's objects")

            def value(term, binding, action: Action = action) -> float:
                return term_value(term, binding, domain, problem, action,
                                  f"a reward of {action.name}")

            whole = Junction("and", action.precondition + ((action.condition,)
                                                           if action.condition else ()))
            for b in action_bindings(action, static_tuples, by_type, typed, fluent):
                bar.update()
                # a plain domain's precondition is its fluent literals as written (one that
                # contradicts itself stays, a ground action that never applies, as always)
                pre = [_literals(action.precondition, b, fluent)] if plain else \
                    ground_dnf(whole, b, objects, static, too_many)
                if pre:
                    args = tuple(b[p] for p, _ in action.parameters)
                    outs = ground_outcomes(action, args, b, objects, static, fluent,
                                           too_many, value, domain.source)
                    if isinstance(outs, Factored):  # relaxed: every part's outcomes
                        factored[len(raw)] = outs
                        outs = [(0, p, g) for part in outs.parts for p, g in part]
                    raw.append((action, args, pre, outs))
    forget()
    init = {str(a) for a in problem.init if a.predicate in fluent}
    reached, found = relaxed_reachability(raw, init, plain)
    facts = tuple(sorted(reached))
    index = {f: i for i, f in enumerate(facts)}

    masks: dict[frozenset[str], int] = {}  # the same sets recur in many outcomes

    def m(atoms: frozenset[str]) -> int:
        mask = masks.get(atoms)
        if mask is None:
            mask = masks[atoms] = sum(1 << index[a] for a in atoms if a in index)
        return mask

    seen: dict[tuple, tuple | None] = {}  # a conditional effect's or reward's masks, once

    def when(c: tuple) -> tuple | None:  # (must hold, must not, add, delete)
        if c not in seen:
            seen[c] = (m(c[0]), m(c[1]), m(c[2]), m(c[3])) if c[0] <= reached else None
        return seen[c]

    def earns(r: tuple) -> tuple | None:  # (alternatives, amount)
        if r not in seen:
            alts = tuple((m(cp), m(cn)) for cp, cn in r[0] if cp <= reached)
            seen[r] = (alts, r[1]) if alts else None
        return seen[r]

    ops, kept = [], []
    with slow_progress("grounding", " actions", len(found), found) as bar:
        for i in bar:
            action, args, pre, outs = raw[i]
            alts = [(m(p), m(n)) for p, n in pre if p <= reached]
            common_pos = common_neg = -1
            for p, n in alts:
                common_pos, common_neg = common_pos & p, common_neg & n
            def outcome(p: float, g: Ground) -> GroundOutcome:
                add, dele, conds, reward, rewards, stuck = g
                return GroundOutcome(
                    p, m(add), m(dele - add), stuck,
                    tuple(w for w in map(when, conds) if w is not None),
                    reward, tuple(r for r in map(earns, rewards) if r is not None))

            name = str(Atom(action.name, args))
            parts: tuple[tuple[GroundOutcome, ...], ...] = ()
            if i in factored:
                listed, known, kept_names = factored_kept(factored[i], determinisation,
                                                          action.name)
                outcomes = tuple(outcome(p, g) for p, g in listed)
                parts = tuple(tuple(outcome(p, g) for p, g in part)
                              for part in factored[i].parts)
            else:
                outcomes = tuple(outcome(p, g) for _, p, g in outs)
                known, kept_names = kept_ground(action, outs, outcomes, determinisation,
                                                names)
            ops.append(GroundOp(name, common_pos, common_neg, outcomes,
                                known, tuple(alts) if len(alts) > 1 else (),
                                cost=action_cost(action, args, domain, problem), parts=parts))
            kept.append(kept_names)
    task = GroundTask(facts, tuple(ops), m(frozenset(init)), statics=statics, fact_index=index,
                      disjunctive=any(op.alternatives for op in ops),
                      **goal_masks(problem, fluent, statics, index))
    return task, kept


def _literals(literals, b: Mapping[str, str], fluent: frozenset[str]
              ) -> tuple[frozenset[str], frozenset[str]]:
    """The fluent atoms of ``literals`` under ``b`` that must hold, and must not."""
    def part(positive: bool) -> frozenset[str]:
        return frozenset(str(Atom(lit.atom.predicate, tuple(b.get(x, x) for x in lit.atom.args)))
                         for lit in literals
                         if lit.positive == positive and lit.atom.predicate in fluent)
    return part(True), part(False)


def relaxed_reachability(raw: list, init: set[str], by_outcome: bool
                         ) -> tuple[set[str], list[int]]:
    """Relaxed reachability (deletes ignored) from ``init`` over the ground actions ``raw``
    (``(action, args, precondition alternatives, ground outcomes)``, in binding order):
    the facts some sequence of them may make true, and those that may ever apply (a bar
    counts them past 2 s), in binding order; ``by_outcome`` (a plain domain: one
    alternative, no conditional effect): in the order found when the outcomes are tried
    schema by schema, outcome by outcome, binding by binding."""
    reached = set(init)
    with slow_progress("relaxed reachability", " actions", len(raw)) as bar:
        if by_outcome:
            items = []
            for _, block in itertools.groupby(range(len(raw)), key=lambda i: id(raw[i][0])):
                block = list(block)
                for k in range(len(raw[block[0]][3])):
                    items += [(i, raw[i][2][0][0], raw[i][3][k][2][0]) for i in block]
            found: dict[int, None] = {}
            changed = True
            while changed:
                changed, rest = False, []
                for item in items:
                    if item[1] <= reached:
                        if item[0] not in found:
                            found[item[0]] = None
                            bar.update()
                        reached |= item[2]
                        changed = True
                    else:
                        rest.append(item)
                items = rest
            return reached, list(found)
        live = [False] * len(raw)
        changed = True
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
    return reached, [i for i, ok in enumerate(live) if ok]


def goal_masks(problem: Problem, fluent, statics, index: dict[str, int]) -> dict:
    """The goal fields of a :class:`GroundTask`, equalities and static atoms (``statics``)
    decided; alternatives that can never hold are dropped."""
    def masks(lits) -> tuple[int, int, bool]:
        pos = neg = 0
        possible = True
        for lit in lits:
            s = str(lit.atom)
            if lit.atom.predicate == "=":
                possible &= (lit.atom.args[0] == lit.atom.args[1]) == lit.positive
            elif lit.atom.predicate not in fluent:
                possible &= (s in statics) == lit.positive
            elif s not in index:
                possible &= not lit.positive
            elif lit.positive:
                pos |= 1 << index[s]
            else:
                neg |= 1 << index[s]
        return pos, neg, possible

    pos, neg, possible = masks(problem.goal)
    alternatives = [m[:2] for m in map(masks, problem.goal_alternatives) if m[2]]
    return {"goal_pos": pos, "goal_neg": neg, "goal_alternatives": tuple(alternatives),
            "goal_possible": possible and (bool(alternatives)
                                           or not problem.goal_alternatives)}
