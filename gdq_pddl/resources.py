"""Files that ship inside the package: PDDL domains and problems, world files.

Everything is found with :mod:`importlib.resources`, so the package works the same from
a wheel, a zip or a source install, whatever the working directory.
"""

from __future__ import annotations

from importlib.resources import files
from importlib.resources.abc import Traversable


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
