"""Errors a user can act on. Each says which file, where in it, and what was expected.

The command line prints these as one message and exits non-zero; they never carry a
traceback from inside a dependency.
"""

from __future__ import annotations


class GdqError(Exception):
    """Base class of every error this package raises on purpose."""


class WorldError(GdqError):
    """A world file is malformed or inconsistent."""

    def __init__(self, source: str, key: str, message: str) -> None:
        self.source, self.key = source, key
        where = f"{source}: {key}: " if key else f"{source}: "
        super().__init__(where + message)


class PDDLError(GdqError):
    """A PDDL file cannot be parsed, or a problem does not match its domain."""

    def __init__(self, source: str, line: int | None, message: str) -> None:
        self.source, self.line = source, line
        where = f"{source}:{line}: " if line is not None else f"{source}: "
        super().__init__(where + message)


class PlanningError(GdqError):
    """A planner cannot be found, loaded or run."""


class AbstractionError(GdqError):
    """A planner state or action has no counterpart in the learner's spaces."""
