"""What a domain and a problem both write, read with file:line errors: conditions (a
precondition, a goal, a ``when``) as written, atoms and terms checked against the
declarations, numbers as exact fractions, and the keys of ``(:requirements ...)``."""

from __future__ import annotations

import re
from fractions import Fraction

from gdq_pddl.limits import MAX_NUMBER
from gdq_pddl.pddl.model import STUCK, Atom, Condition, Junction, Literal, Quantified
from gdq_pddl.pddl.sexpr import Node, Reader

COST_FLUENTS = ("total-cost", "reward")
"""The numeric fluents an effect may change: the action's cost, in either convention."""
MAX_LITERAL = 100
"""Most characters a number may be written in."""
MAX_EXPONENT = 400
"""The largest exponent, in size, of a number like ``2.5e-3``: past what a float holds,
and small enough that its exact fraction is built at once."""
_NUMERIC = re.compile(r"[+-]?[\d._/]+(?:e([+-]?[\d_]+))?")
"""What may be a number (:class:`~fractions.Fraction` decides); linear in its length."""
KNOWN_REQUIREMENTS = frozenset({
    ":strips", ":typing", ":negative-preconditions", ":disjunctive-preconditions",
    ":equality", ":existential-preconditions", ":universal-preconditions",
    ":quantified-preconditions", ":conditional-effects", ":fluents", ":numeric-fluents",
    ":object-fluents", ":adl", ":durative-actions", ":duration-inequalities",
    ":continuous-effects", ":derived-predicates", ":timed-initial-literals",
    ":preferences", ":constraints", ":action-costs", ":probabilistic-effects",
    ":rewards", ":mdp", ":non-deterministic"})
"""Every requirement key of PDDL 3.1 and PPDDL: one outside it is a typo, refused."""


def read_requirements(r: Reader, node: Node | None) -> set[str]:
    """The keys of ``(:requirements ...)``; one that is not a requirement of PDDL or PPDDL
    (a typo) is refused. They never decide what is read."""
    out = set()
    for n in node.items[1:] if node is not None else ():  # type: ignore[index]
        req = r.symbol(n, "a requirement")
        if req not in KNOWN_REQUIREMENTS:
            raise r.fail(n.line, f"unknown requirement {req} (the requirements of PDDL and "
                         "PPDDL are :strips, :typing, :adl, :probabilistic-effects, ...)")
        out.add(req)
    return out


def read_number(r: Reader, node: Node, ctx: str) -> Fraction | None:
    """``0.25``, ``.5``, ``1/4``, ``3`` or ``2.5e-3`` as an exact fraction (None: not a
    number); refused past :data:`~gdq_pddl.limits.MAX_NUMBER`, :data:`MAX_LITERAL`
    characters or an exponent of :data:`MAX_EXPONENT`."""
    text = node.symbol
    match = None if node.is_list else _NUMERIC.fullmatch(text)
    if match is None or not any(ch.isdigit() for ch in text):
        return None
    if len(text) > MAX_LITERAL:
        raise r.fail(node.line, f"{ctx}: the number {text[:24]}... is {len(text)} characters "
                     f"long; a number is read in at most {MAX_LITERAL}")
    if match.group(1) is not None and abs(int(match.group(1))) > MAX_EXPONENT:
        raise r.fail(node.line, f"{ctx}: {text}: an exponent past {MAX_EXPONENT} in size is "
                     f"not read (no float holds such a number; a number is at most "
                     f"{MAX_NUMBER:g} in size)")
    try:
        value = Fraction(text)
    except (ValueError, ZeroDivisionError):
        return None
    if abs(value) > MAX_NUMBER:
        shown = f"{float(value):g}" if abs(value) < 10**308 else text  # a float holds it
        raise r.fail(node.line, f"{ctx}: expected a number of at most {MAX_NUMBER:g} in size, "
                     f"found {text}" + (f" (= {shown})" if shown != text else ""))
    return value


