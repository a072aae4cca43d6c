"""Files that ship inside the package (found with :mod:`importlib.resources`) and the
names that find them: a file's name without folder or suffix (domain ``keys`` is
``domains/keys.pddl``; a world name is a dynamics name too). :func:`resolve` is the one
rule: a value with a folder or a suffix, or naming an existing file, is a path (a file of
yours wins); any other is a shipped name, an unknown one an error listing them.
"""

from __future__ import annotations

import os
import re
from importlib.resources import files
from importlib.resources.abc import Traversable
from pathlib import Path

from gdq_pddl.errors import ConfigError, PDDLError, PlanningError
from gdq_pddl.inputs import read_text


def data_file(*parts: str) -> Traversable:
    """Return the shipped file ``gdq_pddl/data/<parts...>`` (it may not exist)."""
    node = files("gdq_pddl") / "data"
    for part in parts:
        node = node / part
    return node


def domain_text(name: str = "office") -> str:
    """Return the text of the shipped PDDL domain ``domains/<name>.pddl``."""
    return data_file("domains", f"{name}.pddl").read_text(encoding="utf-8")


def problem_text(task: str) -> str:
    """Return the text of the shipped PDDL problem for ``task`` (``problems/task-<x>.pddl``)."""
    return data_file("problems", f"task-{task.lower()}.pddl").read_text(encoding="utf-8")


def world_text(name: str = "office") -> str:
    """Return the text of the shipped world file ``<name>.toml``."""
    return data_file(f"{name}.toml").read_text(encoding="utf-8")


SHIPPED = {"domain": (("domains",), ".pddl"), "problem": (("problems",), ".pddl"),
           "dynamics": (("dynamics", ""), ".toml"), "world": (("",), ".toml")}
"""Per kind of file: the folders under ``gdq_pddl/data/`` that hold it, and its suffix."""


def _shipped_files(kind: str) -> dict[str, Traversable]:
    folders, suffix = SHIPPED[kind]
    return {f.name.removesuffix(suffix): f for folder in folders
            for f in (data_file(folder) if folder else data_file()).iterdir()
            if f.name.endswith(suffix)}


def shipped_names(kind: str) -> list[str]:
    """The sorted names of the shipped files of ``kind`` (a key of :data:`SHIPPED`)."""
    return sorted(_shipped_files(kind))


def is_shipped_name(value: str | Path) -> bool:
    """Whether ``value`` is read as a shipped name, not a path (see the module docstring)."""
    path = Path(value)
    return (isinstance(value, str) and not path.suffix and path.name == value
            and not path.is_file())


def check_name_or_path(kind: str, value: object, also: str = "") -> None:
    """Refuse (:class:`ConfigError`, naming ``kind``) a ``value`` that is neither a string
    nor a path: ``domain=123`` is a type error of the caller's, said in one line (``also``:
    what else the caller takes, as ", or a World")."""
    if not isinstance(value, (str, os.PathLike)) or \
            not isinstance(os.fspath(value), str):
        raise ConfigError(f"{kind}={value!r}: expected the name of a shipped {kind} or a "
                          f"file's path (a str or an os.PathLike){also}, got "
                          f"{type(value).__name__}")


def resolve(kind: str, value: str | Path) -> Path:
    """The file ``value`` means for ``kind`` (PlanningError for an unknown name)."""
    check_name_or_path(kind, value)
    if not is_shipped_name(value):
        return Path(value)
    found = _shipped_files(kind).get(str(value))
    if found is None:
        raise PlanningError(f"{kind} {str(value)!r}: no such file, and no shipped {kind} of "
                            f"that name (shipped: {', '.join(shipped_names(kind))})")
    return Path(str(found))


def resolve_pddl(domain: str | Path, problem: str | Path, dynamics: str | Path | None
                 ) -> tuple[Path, Path, Path | None]:
    """:func:`resolve` a domain, a problem and a dynamics file; a shipped domain without
    ``dynamics`` gets the shipped dynamics of its name when there is one."""
    for kind, value in (("domain", domain), ("problem", problem), ("dynamics", dynamics)):
        if value is not None or kind != "dynamics":
            check_name_or_path(kind, value)
    if dynamics is None and is_shipped_name(domain) and str(domain) in _shipped_files(
            "dynamics"):
        dynamics = str(domain)
    return (resolve("domain", domain), resolve("problem", problem),
            None if dynamics is None else resolve("dynamics", dynamics))


def problem_domain(problem: Path) -> str:
    """The domain a PDDL problem file names in its ``(:domain X)`` ("" if none), or the
    file itself when it defines its domain too (IPPC-2008's files)."""
    text = read_text(problem, lambda src, msg: PDDLError(src, None, msg))
    if re.search(r"\(\s*define\s*\(\s*domain\s", text, re.IGNORECASE):
        return str(problem)
    found = re.search(r"\(:domain\s+([^\s()]+)", text, re.IGNORECASE)
    return found.group(1) if found else ""
