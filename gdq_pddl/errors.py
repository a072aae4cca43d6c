"""Errors a user can act on: each says which file, where in it, and what was expected."""

from __future__ import annotations


class GdqError(Exception):
    """Base class of every error this package raises on purpose."""


class WorldError(GdqError):
    """A world file is malformed or inconsistent."""

    def __init__(self, source: str, key: str, message: str) -> None:
        self.source, self.key, self.message = source, key, message
        where = f"{source}: {key}: " if key else f"{source}: "
        super().__init__(where + message)

    def __reduce__(self):  # raised in a worker process, it travels back pickled
        return type(self), (self.source, self.key, self.message)


class PDDLError(GdqError):
    """A PDDL file cannot be parsed, or a problem does not match its domain."""

    def __init__(self, source: str, line: int | None, message: str) -> None:
        self.source, self.line, self.message = source, line, message
        where = f"{source}:{line}: " if line is not None else f"{source}: "
        super().__init__(where + message)

    def __reduce__(self):
        return type(self), (self.source, self.line, self.message)


class PlanningError(GdqError):
    """A planner cannot be found, loaded or run."""


class TooManyStates(PlanningError):
    """The reachable states of a problem do not fit the table budget: it can be explored
    online instead (``gdq-pddl run --explore``)."""


class AbstractionError(GdqError):
    """A planner state or action has no counterpart in the learner's spaces."""


class ConfigError(GdqError, ValueError):
    """A parameter (a command-line option, an argument of the API) is out of range."""


class ResultsError(GdqError):
    """An output folder, or a file in it, cannot be used as asked (damaged, held by
    another process, of another configuration)."""


class OutputError(GdqError):
    """An output file or folder cannot be written where asked."""


class SizeError(GdqError, MemoryError):
    """A computation would need more memory than the machine has (said up front)."""