def read_condition(r: Reader, node: Node, scope: dict[str, str], ctx: str) -> Condition:
    """A precondition, goal or ``when`` condition as written (``not`` and ``imply`` as
    :class:`Junction` kinds, for :func:`~gdq_pddl.pddl.normalise.nnf`)."""
    node = bare_atom(r, node)
    items = r.lst(node, "a formula")
    if not items:
        return Junction("and", ())
    head = items[0].symbol

    def sub(n: Node, extra: dict[str, str] | None = None) -> Condition:
        return read_condition(r, n, {**scope, **extra} if extra else scope, ctx)

    if head in ("and", "or"):
        return Junction(head, tuple(sub(i) for i in items[1:]))
    if head == "not":
        if len(items) != 2:
            raise r.fail(node.line, f"{ctx}: expected (not FORMULA)")
        return Junction("not", (sub(items[1]),))
    if head == "imply":
        if len(items) != 3:
            raise r.fail(node.line, f"{ctx}: expected (imply FORMULA FORMULA)")
        return Junction("imply", (sub(items[1]), sub(items[2])))
    if head in ("forall", "exists"):
        if len(items) != 3:
            raise r.fail(node.line, f"{ctx}: expected ({head} (?x - TYPE ...) FORMULA)")
        variables = r.variables(items[1], ctx)
        return Quantified(head, variables, sub(items[2], dict(variables)))
    if head == "probabilistic":
        raise r.fail(node.line, f"{ctx}: (probabilistic ...) can only be an effect, not a "
                     f"{'precondition' if ctx.startswith('action') else 'goal'}")
    if head in ("when", "increase", "decrease", "oneof"):
        raise r.fail(node.line, f"{ctx}: ({head} ...) can only be an effect, not part of a "
                     "condition")
    if head == "=":
        return Literal(read_term(r, node, "=", ("object", "object"), scope, ctx), True)
    return Literal(read_atom(r, node, scope, ctx), True)


def bare_atom(r: Reader, node: Node) -> Node:
    """``node``, or, if it is the bare name of a declared 0-ary predicate (``dead`` for
    ``(dead)``, as published IPPC domains write it), its atom ``(dead)``."""
    if not node.is_list and r.predicates.get(node.symbol) == ():
        return Node(node.line, (node,))
    return node


def bare_term(node: Node) -> Node:
    """A function term written without parentheses (``reward`` for ``(reward)``: PDDL
    2.1's ``<f-head> ::= <function-symbol>``, as published IPPC domains write it) as the
    term; any other node as it is."""
    return Node(node.line, (node,)) if not node.is_list else node


def read_atom(r: Reader, node: Node, scope: dict[str, str], ctx: str,
          effect: bool = False) -> Atom:
    """An atom of a declared predicate; (stuck) only in an ``effect``: it marks a failed
    trial, never part of a state."""
    node = bare_atom(r, node)
    items = r.lst(node, "an atom")
    if not items:
        raise r.fail(node.line, f"{ctx}: expected an atom (PREDICATE ARGS...), found ()")
    name = r.symbol(items[0], "a predicate name")
    if name not in r.predicates:
        raise r.fail(node.line, f"{ctx}: unknown predicate {name!r} "
                     f"(declared: {', '.join(sorted(r.predicates)) or 'none'})")
    atom = read_term(r, node, name, r.predicates[name], scope, ctx)
    if atom.predicate == STUCK and r.stuck_domain and not effect:
        raise r.fail(node.line, f"{ctx}: (stuck) marks a failed trial (an outcome that makes "
                     "it true ends the episode), so it cannot be a precondition, a goal or "
                     "initially true; rename the predicate if it is an ordinary fluent")
    return atom


def read_term(r: Reader, node: Node, name: str, want: tuple[str, ...], scope: dict[str, str],
          ctx: str) -> Atom:
    """``(name args...)`` whose arguments, known in ``scope``, fit the types ``want``."""
    args = tuple(r.symbol(a, "a term") for a in node.items[1:])
    if len(args) != len(want):
        raise r.fail(node.line, f"{ctx}: {name} takes {len(want)} argument(s), got {len(args)}")
    for a, t in zip(args, want, strict=True):
        if a not in scope:
            raise r.fail(node.line, f"{ctx}: unknown {'variable' if a[0] == '?' else 'object'}"
                         f" {a!r} in ({name} ...)")
        if not is_subtype(r.types, scope[a], t):
            raise r.fail(node.line, f"{ctx}: {a} is a {scope[a]}, but {name} expects a {t}")
    return Atom(name, args)


def is_subtype(types: dict[str, str | None], t: str, want: str) -> bool:
    """Whether type ``t`` is ``want`` or one of its descendants."""
    seen: set[str] = set()
    cur: str | None = t
    while cur is not None and cur not in seen:
        if cur == want:
            return True
        seen.add(cur)
        cur = types.get(cur)
    return want == "object"
