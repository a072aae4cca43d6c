"""PDDL's s-expressions, read with file:line errors: the tokens of a file, its top-level
``(define ...)`` forms, names, typed lists and sections, checked as they are read
(:class:`Reader`), and the text of a PDDL file (:func:`read_pddl_text`). Every error is a
:class:`~gdq_pddl.errors.PDDLError` naming the file, the line and what was expected."""

from __future__ import annotations

import re
import string
import warnings
from dataclasses import dataclass
from pathlib import Path

from gdq_pddl.errors import PDDLError
from gdq_pddl.inputs import BOM, read_text
from gdq_pddl.pddl.model import STUCK, Domain

_TOKEN = re.compile(r";[^\n]*|\(|\)|[^\s();]+|\s+")
_SYMBOL = re.compile(r"[?:]?[A-Za-z0-9_.+/-]+|=")
"""A name, ``?variable``, ``:keyword``, number, ``-`` or ``=``; any other character is
refused where it stands (``#`` does not start a comment: ``;`` does)."""
_SYMBOL_CHARS = frozenset(string.ascii_letters + string.digits + "_.+/-")
_NAME = re.compile(r"[a-z][a-z0-9_-]*")
"""PDDL's names: a letter, then letters, digits, ``-`` and ``_``."""
_PROBLEM_NAME = re.compile(r"[a-z0-9][a-z0-9_-]*")
"""A problem's name may also start with a digit (as a world file's name may)."""
MAX_DEPTH = 200
"""Deepest nesting of parentheses read (later stages recurse over formulas)."""
_OUTSIDE = {"oneof": " (FOND: give probabilities with (probabilistic ...))",
            "assign": " (numeric fluents)", "scale-up": " (numeric fluents)",
            "scale-down": " (numeric fluents)", "either": " (either-types)",
            **dict.fromkeys((":durative-action", ":derived", ":process", ":event", ":axiom",
                             ":constraints", ":timed-initial-literals"), "")}
"""Connectives and sections outside the language read, each with a hint."""


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


