"""The package's layers (SPEC section 7), read from the source with ``ast``.

Every module of ``gdq_pddl`` is parsed; every import in it (at the top, under
``TYPE_CHECKING``, inside a function; absolute, relative, ``import a.b.c`` and
``from a import submodule``) is an edge of the module import graph. The test fails on

- an import cycle between modules, hidden behind a function-level import or not;
- an import that points up the layer order of :data:`LAYERS` (``gdq_pddl/__init__.py``,
  the package face, may import from any layer; nothing may import the face);
- an import inside a function without a comment, on its line or the line above, saying
  why it is deferred: an optional dependency or start-up time (see :data:`REASON`);
- a module that no layer holds: add it to :data:`LAYERS`.

What it cannot see: modules loaded by name at run time (``importlib``, entry points).
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from dataclasses import dataclass, field
from pathlib import Path

import pytest

import gdq_pddl

LAYERS: dict[str, int] = {
    "errors": 0, "resources": 0, "limits": 0, "inputs": 0, "outputs": 0, "_jit_cache": 0,
    "pddl": 1,
    "planning": 2,
    "abstraction": 3, "spaces": 3,
    "dynamics": 4, "world_types": 4, "world": 4, "buildings": 4,
    "envs": 5,
    "learners": 6, "wrappers": 6,
    "experiments": 7,
    "analysis": 8, "exercises": 8,
    "cli": 9,
}
"""The layer of each top-level module or subpackage of the package, lowest first. A
module imports from its own layer or lower ones, never from a higher one."""

REASON = re.compile(r"optional|start[- ]?up|(import|load)(ing)? time|slow to (import|load)"
                    r"|heavy to import|import cost", re.IGNORECASE)
"""What a comment must say to justify an import inside a function."""

PRAGMA = re.compile(r"#\s*(noqa|type:|pragma|pyright:|mypy:)[^#]*", re.IGNORECASE)


@dataclass(frozen=True)
class Edge:
    """One import statement of ``source`` that loads ``target`` (both module names)."""

    source: str
    target: str
    path: Path
    line: int
    kind: str  # "top", "function" or "TYPE_CHECKING"

    def where(self) -> str:
        at = f"{self.path.as_posix()}:{self.line}"
        return at if self.kind == "top" else f"{at} ({self.kind})"


@dataclass(frozen=True)
class Cycle:
    """A group of modules that import each other: one cycle through it, and every import
    inside the group (each lies on some cycle: the candidates to cut)."""

    cycle: list[Edge]
    edges: list[Edge]


@dataclass
class Findings:
    """What :func:`check_package` finds; each list empty when the package is clean."""

    cycles: list[Cycle] = field(default_factory=list)
    upward: list[Edge] = field(default_factory=list)
    unjustified: list[Edge] = field(default_factory=list)
    unassigned: list[str] = field(default_factory=list)
    edges: list[Edge] = field(default_factory=list)
    layer_of: dict[str, int | None] = field(default_factory=dict)  # None: the package face

    def layer(self, module: str) -> str:
        layer = self.layer_of[module]
        return "face" if layer is None else str(layer)

    def report(self) -> str:
        lines: list[str] = []
        if self.unassigned:
            lines.append(f"{len(self.unassigned)} module(s) in no layer (add each to LAYERS "
                         "in tests/test_architecture.py):")
            lines += [f"  {m}" for m in self.unassigned]
        if self.cycles:
            lines.append(f"{len(self.cycles)} group(s) of modules importing each other "
                         "(a cycle through each, then every import inside the group):")
            for c in self.cycles:
                lines.append("  cycle: " + " -> ".join([e.source for e in c.cycle]
                                                       + [c.cycle[0].source]))
                lines += [f"      {e.source} -> {e.target}  at {e.where()}" for e in c.edges]
        if self.upward:
            lines.append(f"{len(self.upward)} import(s) pointing up the layers:")
            lines += [f"  {e.source} (layer {self.layer(e.source)}) -> {e.target} (layer "
                      f"{self.layer(e.target)})  at {e.where()}" for e in self.upward]
        if self.unjustified:
            lines.append(f"{len(self.unjustified)} import(s) inside a function with no "
                         "comment saying why (optional dependency or start-up time); "
                         "move each to the top of its module or say why:")
            lines += [f"  {e.path.as_posix()}:{e.line}  {e.target}" for e in self.unjustified]
        return "\n".join(lines)


def module_names(root: Path, package: str) -> dict[str, Path]:
    """Every module of the package under ``root`` (the package's folder), by its name."""
    modules = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        modules[".".join([package, *parts])] = path
    return modules


def _resolve(name: str, modules: dict[str, Path]) -> str | None:
    """The module ``name`` loads: itself, or its nearest enclosing package that exists."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _imports(tree: ast.Module):
    """(node, kind) for every import statement, with where it sits."""
    def visit(node: ast.AST, kind: str):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Import | ast.ImportFrom):
                yield child, kind
            elif isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
                yield from visit(child, "function")
            elif isinstance(child, ast.If) and _is_type_checking(child.test) and kind == "top":
                for stmt in child.body:
                    yield from visit(ast.Module(body=[stmt], type_ignores=[]), "TYPE_CHECKING")
                for stmt in child.orelse:
                    yield from visit(ast.Module(body=[stmt], type_ignores=[]), kind)
            else:
                yield from visit(child, kind)

    yield from visit(tree, "top")


def _targets(node: ast.Import | ast.ImportFrom, module: str, is_package: bool,
             package: str, modules: dict[str, Path]) -> list[str]:
    """The modules of the package one import statement loads."""
    if isinstance(node, ast.Import):
        names = [alias.name for alias in node.names]
    else:
        if node.level:
            base = module if is_package else module.rpartition(".")[0]
            for _ in range(node.level - 1):
                base = base.rpartition(".")[0]
            origin = f"{base}.{node.module}" if node.module else base
        else:
            origin = node.module or ""
        # ``from a import b``: the submodule a.b when there is one, else a itself
        names = [f"{origin}.{alias.name}" if f"{origin}.{alias.name}" in modules else origin
                 for alias in node.names]
    targets = []
    for name in names:
        if name == package or name.startswith(package + "."):
            target = _resolve(name, modules)
            if target and target != module and target not in targets:
                targets.append(target)
    return targets


def _comments(source: str) -> dict[int, str]:
    """The comment on each line (pragmas such as ``# noqa`` left out)."""
    comments = {}
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            text = PRAGMA.sub("", tok.string).strip("# ").strip()
            if text:
                comments[tok.start[0]] = text
    return comments


def _justified(node: ast.stmt, comments: dict[int, str]) -> bool:
    lines = range(node.lineno - 1, (node.end_lineno or node.lineno) + 1)
    return any(REASON.search(comments.get(line, "")) for line in lines)


def _layer(module: str, package: str, layers: dict[str, int]) -> int | None:
    """The layer of ``module``; None for the package face; KeyError if unassigned."""
    if module == package:
        return None
    return layers[module.split(".")[1]]


def _groups(edges: list[Edge], modules: list[str]) -> list[list[str]]:
    """The strongly connected groups of two or more modules (Tarjan): the modules that
    import each other, directly or round about."""
    out: dict[str, list[str]] = {m: [] for m in modules}
    for e in edges:
        out[e.source].append(e.target)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in out[v]:
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for m in sorted(modules):
        if m not in index:
            connect(m)
    return sorted(groups)


def _shortest_cycle(edges: list[Edge], start: str) -> list[Edge]:
    """The shortest cycle from ``start`` back to it over ``edges`` (breadth first)."""
    previous: dict[str, Edge] = {}
    frontier = [start]
    while start not in previous:
        step = []
        for e in edges:
            if e.source in frontier and e.target not in previous:
                previous[e.target] = e
                step.append(e.target)
        frontier = step
    cycle, v = [], start
    while True:
        cycle.append(previous[v])
        v = previous[v].source
        if v == start:
            return cycle[::-1]


def _cycles(edges: list[Edge], modules: list[str]) -> list[Cycle]:
    cycles = []
    for group in _groups(edges, modules):
        members = set(group)
        inside = [e for e in edges if e.source in members and e.target in members]
        cycles.append(Cycle(_shortest_cycle(inside, group[0]), inside))
    return cycles


def check_package(root: Path, package: str, layers: dict[str, int]) -> Findings:
    """Read every module of the package in ``root`` and check its imports."""
    modules = module_names(root, package)
    found = Findings()
    for module in modules:
        if module != package and module.split(".")[1] not in layers:
            found.unassigned.append(module)
    for module, path in modules.items():
        source = path.read_text(encoding="utf-8")
        tree = ast.parse(source, filename=str(path))
        comments = _comments(source)
        shown = path.relative_to(root.parent)
        for node, kind in _imports(tree):
            if kind == "function" and not _justified(node, comments):
                # any import, of the package or not; its target here: the statement
                found.unjustified.append(Edge(module, _describe(node), shown, node.lineno,
                                              kind))
            for target in _targets(node, module, path.name == "__init__.py", package,
                                   modules):
                found.edges.append(Edge(module, target, shown, node.lineno, kind))
    for e in found.edges:
        if e.source == package or e.source in found.unassigned or e.target in found.unassigned:
            continue
        source, target = _layer(e.source, package, layers), _layer(e.target, package, layers)
        found.layer_of[e.source], found.layer_of[e.target] = source, target
        if target is None or target > source:
            found.upward.append(e)
    found.cycles = _cycles(found.edges, list(modules))
    return found


def _describe(node: ast.Import | ast.ImportFrom) -> str:
    names = ", ".join(a.name for a in node.names)
    if isinstance(node, ast.Import):
        return f"import {names}"
    return f"from {'.' * node.level}{node.module or ''} import {names}"


def test_the_package_keeps_its_layers_and_has_no_import_cycle() -> None:
    root = Path(gdq_pddl.__file__).resolve().parent
    found = check_package(root, "gdq_pddl", LAYERS)
    assert found.edges, "no import read: is the package where the test looks?"
    if found.cycles or found.upward or found.unjustified or found.unassigned:
        pytest.fail("\n" + found.report(), pytrace=False)


# --- the checker itself, on a tiny package ------------------------------------------------

FAKE = {
    "__init__.py": "from fake.top import main  # the face may import anything\n",
    "low.py": (
        "def f():\n"
        "    from fake import mid\n"
        "    return mid\n"
        "def g():\n"
        "    import json  # deferred: start-up time\n"
        "    # numpy: an optional dependency\n"
        "    import numpy\n"
        "    return json, numpy\n"),
    "side.py": ("from typing import TYPE_CHECKING\n"
                "import fake\n"
                "if TYPE_CHECKING:\n"
                "    from fake.top import main\n"),
    "mid/__init__.py": "from . import inner\n",
    "mid/inner.py": "import fake.low\nfrom ..low import f\n",
    "top.py": ("import fake.mid.inner\nfrom fake.mid import inner\nfrom .low import g\n"
               "def main():\n"
               "    import os  # noqa: F401\n"
               "    from fake import (\n"
               "        extra,\n"
               "    )\n"),
    "extra.py": "from fake import top\n",
}
FAKE_LAYERS = {"low": 0, "side": 0, "mid": 1, "top": 2}


def test_the_checker_finds_cycles_upward_imports_and_unexplained_deferred_ones(tmp_path):
    root = tmp_path / "fake"
    for name, text in FAKE.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text, encoding="utf-8")
    found = check_package(root, "fake", FAKE_LAYERS)
    assert {(e.source, e.target, e.line, e.kind) for e in found.edges} == {
        ("fake", "fake.top", 1, "top"),
        ("fake.low", "fake.mid", 2, "function"),  # a package: its __init__
        ("fake.side", "fake", 2, "top"),
        ("fake.side", "fake.top", 4, "TYPE_CHECKING"),
        ("fake.mid", "fake.mid.inner", 1, "top"),  # from . import submodule
        ("fake.mid.inner", "fake.low", 1, "top"),
        ("fake.mid.inner", "fake.low", 2, "top"),  # from ..low import name
        ("fake.top", "fake.mid.inner", 1, "top"),  # import a.b.c
        ("fake.top", "fake.mid.inner", 2, "top"),  # from a.b import submodule
        ("fake.top", "fake.low", 3, "top"),
        ("fake.top", "fake.extra", 6, "function"),
        ("fake.extra", "fake.top", 1, "top"),
    }
    assert found.unassigned == ["fake.extra"]
    assert {(e.source, e.target, e.kind) for e in found.upward} == {
        ("fake.low", "fake.mid", "function"), ("fake.side", "fake", "top"),
        ("fake.side", "fake.top", "TYPE_CHECKING")}
    # a pragma is no reason; a reason on the line or the line above is
    assert {(e.path.as_posix(), e.line) for e in found.unjustified} == {
        ("fake/low.py", 2), ("fake/top.py", 5), ("fake/top.py", 6)}
    assert [[e.source for e in c.cycle] for c in found.cycles] == [
        ["fake.extra", "fake.top"], ["fake.low", "fake.mid", "fake.mid.inner"]]
    assert len(found.cycles[1].edges) == 4  # both imports of low by inner are named
    report = found.report()
    assert report.startswith("1 module(s) in no layer")
    assert "cycle: fake.low -> fake.mid -> fake.mid.inner -> fake.low" in report
    assert "fake.mid.inner -> fake.low  at fake/mid/inner.py:2" in report
    assert "fake.low (layer 0) -> fake.mid (layer 1)  at fake/low.py:2 (function)" in report
    assert "fake.side (layer 0) -> fake (layer face)  at fake/side.py:2" in report
    assert "fake/top.py:6  from fake import extra" in report


def test_a_clean_package_passes(tmp_path):
    root = tmp_path / "clean"
    (root / "sub").mkdir(parents=True)
    (root / "__init__.py").write_text("from clean.sub import x\n")
    (root / "base.py").write_text("X = 1\n")
    (root / "sub" / "__init__.py").write_text("from .x import Y\n")
    (root / "sub" / "x.py").write_text(
        "from clean.base import X\nY = X\ndef f():\n    import clingo  # optional dependency\n")
    found = check_package(root, "clean", {"base": 0, "sub": 1})
    assert not (found.cycles or found.upward or found.unjustified or found.unassigned)
    assert found.report() == ""
    assert len(found.edges) == 3
