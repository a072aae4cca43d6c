"""A PDDL reader for STRIPS with typing (plus negative preconditions and equality).

It reads a domain and a problem into the small frozen types of :mod:`gdq_pddl.pddl.model`
and checks that they fit together. Every error is a :class:`~gdq_pddl.errors.PDDLError`
naming the file, the line and what was expected. It exists beside unified-planning's
reader because that one took about 1.2 s on its first call (it builds its grammar) and
reports pyparsing character offsets; plans are still validated with unified-planning.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from gdq_pddl.errors import PDDLError
from gdq_pddl.inputs import read_text
from gdq_pddl.pddl.model import Action, Atom, Domain, Literal, Problem

SUPPORTED = {":strips", ":typing", ":negative-preconditions", ":equality"}
_TOKEN = re.compile(r";[^\n]*|\(|\)|[^\s()]+|\s+")


@dataclass(frozen=True)
class Node:
    """An s-expression: a list of nodes or a lower-cased symbol, with its line."""

    line: int
    items: tuple[Node, ...] | None = None
    symbol: str = ""

    @property
    def is_list(self) -> bool:
        return self.items is not None

    def text(self) -> str:
        if self.items is None:
            return self.symbol
        return "(" + " ".join(i.text() for i in self.items) + ")"


class _Reader:
    def __init__(self, text: str, source: str) -> None:
        self.text, self.source = text, source

    def fail(self, line: int | None, message: str) -> PDDLError:
        return PDDLError(self.source, line, message)

    def tree(self) -> Node:
        stack: list[tuple[int, list[Node]]] = []
        line, top = 1, None
        for match in _TOKEN.finditer(self.text):
            tok = match.group()
            if tok == "(":
                stack.append((line, []))
            elif tok == ")":
                if not stack:
                    raise self.fail(line, "unexpected ')' with no '(' open")
                start, items = stack.pop()
                node = Node(start, tuple(items))
                if stack:
                    stack[-1][1].append(node)
                elif top is None:
                    top = node
                else:
                    raise self.fail(start, "expected end of file after the (define ...) form")
            elif tok[0].isspace() or tok[0] == ";":
                pass
            elif not stack:
                raise self.fail(line, f"expected '(' but found {tok!r}")
            else:
                stack[-1][1].append(Node(line, symbol=tok.lower()))
            line += tok.count("\n")
        if stack:
            line = _suspect_unclosed(self.text) or stack[-1][0]
            raise self.fail(line, "expected ')': this '(' is never closed")
        if top is None:
            raise self.fail(None, "empty file: expected (define ...)")
        return top

    # --- helpers ---------------------------------------------------------------------
    def symbol(self, node: Node, what: str) -> str:
        if node.is_list:
            raise self.fail(node.line, f"expected {what}, found {node.text()}")
        return node.symbol

    def lst(self, node: Node, what: str) -> tuple[Node, ...]:
        if not node.is_list:
            raise self.fail(node.line, f"expected {what}, found {node.symbol!r}")
        return node.items  # type: ignore[return-value]

    def header(self, top: Node, kind: str) -> tuple[str, tuple[Node, ...]]:
        items = self.lst(top, "(define ...)")
        if len(items) < 2 or items[0].symbol != "define":
            raise self.fail(top.line, "expected (define (" + kind + " NAME) ...)")
        head = self.lst(items[1], f"({kind} NAME)")
        if len(head) != 2 or head[0].symbol != kind:
            raise self.fail(items[1].line, f"expected ({kind} NAME), found {items[1].text()}")
        return self.symbol(head[1], f"a {kind} name"), items[2:]

    def typed_list(self, nodes: tuple[Node, ...], variables: bool) -> list[tuple[str, str]]:
        """``a b - t c`` -> [(a, t), (b, t), (c, object)]."""
        out: list[tuple[str, str]] = []
        pending: list[str] = []
        i = 0
        while i < len(nodes):
            name = self.symbol(nodes[i], "a name")
            if name == "-":
                if i + 1 >= len(nodes) or not pending:
                    raise self.fail(nodes[i].line, "expected names before '- TYPE'")
                typ = self.symbol(nodes[i + 1], "a type name")
                out += [(p, typ) for p in pending]
                pending = []
                i += 2
                continue
            if variables != name.startswith("?"):
                want = "a variable (?x)" if variables else "a name (not a variable)"
                raise self.fail(nodes[i].line, f"expected {want}, found {name!r}")
            pending.append(name)
            i += 1
        return out + [(p, "object") for p in pending]

    def sections(self, body: tuple[Node, ...]) -> dict[str, Node]:
        out: dict[str, Node] = {}
        for node in body:
            items = self.lst(node, "a section such as (:predicates ...)")
            if not items or items[0].is_list or not items[0].symbol.startswith(":"):
                raise self.fail(node.line,
                                f"expected a section (:keyword ...), found {node.text()}")
            key = items[0].symbol
            if key != ":action" and key in out:
                raise self.fail(node.line, f"duplicate section {key}")
            out[key if key != ":action" else f":action{len(out)}"] = node
        return out


def _suspect_unclosed(text: str) -> int | None:
    """The line of the '(' most likely missing its ')', judged by indentation.

    A form still open when a later line starts at its own indentation or further left
    (not counting lines that start with ')') has most probably lost its ')'.
    """
    open_at: list[tuple[int, int]] = []  # (line, indentation of that line)
    for number, raw in enumerate(text.splitlines(), 1):
        code = raw.split(";", 1)[0]
        stripped = code.lstrip()
        indent = len(code) - len(stripped)
        if stripped and not stripped.startswith(")"):
            for line, ind in reversed(open_at):
                if line < number and ind >= indent:
                    return line
        for ch in code:
            if ch == "(":
                open_at.append((number, indent))
            elif ch == ")" and open_at:
                open_at.pop()
    return None


def parse_domain(text: str, source: str = "<domain>") -> Domain:
    """Parse a domain; raise :class:`PDDLError` with file and line on any problem."""
    r = _Reader(text, source)
    name, body = r.header(r.tree(), "domain")
    sec = r.sections(body)
    known = {":requirements", ":types", ":constants", ":predicates"}
    for key, node in sec.items():
        if key not in known and not key.startswith(":action"):
            raise r.fail(node.line, f"{key.split('0')[0]} is not supported "
                         "(gdq_pddl reads STRIPS with typing)")
    reqs = set()
    if ":requirements" in sec:
        for n in sec[":requirements"].items[1:]:
            req = r.symbol(n, "a requirement")
            if req not in SUPPORTED:
                raise r.fail(n.line, f"requirement {req} is not supported "
                             f"(supported: {' '.join(sorted(SUPPORTED))})")
            reqs.add(req)
    types = {"object": None}
    if ":types" in sec:
        for t, parent in r.typed_list(sec[":types"].items[1:], variables=False):
            types[t] = parent
        for t, parent in list(types.items()):
            if parent is not None and parent not in types:
                raise r.fail(sec[":types"].line, f"type {t} has unknown parent type {parent}")
    constants = {}
    if ":constants" in sec:
        for c, t in r.typed_list(sec[":constants"].items[1:], variables=False):
            _check_type(r, types, t, sec[":constants"].line)
            constants[c] = t
    predicates: dict[str, tuple[str, ...]] = {}
    if ":predicates" in sec:
        for node in sec[":predicates"].items[1:]:
            items = r.lst(node, "a predicate (name ?x - type ...)")
            if not items:
                raise r.fail(node.line, "expected a predicate name")
            pname = r.symbol(items[0], "a predicate name")
            params = r.typed_list(items[1:], variables=True)
            for _, t in params:
                _check_type(r, types, t, node.line)
            predicates[pname] = tuple(t for _, t in params)
    actions = []
    for key, node in sec.items():
        if key.startswith(":action"):
            actions.append(_action(r, node, predicates, types, constants, reqs))
    names = [a.name for a in actions]
    if len(set(names)) != len(names):
        raise r.fail(None, f"duplicate action names in {sorted(names)}")
    return Domain(name, frozenset(reqs), types, constants, predicates, tuple(actions), source)


def _check_type(r: _Reader, types: dict[str, str | None], t: str, line: int) -> None:
    if t not in types:
        raise r.fail(line, f"unknown type {t!r} (declared: {', '.join(sorted(types))})")


def _action(r: _Reader, node: Node, predicates: dict[str, tuple[str, ...]],
            types: dict[str, str | None], constants: dict[str, str], reqs: set[str]) -> Action:
    items = node.items
    assert items is not None
    if len(items) < 2:
        raise r.fail(node.line, "expected (:action NAME :parameters (...) ...)")
    name = r.symbol(items[1], "an action name")
    fields: dict[str, Node] = {}
    rest = items[2:]
    if len(rest) % 2:
        raise r.fail(node.line, f"action {name}: expected pairs of :keyword value")
    for key, value in zip(rest[::2], rest[1::2], strict=True):
        k = r.symbol(key, ":parameters, :precondition or :effect")
        if k not in (":parameters", ":precondition", ":effect"):
            raise r.fail(key.line, f"action {name}: unexpected {k} (expected :parameters, "
                         ":precondition or :effect)")
        fields[k] = value
    params = r.typed_list(r.lst(fields[":parameters"], "a parameter list"), variables=True) \
        if ":parameters" in fields else []
    for _, t in params:
        _check_type(r, types, t, node.line)
    scope = dict(params) | constants
    ctx = f"action {name}"
    pre = _literals(r, fields.get(":precondition"), predicates, types, scope, ctx, reqs, True)
    eff = _literals(r, fields.get(":effect"), predicates, types, scope, ctx, reqs, False)
    return Action(name, tuple(params), tuple(pre), tuple(eff), node.line)


def _literals(r: _Reader, node: Node | None, predicates: dict[str, tuple[str, ...]],
              types: dict[str, str | None], scope: dict[str, str], ctx: str,
              reqs: set[str], precondition: bool) -> list[Literal]:
    """Flatten a conjunction of (possibly negated) atoms."""
    if node is None:
        return []
    items = r.lst(node, "a formula")
    if not items:
        return []
    head = items[0].symbol
    if head == "and":
        out: list[Literal] = []
        for sub in items[1:]:
            out += _literals(r, sub, predicates, types, scope, ctx, reqs, precondition)
        return out
    if head == "not":
        if len(items) != 2:
            raise r.fail(node.line, f"{ctx}: expected (not (ATOM))")
        inner = _literals(r, items[1], predicates, types, scope, ctx, reqs, precondition)
        if len(inner) != 1 or not inner[0].positive:
            raise r.fail(node.line, f"{ctx}: (not ...) must wrap a single atom")
        if precondition and inner[0].atom.predicate != "=" and \
                ":negative-preconditions" not in reqs:
            raise r.fail(node.line, f"{ctx}: a negative precondition needs the "
                         ":negative-preconditions requirement")
        return [Literal(inner[0].atom, False)]
    if head in ("or", "imply", "forall", "exists", "when", "increase", "decrease"):
        raise r.fail(node.line, f"{ctx}: ({head} ...) is not supported (STRIPS with typing only)")
    if head == "=":
        if not precondition:
            raise r.fail(node.line, f"{ctx}: equality cannot be an effect")
        args = tuple(r.symbol(a, "a term") for a in items[1:])
        if len(args) != 2:
            raise r.fail(node.line, f"{ctx}: (= a b) takes two terms")
        for a in args:
            if a not in scope:
                raise r.fail(node.line, f"{ctx}: unknown term {a!r}")
        return [Literal(Atom("=", args), True)]
    return [Literal(_atom(r, node, predicates, types, scope, ctx), True)]


def _atom(r: _Reader, node: Node, predicates: dict[str, tuple[str, ...]],
          types: dict[str, str | None], scope: dict[str, str], ctx: str) -> Atom:
    items = r.lst(node, "an atom")
    if not items:
        raise r.fail(node.line, f"{ctx}: expected an atom (PREDICATE ARGS...), found ()")
    name = r.symbol(items[0], "a predicate name")
    if name not in predicates:
        raise r.fail(node.line, f"{ctx}: unknown predicate {name!r} "
                     f"(declared: {', '.join(sorted(predicates)) or 'none'})")
    args = tuple(r.symbol(a, "a term") for a in items[1:])
    want = predicates[name]
    if len(args) != len(want):
        raise r.fail(node.line, f"{ctx}: {name} takes {len(want)} argument(s), got {len(args)}")
    for a, t in zip(args, want, strict=True):
        if a not in scope:
            raise r.fail(node.line, f"{ctx}: unknown {'variable' if a[0] == '?' else 'object'}"
                         f" {a!r} in ({name} ...)")
        if not is_subtype(types, scope[a], t):
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


def parse_problem(text: str, domain: Domain, source: str = "<problem>") -> Problem:
    """Parse a problem for ``domain``; raise :class:`PDDLError` if it does not fit."""
    r = _Reader(text, source)
    name, body = r.header(r.tree(), "problem")
    sec = r.sections(body)
    for key, node in sec.items():
        if key not in (":domain", ":objects", ":init", ":goal", ":requirements"):
            raise r.fail(node.line, f"{key} is not supported in a problem")
    if ":domain" not in sec:
        raise r.fail(None, "expected (:domain NAME)")
    dnode = sec[":domain"]
    dname = r.symbol(dnode.items[1], "a domain name") if len(dnode.items) == 2 else None
    if dname != domain.name:
        raise r.fail(dnode.line, f"problem is for domain {dname!r}, but the domain is "
                     f"{domain.name!r} ({domain.source})")
    objects = dict(domain.constants)
    if ":objects" in sec:
        for o, t in r.typed_list(sec[":objects"].items[1:], variables=False):
            _check_type(r, domain.types, t, sec[":objects"].line)
            if o in objects:
                raise r.fail(sec[":objects"].line, f"object {o} is declared twice")
            objects[o] = t
    if ":init" not in sec:
        raise r.fail(None, "expected (:init ...), the initial state")
    init = [_atom(r, node, domain.predicates, domain.types, objects, "init")
            for node in sec[":init"].items[1:]]
    if ":goal" not in sec:
        raise r.fail(None, "expected (:goal ...)")
    gnode = sec[":goal"]
    if len(gnode.items) != 2:
        raise r.fail(gnode.line, f"expected (:goal FORMULA), one formula; found "
                     f"{len(gnode.items) - 1}")
    goal = _literals(r, gnode.items[1], domain.predicates, domain.types, objects, "goal",
                     set(domain.requirements), True)
    return Problem(name, domain.name, objects, frozenset(init), tuple(goal), source)


def read_domain(path: str | Path) -> Domain:
    """Read and parse a domain file."""
    return parse_domain(_read(path), str(path))


def read_problem(path: str | Path, domain: Domain) -> Problem:
    """Read and parse a problem file for ``domain``."""
    return parse_problem(_read(path), domain, str(path))


def _read(path: str | Path) -> str:
    return read_text(path, lambda src, msg: PDDLError(src, None, msg))
