"""Planners: one result type, backends found through the ``gdq_pddl.planners`` entry points
(any class with the :class:`~gdq_pddl.planning.base.Planner` interface, imported only when
asked for)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from importlib.metadata import EntryPoint, entry_points

from gdq_pddl.errors import PlanningError
from gdq_pddl.planning.base import Plan, Planner, PlanningProblem, PlanResult, State, Status

GROUP = "gdq_pddl.planners"
DEFAULT = "graph"

__all__ = ["DEFAULT", "GROUP", "Plan", "PlanResult", "Planner", "PlannerInfo",
           "PlanningProblem", "State", "Status", "get_planner", "planner_names", "planners"]


def _entry_points() -> dict[str, EntryPoint]:
    return {ep.name: ep for ep in entry_points(group=GROUP)}


def planner_names() -> list[str]:
    """Names of every registered backend, usable or not."""
    return sorted(_entry_points())


@dataclass(frozen=True)
class PlannerInfo:
    """A registered backend: whether it can run here, and why not."""

    name: str
    usable: bool
    reason: str
    target: str


def planners() -> list[PlannerInfo]:
    """Every registered backend with its status (loading each one to ask)."""
    out = []
    for name, ep in sorted(_entry_points().items()):
        try:
            cls = ep.load()
            reason = cls.unusable_reason()
        except Exception as exc:  # a broken plugin must not break the listing
            reason = f"cannot be loaded: {type(exc).__name__}: {exc}"
        out.append(PlannerInfo(name, reason is None, reason or "", ep.value))
    return out


@cache
def get_planner(name: str = DEFAULT) -> Planner:
    """Load and instantiate the backend ``name``; raise :class:`PlanningError` if unusable."""
    eps = _entry_points()
    if name not in eps:
        raise PlanningError(f"unknown planner {name!r} (known: {', '.join(sorted(eps))})")
    try:
        cls = eps[name].load()
    except Exception as exc:
        raise PlanningError(f"planner {name!r} cannot be loaded from {eps[name].value}: "
                            f"{type(exc).__name__}: {exc}") from None
    reason = cls.unusable_reason()
    if reason is not None:
        raise PlanningError(f"planner {name!r} is not usable here: {reason}")
    return cls()
