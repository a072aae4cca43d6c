"""The domain reader for the PPDDL of the IPPC probabilistic tracks (``docs/domains.md``,
"PPDDL"; why not unified-planning's: ``docs/decisions.md``) into the frozen types of
:mod:`gdq_pddl.pddl.model`: types, predicates and functions declared, actions with their
preconditions and effects, probabilistic effects flattened into outcomes, conditions in
negation normal form. Every error is a :class:`~gdq_pddl.errors.PDDLError` naming the
file, the line and what was expected.

The s-expressions are read by :mod:`gdq_pddl.pddl.sexpr`, what a domain and a problem both
write by :mod:`gdq_pddl.pddl.formulas`, problems by :mod:`gdq_pddl.pddl.problem_reader`;
the problem reader's public functions and :class:`~gdq_pddl.errors.PDDLError` can be
imported from here too."""

from __future__ import annotations

import math
from fractions import Fraction
from functools import partial
from pathlib import Path

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl.formulas import (
    COST_FLUENTS,
    bare_atom,
    bare_term,
    read_atom,
    read_condition,
    read_number,
    read_requirements,
    read_term,
)
from gdq_pddl.pddl.model import (
    STUCK,
    Action,
    Atom,
    Choice,
    CondEffect,
    Condition,
    CostTerm,
    Domain,
    Junction,
    Literal,
    Outcome,
    Quantified,
    Reward,
)
from gdq_pddl.pddl.normalise import conjunction, nnf
from gdq_pddl.pddl.problem_reader import parse_problem, problem_file, read_problem
from gdq_pddl.pddl.sexpr import Node, Reader, read_pddl_text

__all__ = ["MAX_OUTCOMES", "PDDLError", "parse_domain", "parse_problem", "problem_file",
           "read_domain", "read_problem"]

MAX_OUTCOMES = 4096
"""Most outcomes one action's effect may flatten into."""
SUM_TOLERANCE = 1e-12
"""How far past 1 the probabilities of one ``(probabilistic ...)`` may sum (they are summed
exactly, as written), as a dynamics file's ``success + stuck``: probabilities printed
from floats (``0.1 0.2 0.7000000000000001``) miss 1 by some 1e-16 each. Such a sum is
taken as 1: the likeliest outcome gives up the excess."""
_DOMAIN_SECTIONS = (":requirements", ":types", ":constants", ":predicates", ":functions",
                    ":action")
_CONNECTIVES = ("or", "imply", "forall", "exists", "when", "oneof", "probabilistic",
                "increase", "decrease", "and", "not", "=")
_RESERVED = frozenset(_CONNECTIVES) - {"="} | {"either", "assign"}
"""Words a formula reads as connectives: no predicate may be named so."""


def parse_domain(text: str, source: str = "<domain>") -> Domain:
    """Parse a domain; raise :class:`PDDLError` with file and line on any problem."""
    r = Reader(text, source)
    _, name, body = r.pick("domain")
    sec, action_nodes = r.sections(body, _DOMAIN_SECTIONS, "domain")
    reqs = read_requirements(r, sec.get(":requirements"))
    if ":types" in sec:
        r.types = _types(r, sec[":types"])
    constants = {c: t for c, t, _ in r.typed_list(sec[":constants"].items[1:], False,
                                                   "constant")} if ":constants" in sec else {}
    r.predicates = _declarations(r, sec.get(":predicates"), "predicate")
    r.functions = _declarations(r, sec.get(":functions"), "function")
    actions: list[Action] = []
    rewards = False
    for node in action_nodes:
        action, uses_reward = _action(r, node, constants)
        rewards |= uses_reward
        twin = next((a for a in actions if a.name == action.name), None)
        if twin is not None:
            raise r.fail(node.line, f"action {action.name} is declared twice (first at line "
                         f"{twin.line})")
        actions.append(action)
    return Domain(name, frozenset(reqs), r.types, constants, r.predicates, tuple(actions),
                  source, r.functions, rewards)