class Reader:
    """One file's text, and the declarations of the domain being read or read for."""

    def __init__(self, text: str, source: str, domain: Domain | None = None) -> None:
        self.text, self.source = text.removeprefix(BOM), source
        self.types: dict[str, str | None] = dict(domain.types) if domain else {"object": None}
        self.predicates = dict(domain.predicates) if domain else {}
        self.functions = dict(domain.functions) if domain else {}

    @property
    def stuck_domain(self) -> bool:
        """The domain declares the 0-ary predicate :data:`~gdq_pddl.pddl.model.STUCK`."""
        return self.predicates.get(STUCK) == ()

    def fail(self, line: int | None, message: str) -> PDDLError:
        return PDDLError(self.source, line, message)

    def forms(self) -> list[Node]:
        """The file's top-level forms (one ``(define ...)`` each); a file using constructs
        outside the language is refused, naming every use."""
        top: list[Node] = []
        stack: list[tuple[int, list[Node]]] = [(0, top)]  # the file, then the open forms
        line, outside = 1, {}  # outside: construct -> the lines it is used at
        for match in _TOKEN.finditer(self.text):
            tok = match.group()
            if tok == "(":
                if len(stack) > MAX_DEPTH:
                    raise self.fail(line, f"parentheses nested more than {MAX_DEPTH} levels "
                                    "deep; no domain or problem needs that many (is a ')' "
                                    "missing?)")
                stack.append((line, []))
            elif tok == ")":
                if len(stack) == 1:
                    raise self.fail(line, "unexpected ')' with no '(' open")
                start, items = stack.pop()
                if items and items[0].symbol in _OUTSIDE:
                    outside.setdefault(items[0].symbol, []).append(start)
                stack[-1][1].append(Node(start, tuple(items)))
            elif tok[0].isspace() or tok[0] == ";":
                pass
            elif len(stack) == 1:
                raise self.fail(line, f"expected '(' but found {tok!r}")
            else:
                stack[-1][1].append(Node(line, symbol=self.checked(tok, line)))
            line += tok.count("\n")
        suspect = _suspect_unclosed(self.text) if len(stack) > 1 else None
        if len(stack) == 2 and stack[1][1][:1] and stack[1][1][0].symbol == "define" and \
                suspect in (None, stack[1][0]):
            # only the last (define ...) is open at the end, and the indentation does not
            # point at a '(' inside it: pddlgym ships files that lack the define's final
            # ')' (navigation2-10) and reads them; so do we, saying so
            start, items = stack.pop()
            warnings.warn(f"{self.source}:{start}: this (define ...) is never closed; read as "
                          "if the file ended with its ')'", stacklevel=2)
            top.append(Node(start, tuple(items)))
        if len(stack) > 1:
            line = suspect or stack[-1][0]
            raise self.fail(line, "expected ')': this '(' is never closed")
        if not top:
            raise self.fail(None, "empty file: expected (define ...)")
        if outside:
            order = sorted(outside, key=lambda h: min(outside[h]))
            listed = "; ".join(f"({h} ...){_OUTSIDE[h]} at line"
                               f"{'s' if len(outside[h]) > 1 else ''} "
                               f"{', '.join(map(str, sorted(outside[h])))}" for h in order)
            raise self.fail(min(outside[order[0]]), "not supported (gdq_pddl reads the PPDDL of "
                            f"the IPPC probabilistic tracks, docs/domains.md): {listed}")
        return top

    def pick(self, kind: str, name: str | None = None) -> tuple[Node, str, tuple[Node, ...]]:
        """The ``(define (KIND NAME) BODY...)`` form of the file (the only one of its kind,
        or the one named ``name``; the others may be of the other kind), its name and
        body."""
        found: list[tuple[str, Node]] = []
        for node in self.forms():
            items = self.lst(node, "(define ...)")
            head = items[1] if len(items) >= 2 and items[0].symbol == "define" else None
            if head is None or not head.is_list or not head.items or \
                    head.items[0].symbol not in ("domain", "problem"):
                text = node.text()
                raise self.fail(node.line, "expected (define (domain NAME) ...) or (define "
                                "(problem NAME) ...), found "
                                + (text if len(text) <= 60 else text[:57] + "..."))
            if head.items[0].symbol == kind:
                label = head.items[1].symbol if len(head.items) == 2 else ""
                found.append((label, node))
        if not found:
            raise self.fail(None, f"expected a (define ({kind} NAME) ...) form; this file "
                            f"has only {'problem' if kind == 'domain' else 'domain'}s")
        first_at: dict[str, Node] = {}
        for label, node in found:  # symbols are read lower-cased: ONE and one are one name
            if label and first_at.setdefault(label, node) is not node:
                raise self.fail(node.line, f"two {kind}s are named {label!r}, at lines "
                                f"{first_at[label].line} and {node.line} (names ignore "
                                f"case): rename one, a name must pick one {kind}")
        labels = ", ".join(label for label, _ in found)
        if name is not None:
            chosen = [node for label, node in found if label == name.lower()]
            if not chosen:
                raise self.fail(None, f"no {kind} named {name!r} in this file (it has "
                                f"{labels})")
            top = chosen[0]
        elif len(found) > 1:
            raise self.fail(found[1][1].line, f"this file has {len(found)} {kind}s "
                            f"({labels}): pick one by name" + self._pick_advice(kind, found))
        else:
            top = found[0][1]
        items = self.lst(top, "(define ...)")
        head = self.lst(items[1], f"({kind} NAME)")
        if len(head) != 2:
            raise self.fail(items[1].line, f"expected ({kind} NAME), found {items[1].text()}")
        grammar = _PROBLEM_NAME if kind == "problem" else _NAME
        return top, self.name(head[1], f"a {kind} name", grammar=grammar), items[2:]

    def _pick_advice(self, kind: str, found: list[tuple[str, Node]]) -> str:
        """How to name one of the problems ``found`` (the first named one), as the place the
        text came from takes it: ``FILE:NAME`` for a file, the name alone for a text."""
        named = next((label for label, _ in found if label), None)
        if kind != "problem" or named is None:
            return ""
        if not self.source.startswith("<"):  # a file's name, not a label like <problem>
            return f" ({self.source}:{named})"
        return f" (its name, such as {named!r})"

    def checked(self, tok: str, line: int) -> str:
        """``tok`` lower-cased, or a :class:`PDDLError` naming its first character that
        no symbol may have."""
        if _SYMBOL.fullmatch(tok):
            return tok.lower()
        bad = next((ch for i, ch in enumerate(tok)
                    if ch not in _SYMBOL_CHARS and not (i == 0 and ch in "?:")), None)
        if bad is None:  # a lone '?' or ':'
            raise self.fail(line, f"expected a name, a ?variable, a :keyword or a number, "
                            f"found {tok!r}")
        hint = " (a comment starts with ';', not '#')" if bad == "#" else ""
        raise self.fail(line, f"the character {bad!r} cannot be part of a name, found in "
                        f"{tok!r}{hint}; names are ASCII letters, digits, '-' and '_'")

    def name(self, node: Node, what: str, variable: bool = False,
             grammar: re.Pattern = _NAME) -> str:
        """The symbol ``node``, which must be a name (``variable``: a ``?name``)."""
        text = self.symbol(node, what)
        bare = text[1:] if variable and text.startswith("?") else text
        if (variable and not text.startswith("?")) or not grammar.fullmatch(bare):
            first = "letter or digit" if grammar is _PROBLEM_NAME else "letter"
            raise self.fail(node.line, f"expected {what}, found {text!r} (a name is a "
                            f"{first}, then letters, digits, '-' and '_'"
                            + ("; a variable is '?' and a name)" if variable else ")"))
        return text

    def symbol(self, node: Node, what: str) -> str:
        if node.is_list:
            raise self.fail(node.line, f"expected {what}, found {node.text()}")
        return node.symbol

    def lst(self, node: Node, what: str) -> tuple[Node, ...]:
        if not node.is_list:
            raise self.fail(node.line, f"expected {what}, found {node.symbol!r}")
        return node.items  # type: ignore[return-value]

    def typed_list(self, nodes: tuple[Node, ...], variables: bool, what: str,
                   check: bool = True) -> list[tuple[str, str, int]]:
        """``a b - t c`` -> [(a, t, line), (b, t, line), (c, object, line)]; a name
        given twice (``what``: what the names are) and, if ``check``, an undeclared type
        are refused."""
        out: list[tuple[str, str, int]] = []
        pending: list[tuple[str, int]] = []
        first: dict[str, int] = {}
        i = 0
        while i < len(nodes):
            glued = nodes[i].symbol[:1] == "-" and _NAME.fullmatch(nodes[i].symbol[1:])
            if nodes[i].symbol == "-" or glued:  # '-TYPE' is '- TYPE', as PDDL lexers read it
                if (not glued and i + 1 >= len(nodes)) or not pending:
                    raise self.fail(nodes[i].line, "expected names before '- TYPE'")
                typ = nodes[i].symbol[1:] if glued else self.name(nodes[i + 1], "a type name")
                out += [(p, typ, line) for p, line in pending]
                pending = []
                i += 1 if glued else 2
                continue
            kind = "a variable (?x)" if variables else "a name (not a variable)"
            name = self.name(nodes[i], kind, variable=variables)
            if name in first:
                raise self.fail(nodes[i].line, f"{what} {name} is declared twice (first at "
                                f"line {first[name]})")
            first[name] = nodes[i].line
            pending.append((name, nodes[i].line))
            i += 1
        out += [(p, "object", line) for p, line in pending]
        for _, t, line in out if check else ():
            if t not in self.types:
                raise self.fail(line, f"unknown type {t!r} (declared: "
                                f"{', '.join(sorted(self.types))})")
        return out

    def variables(self, node: Node, ctx: str) -> tuple[tuple[str, str], ...]:
        """The ``(?x - t ...)`` of a ``forall`` or ``exists``."""
        typed = self.typed_list(self.lst(node, "a variable list"), True, f"{ctx}: variable")
        return tuple((v, t) for v, t, _ in typed)

    def sections(self, body: tuple[Node, ...], known: tuple[str, ...],
                 kind: str) -> tuple[dict[str, Node], list[Node]]:
        """The sections of a domain or problem by keyword, and its ``(:action ...)``
        forms in order; a keyword not in ``known`` and a section given twice are refused."""
        out: dict[str, Node] = {}
        actions: list[Node] = []
        for node in body:
            items = self.lst(node, "a section such as (:predicates ...)")
            if not items or items[0].is_list or not items[0].symbol.startswith(":"):
                raise self.fail(node.line,
                                f"expected a section (:keyword ...), found {node.text()}")
            key = items[0].symbol
            if key not in known:
                raise self.fail(node.line, f"unknown section {key} in a {kind} (expected "
                                f"one of {', '.join(known)})")
            if key == ":action":
                actions.append(node)
                continue
            if key in out:
                raise self.fail(node.line, f"duplicate section {key} (first at line "
                                f"{out[key].line})")
            out[key] = node
        return out, actions


def _suspect_unclosed(text: str) -> int | None:
    """The line of the '(' most likely missing its ')': the last one still open when a
    later line (not starting with ')') starts at its indentation or further left."""
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


def read_pddl_text(path: str | Path) -> str:
    """The text of a PDDL file; an unreadable one is a :class:`PDDLError` naming it."""
    return read_text(path, lambda src, msg: PDDLError(src, None, msg))
