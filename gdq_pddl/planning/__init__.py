"""Planners: one result type, backends found through the ``gdq_pddl.planners`` entry points
(any class with the :class:`~gdq_pddl.planning.base.Planner` interface, imported only when
asked for)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache
from importlib.metadata import EntryPoint, entry_points

from gdq_pddl.errors import PlanningError
from gdq_pddl.planning.base import Plan, Planner, PlanningProblem, PlanResult, State, Status
from gdq_pddl.planning.checked import CheckedPlanner, one_line

GROUP = "gdq_pddl.planners"
DEFAULT = "graph"
BUILT_IN = ("graph", "pyperplan", "clingo")
"""Names only this package may register: another distribution cannot replace them."""
OWN = "gdq-pddl"
"""This package's distribution name, normalised (:func:`_dist_name`)."""

__all__ = ["BUILT_IN", "DEFAULT", "GROUP", "CheckedPlanner", "Plan", "PlanResult", "Planner",
           "PlannerInfo", "PlanningProblem", "State", "Status", "get_planner",
           "planner_names", "planners"]


def _dist_name(ep: EntryPoint) -> str:
    """The normalised name of the distribution that registers ``ep`` (``?`` if unknown)."""
    dist = getattr(ep, "dist", None)
    name = getattr(dist, "name", None) if dist is not None else None
    return re.sub(r"[-_.]+", "-", name).lower() if isinstance(name, str) else "?"


def _registered() -> dict[str, list[EntryPoint]]:
    """Every name of the group and the entry points that register it, one per
    distribution (the first found of each, as Python's import path orders them)."""
    out: dict[str, list[EntryPoint]] = {}
    for ep in entry_points(group=GROUP):
        eps = out.setdefault(ep.name, [])
        dist = _dist_name(ep)
        if dist == "?" or dist not in {_dist_name(e) for e in eps}:
            eps.append(ep)
    return out


def _refusal(name: str, eps: list[EntryPoint]) -> str | None:
    """Why the name ``name``, registered by ``eps``, cannot be used: registered by two
    distributions, or a built-in name registered by another; None when it can."""
    dists = [_dist_name(ep) for ep in eps]
    others = [d for d in dists if d != OWN]
    if name in BUILT_IN and others:
        return (f"the built-in planner name {name!r} is also registered in {GROUP} by the "
                f"distribution {others[0]} ({eps[dists.index(others[0])].value}); a built-in "
                f"planner cannot be replaced: uninstall {others[0]} or have it register "
                "another name")
    if len(eps) > 1:
        return (f"the planner name {name!r} is registered in {GROUP} by two distributions, "
                f"{dists[0]} ({eps[0].value}) and {dists[1]} ({eps[1].value}); uninstall "
                "one of them")
    return None


def planner_names() -> list[str]:
    """Names of every registered backend, usable or not."""
    return sorted(_registered())


@dataclass(frozen=True)
class PlannerInfo:
    """A registered backend: whether it can run here, and why not."""

    name: str
    usable: bool
    reason: str
    target: str


def _load(name: str, eps: list[EntryPoint]) -> type:
    """The backend class registered as ``name``, or :class:`PlanningError` saying why it
    cannot be used (refused registration, import failure, an ``unusable_reason``)."""
    refusal = _refusal(name, eps)
    if refusal is not None:
        raise PlanningError(f"planner {name!r} is refused: {refusal}")
    ep = eps[0]
    try:
        cls = ep.load()
    except Exception as exc:
        raise PlanningError(f"planner {name!r} cannot be loaded from {ep.value}: "
                            f"{one_line(exc)}") from None
    try:
        reason = cls.unusable_reason()
    except Exception as exc:  # a plugin's bug, said in one line
        raise PlanningError(f"planner {name!r}: unusable_reason() of {ep.value} failed: "
                            f"{one_line(exc)}") from None
    if reason is not None and not isinstance(reason, str):
        raise PlanningError(f"planner {name!r}: unusable_reason() of {ep.value} returned "
                            f"{type(reason).__name__}, not a message or None")
    if reason is not None:
        raise PlanningError(f"planner {name!r} is not usable here: {reason}")
    return cls


def planners() -> list[PlannerInfo]:
    """Every registered backend with its status (loading each one to ask)."""
    out = []
    for name, eps in sorted(_registered().items()):
        try:  # a broken plugin must not break the listing
            _load(name, eps)
            reason = None
        except PlanningError as exc:
            reason = str(exc).removeprefix(f"planner {name!r} is not usable here: ")
        out.append(PlannerInfo(name, reason is None, reason or "", eps[0].value))
    return out


@cache
def get_planner(name: str = DEFAULT) -> CheckedPlanner:
    """Load and instantiate the backend ``name``, wrapped so that every answer it gives is
    checked (:class:`~gdq_pddl.planning.checked.CheckedPlanner`); raise
    :class:`PlanningError` if it is unknown, refused (a name two distributions register, or
    a built-in name another registers), unusable or broken."""
    registered = _registered()
    if name not in registered:
        raise PlanningError(f"unknown planner {name!r} (known: {', '.join(sorted(registered))})")
    cls = _load(name, registered[name])
    try:
        backend = cls()
    except Exception as exc:
        raise PlanningError(f"planner {name!r} cannot be created: {one_line(exc)}") from None
    return CheckedPlanner(name, backend)