def _types(r: Reader, node: Node) -> dict[str, str | None]:
    """``(:types a b - c)`` -> ``{object: None, a: c, b: c, c: object}``; a type declared
    twice, an undeclared parent and a cycle of parents are refused."""
    types: dict[str, str | None] = {"object": None}
    lines: dict[str, int] = {}
    for t, parent, line in r.typed_list(node.items[1:], False, "type", check=False):
        if t == "object":
            if parent != "object":
                raise r.fail(line, f"object is the root type: it cannot be a {parent}")
            continue
        types[t], lines[t] = parent, line
    for t in lines:
        chain = [t]
        while (parent := types[chain[-1]]) is not None:
            if parent not in types:
                raise r.fail(lines[chain[-1]], f"type {chain[-1]} has unknown parent type "
                             f"{parent}")
            if parent in chain:
                cycle = " - ".join(chain[chain.index(parent):] + [parent])
                raise r.fail(lines[t], f"the types form a cycle ({cycle}): every type must "
                             "lead up to object")
            chain.append(parent)
    return types


def _declarations(r: Reader, node: Node | None, what: str) -> dict[str, tuple[str, ...]]:
    """``(:predicates (p ?x - t) ...)`` or ``(:functions (f ?x - t) - number ...)`` ->
    ``{p: (t,), ...}`` (``what``: ``"predicate"`` or ``"function"``)."""
    out: dict[str, tuple[str, ...]] = {}
    first: dict[str, int] = {}
    items = node.items[1:] if node is not None else ()  # type: ignore[index]
    i = 0
    while i < len(items):
        item = items[i]
        if what == "function" and not item.is_list:
            if item.symbol != "-" or i + 1 >= len(items) or items[i + 1].symbol != "number":
                raise r.fail(item.line, "expected a function (name ?x - type ...) or "
                             f"'- number' after one, found {item.text()}")
            i += 2
            continue
        sig = r.lst(item, f"a {what} (name ?x - type ...)")
        if not sig:
            raise r.fail(item.line, f"expected a {what} name")
        name = r.name(sig[0], f"a {what} name")
        params = r.typed_list(sig[1:], True, f"{what} {name}: parameter")
        if name in first:
            raise r.fail(item.line, f"{what} {name} is declared twice (first at line "
                         f"{first[name]})")
        if what == "predicate" and name in _RESERVED:
            raise r.fail(item.line, f"a predicate cannot be named {name}: formulas read it "
                         "as a connective")
        first[name] = item.line
        out[name] = tuple(t for _, t, _ in params)
        i += 1
    return out


def _action(r: Reader, node: Node, constants: dict[str, str]) -> tuple[Action, bool]:
    """An action, and whether an effect of it changes ``(reward)``."""
    items = r.lst(node, "an action")
    if len(items) < 2:
        raise r.fail(node.line, "expected (:action NAME :parameters (...) ...)")
    name = r.name(items[1], "an action name")
    fields: dict[str, Node] = {}
    rest = items[2:]
    if len(rest) % 2:
        raise r.fail(node.line, f"action {name}: expected pairs of :keyword value")
    for key, value in zip(rest[::2], rest[1::2], strict=True):
        k = r.symbol(key, ":parameters, :precondition or :effect")
        if k not in (":parameters", ":precondition", ":effect"):
            raise r.fail(key.line, f"action {name}: unexpected {k} (expected :parameters, "
                         ":precondition or :effect)")
        if k in fields:
            raise r.fail(key.line, f"action {name}: {k} is given twice (first at line "
                         f"{fields[k].line})")
        fields[k] = value
    typed = r.typed_list(r.lst(fields[":parameters"], "a parameter list"), True,
                         f"action {name}: parameter") if ":parameters" in fields else []
    params = [(p, t) for p, t, _ in typed]
    scope = dict(params) | constants
    ctx = f"action {name}"
    pre, rest = _precondition(r, fields.get(":precondition"), scope, ctx)
    reader = _Effects(r, scope, ctx)
    branches = reader.effect(fields.get(":effect"), inside=False)
    if not reader.probabilistic and not reader.conditional and rest is None:
        return Action(name, tuple(params), pre, branches[0][1], node.line,  # type: ignore
                      cost=tuple(reader.costs)), reader.reward_effects
    return Action(name, tuple(params), pre, (), node.line,
                  _outcomes(branches, r.stuck_domain, r, node.line, ctx),
                  tuple(reader.costs), rest), reader.reward_effects


def _precondition(r: Reader, node: Node | None, scope: dict[str, str],
                  ctx: str) -> tuple[tuple[Literal, ...], Condition | None]:
    """A precondition as its literals (in order) and the rest, in negation normal form,
    that only grounding can decide (quantifiers, disjunctions; None: there is none)."""
    if node is None:
        return (), None
    cond = nnf(read_condition(r, node, scope, ctx))
    lits = conjunction(cond)
    if lits is not None:
        return lits, None
    assert isinstance(cond, (Junction, Quantified))
    parts = cond.parts if isinstance(cond, Junction) and cond.kind == "and" else (cond,)
    literals = tuple(p for p in parts if isinstance(p, Literal))
    others = tuple(p for p in parts if not isinstance(p, Literal))
    return literals, (others[0] if len(others) == 1 else Junction("and", others))


Branches = list[tuple[Fraction, tuple[Literal | CondEffect | Reward | Choice, ...]]]
"""An effect as a distribution: ``(probability, effects)`` pairs summing to 1."""


class _Effects:
    """Reads one action's effect into :data:`Branches`, and its cost terms."""

    def __init__(self, r: Reader, scope: dict[str, str], ctx: str) -> None:
        self.r, self.scope, self.ctx = r, scope, ctx
        self.costs: list[CostTerm] = []
        self.probabilistic = self.conditional = self.reward_effects = False
        self.variables: tuple[tuple[str, str], ...] = ()  # of the forall effects around
        self.when: Condition | None = None  # the when effects' conditions around, joined

    def effect(self, node: Node | None, inside: bool) -> Branches:
        """The distribution of ``node``'s outcomes; ``inside`` a probabilistic effect."""
        r, ctx = self.r, self.ctx
        node = bare_atom(r, node) if node is not None else None
        items = r.lst(node, "an effect") if node is not None else ()
        if not items:
            return [(Fraction(1), ())]
        head = items[0].symbol
        if head in ("when", "forall"):
            return self.scoped(node, items, inside)
        if head == "and":
            out: Branches = [(Fraction(1), ())]
            for sub in items[1:]:  # independent effects: every pair of their outcomes
                more = self.effect(sub, inside)
                out = [(p * q, la + lb) for p, la in out for q, lb in more]
                if len(out) > MAX_OUTCOMES:
                    raise r.fail(node.line, f"{ctx}: the effect has more than {MAX_OUTCOMES} "
                                 "outcomes (independent probabilistic effects multiply)")
            return out
        if head == "probabilistic":
            return self.probabilistic_effect(node, items)
        if head in ("increase", "decrease"):
            term, sign = self.cost(node, items)
            if not inside and self.when is None and not self.variables and sign < 0:
                self.costs.append(term)  # the action's cost, whatever happens
                return [(Fraction(1), ())]
            self.conditional = True  # a reward of the outcome or the state
            return [(Fraction(1), (Reward(term, sign, self.variables, self.when),))]
        if head == "not":
            items = (items[0], *map(partial(bare_atom, r), items[1:]))
            if len(items) != 2 or not items[1].is_list or not items[1].items or \
                    items[1].items[0].symbol in _CONNECTIVES:
                raise r.fail(node.line, f"{ctx}: (not ...) must wrap a single atom")
        elif head == "=":
            raise r.fail(node.line, f"{ctx}: equality cannot be an effect")
        elif head in _CONNECTIVES:
            hint = " (FOND); give probabilities with (probabilistic ...)" \
                if head == "oneof" else ""
            raise r.fail(node.line, f"{ctx}: ({head} ...) cannot be an effect{hint} (an "
                         "effect is made of literals, and, when, forall, probabilistic and "
                         "costs)")
        positive = head != "not"
        atom = read_atom(r, node if positive else items[1], self.scope, ctx, effect=True)
        if not positive and atom.predicate == STUCK and r.stuck_domain:
            raise r.fail(node.line, f"{ctx}: (not (stuck)) is not an effect: (stuck) marks "
                         "a failed trial, which ends the episode")
        if self.when is None and not self.variables:
            return [(Fraction(1), (Literal(atom, positive),))]
        if atom.predicate == STUCK and r.stuck_domain:
            raise r.fail(node.line, f"{ctx}: (stuck) inside (when ...) or (forall ...) is not "
                         "supported: a failed trial is an outcome of its own; write it in "
                         "(probabilistic ...)")
        self.conditional = True  # the literal of the when/forall effects around it
        return [(Fraction(1), (CondEffect(self.variables, self.when, Literal(atom, positive)),))]

    def scoped(self, node: Node, items: tuple[Node, ...], inside: bool) -> Branches:
        """``(when CONDITION EFFECT)`` or ``(forall (?x - t ...) EFFECT)``: the effect's
        literals hold under the condition, for every binding of the variables. A forall
        of a probabilistic effect is a :class:`Choice` (:meth:`choice`)."""
        r, ctx, head = self.r, self.ctx, items[0].symbol
        if len(items) != 3:
            raise r.fail(node.line, f"{ctx}: expected ({head} "
                         f"{'CONDITION' if head == 'when' else '(?x - TYPE ...)'} EFFECT)")
        if head == "forall" and _mentions(items[2], "probabilistic"):
            return self.choice(node, items)
        saved = self.scope, self.variables, self.when  # an error ends the reading
        if head == "when":
            cond = nnf(read_condition(r, items[1], self.scope, ctx))
            self.when = cond if self.when is None else Junction("and", (self.when, cond))
        else:
            variables = r.variables(items[1], ctx)
            self.variables += variables
            self.scope = {**self.scope, **dict(variables)}
        branches = self.effect(items[2], inside)
        self.scope, self.variables, self.when = saved
        return branches

    def choice(self, node: Node, items: tuple[Node, ...]) -> Branches:
        """``(forall (?x - t ...) EFFECT)`` with a probabilistic ``EFFECT``: one draw of
        ``EFFECT``'s outcomes per binding, expanded when the action is grounded (the
        objects are not known yet; ``docs/decisions.md``, "Flattening"). Every forall
        around it is such a choice too, so its variables are bound by then; the ``when``
        conditions around it stay on its literals."""
        variables = self.r.variables(items[1], self.ctx)
        saved = self.scope
        self.scope = {**self.scope, **dict(variables)}
        branches = self.effect(items[2], inside=True)  # a cost in it is paid per binding
        self.scope = saved
        self.conditional = True
        outcomes = _outcomes(branches, self.r.stuck_domain, self.r, node.line, self.ctx)
        return [(Fraction(1), (Choice(variables, outcomes, node.line),))]

    def probabilistic_effect(self, node: Node, items: tuple[Node, ...]) -> Branches:
        """``(probabilistic p1 e1 ...)``: each ``e_i`` with ``p_i``; the rest, no effect."""
        r, ctx = self.r, self.ctx
        self.probabilistic = True
        pairs = items[1:]
        if not pairs or len(pairs) % 2:
            raise r.fail(node.line, f"{ctx}: expected (probabilistic p1 e1 p2 e2 ...): pairs "
                         "of a probability and an effect")
        probs = [_probability(r, p_node, ctx) for p_node in pairs[::2]]
        total = sum(probs, Fraction(0))
        if total > 1 + Fraction(SUM_TOLERANCE):
            raise r.fail(node.line, f"{ctx}: the probabilities of (probabilistic ...) sum to "
                         f"{float(total)!r}, {float(total - 1):.3g} more than 1; they must sum "
                         f"to at most 1 (within {SUM_TOLERANCE:g}; the rest means no effect)")
        if total > 1:  # past 1 by what printing floats leaves: off the likeliest, the sum 1
            big = max(range(len(probs)), key=lambda i: (probs[i], -i))
            probs[big] -= total - 1
        out: Branches = []
        for p, e_node in zip(probs, pairs[1::2], strict=True):
            out += [(p * q, lits) for q, lits in self.effect(e_node, inside=True)]
        if total < 1:
            out.append((1 - total, ()))
        return out

    def cost(self, node: Node, items: tuple[Node, ...]) -> tuple[CostTerm, float]:
        """The term of ``(increase (reward) X)`` (sign +1), ``(decrease (reward) X)`` or
        ``(increase (total-cost) X)`` (sign -1)."""
        r, ctx = self.r, self.ctx
        head = items[0].symbol
        target = bare_term(items[1]) if len(items) == 3 else None
        fluent = target.items[0].symbol if target is not None and target.is_list and \
            len(target.items) == 1 else None
        if fluent not in COST_FLUENTS:
            raise r.fail(node.line, f"{ctx}: expected ({head} (total-cost) X) or ({head} "
                         f"(reward) X); other numeric fluents are not supported, found "
                         f"{node.text()}")
        if (head, fluent) == ("decrease", "total-cost"):
            raise r.fail(node.line, f"{ctx}: (decrease (total-cost) ...): a cost must be >= 0")
        self.reward_effects |= fluent == "reward"
        sign = 1.0 if (head, fluent) == ("increase", "reward") else -1.0
        value = items[2]
        if not value.is_list and r.functions.get(value.symbol) == ():
            value = bare_term(value)
        if not value.is_list:
            number = read_number(r, value, ctx)
            if number is None or number < 0:
                raise r.fail(value.line, f"{ctx}: expected an amount >= 0 (a number or a "
                             f"function term), found {value.symbol!r}")
            return float(number), sign
        fname = value.items[0].symbol if value.items and not value.items[0].is_list else ""
        if fname not in r.functions or fname in COST_FLUENTS:
            raise r.fail(value.line, f"{ctx}: expected a cost (a number, or a function "
                         f"declared in :functions), found {value.text()}")
        return read_term(r, value, fname, r.functions[fname], self.scope, ctx), sign


def _outcomes(branches: Branches, stuck_domain: bool, r: Reader | None = None,
              line: int = 0, ctx: str = "") -> tuple[Outcome, ...]:
    """Flattened branches as outcomes: equal effects merged (first appearance first), those
    of probability 0 dropped, every outcome that makes (stuck) true one stuck outcome; an
    outcome whose probability (a product of nested ones) underflows a float is refused
    at ``line`` (with ``r``)."""
    stuck = Literal(Atom(STUCK, ()), True)
    merged: dict[tuple, Fraction] = {}
    for p, effects in branches:
        if p == 0:
            continue
        if not float(p) and r is not None:
            size = math.log10(p.numerator) - math.log10(p.denominator)
            raise r.fail(line, f"{ctx}: an outcome's probability, the product of nested "
                         f"(probabilistic ...) ones, is about 1e{size:.0f}: below the smallest "
                         "positive float (about 5e-324), it would underflow to 0")
        lits = tuple(dict.fromkeys(e for e in effects if isinstance(e, Literal)))
        conds = tuple(dict.fromkeys(e for e in effects if isinstance(e, CondEffect)))
        rewards = tuple(e for e in effects if isinstance(e, Reward))  # two add up: no merge
        choices = tuple(e for e in effects if isinstance(e, Choice))  # two draw twice
        key = ((), True, (), rewards, ()) if stuck_domain and stuck in lits else \
            (lits, False, conds, rewards, choices)  # Outcome's fields after its probability
        merged[key] = merged.get(key, Fraction(0)) + p
    return tuple(Outcome(float(p), *key) for key, p in merged.items())


def _mentions(node: Node, head: str) -> bool:
    """Whether ``(head ...)`` is written anywhere in ``node``."""
    return node.is_list and any(i == 0 and n.symbol == head or _mentions(n, head)
                                for i, n in enumerate(node.items))  # type: ignore[arg-type]


def _probability(r: Reader, node: Node, ctx: str) -> Fraction:
    value = read_number(r, node, ctx)
    if value is None:
        raise r.fail(node.line, f"{ctx}: expected a probability (a number such as 0.25 or "
                     f"1/4), found {node.text()}")
    if not 0 <= value <= 1:
        raise r.fail(node.line, f"{ctx}: a probability must be in [0, 1], got {node.symbol}")
    if value and not float(value):
        raise r.fail(node.line, f"{ctx}: the probability {node.symbol} is below the smallest "
                     "positive float (about 5e-324): it would underflow to 0; write 0 for an "
                     "outcome that never happens")
    return value


def read_domain(path: str | Path) -> Domain:
    """Read and parse a domain file."""
    return parse_domain(read_pddl_text(path), str(path))
