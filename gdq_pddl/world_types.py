"""A world as data: its door, task and world types (:class:`World` with its reality,
:meth:`World.dynamics`, and its reachability) and the PDDL problem it generates for
``domains/office.pddl`` (:func:`office_problem`). :mod:`gdq_pddl.world` reads and checks
the world file that makes one.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property

from gdq_pddl.dynamics import CostDist, Dynamics, Outcomes
from gdq_pddl.errors import WorldError

DOOR_VERBS = ("opendoor", "gothrough")
"""The verbs aimed at a door, whose outcomes and costs a door may set."""


@dataclass(frozen=True)
class Door:
    """A door between two positions (its sides) with its dynamics."""

    name: str
    sides: tuple[str, str]
    success: float
    stuck: float
    label: str = ""
    costs: Mapping[str, CostDist] = field(default_factory=dict)  # opendoor, gothrough


@dataclass(frozen=True)
class Task:
    """A navigation task: reach ``goal`` from ``start`` (both position names)."""

    name: str
    start: str
    goal: str
    irrelevant_areas: tuple[int, ...] = ()  # as the paper calls them


@dataclass(frozen=True)
class World:
    """A validated world. Build one with :func:`~gdq_pddl.world.load_world`."""

    name: str
    source: str
    positions: tuple[str, ...]
    edges: tuple[tuple[str, str], ...]
    doors: tuple[Door, ...]
    areas: Mapping[int, tuple[str, ...]]
    landmarks: Mapping[str, str]
    tasks: Mapping[str, Task]
    costs: Mapping[str, CostDist]
    step_limit: int = 20
    r_max: float = 20.0
    navigation_success: float = 0.95
    description: str = ""

    @cached_property
    def index(self) -> dict[str, int]:
        """Position name -> index in :attr:`positions`."""
        return {p: i for i, p in enumerate(self.positions)}

    @cached_property
    def door_at(self) -> dict[str, Door]:
        """Door-side position -> its door (open-floor positions are absent)."""
        return {side: d for d in self.doors for side in d.sides}

    @cached_property
    def door_edges(self) -> frozenset[frozenset[str]]:
        """The edges crossed only by ``gothrough``: the two sides of each door."""
        return frozenset(frozenset(d.sides) for d in self.doors)

    @cached_property
    def walk_neighbours(self) -> dict[str, tuple[str, ...]]:
        """Neighbours reachable on foot (every edge but a door's own), sorted by index."""
        out: dict[str, list[str]] = {p: [] for p in self.positions}
        for a, b in self.edges:
            if frozenset((a, b)) not in self.door_edges:
                out[a].append(b)
                out[b].append(a)
        return {p: tuple(sorted(ns, key=self.index.__getitem__)) for p, ns in out.items()}

    @cached_property
    def area_of(self) -> dict[str, int]:
        """Position -> area number (positions in no area are absent)."""
        return {p: a for a, ps in self.areas.items() for p in ps}

    def cost(self, verb: str, position: str) -> CostDist:
        """Cost distribution of ``verb`` aimed at ``position`` (door overrides first)."""
        door = self.door_at.get(position)
        if door is not None and verb in door.costs:
            return door.costs[verb]
        return self.costs[verb]

    def dynamics(self) -> Dynamics:
        """The world's reality for ``domains/office.pddl``: ``goto`` and ``approach`` work
        with ``navigation_success``, else slip; ``opendoor`` and ``gothrough`` work with
        their door's ``success``, get stuck with its ``stuck``, else do nothing."""
        nav = Outcomes(self.navigation_success, 0.0, ("goto", "approach"))
        actions = {v: replace(nav, cost=self.costs[v]) for v in ("goto", "approach")}
        actions |= {v: Outcomes(cost=self.costs[v]) for v in DOOR_VERBS}
        objects = {v: {d.name: Outcomes(d.success, d.stuck, "nothing",
                                        d.costs.get(v, self.costs[v])) for d in self.doors}
                   for v in DOOR_VERBS}
        return Dynamics(self.source, self.r_max, self.step_limit, actions, objects,
                        self.name, self.description, frozenset({"r_max", "step_limit"}))

    def position(self, name: str) -> str:
        """Resolve a position or landmark name; raise :class:`WorldError` if unknown."""
        if not isinstance(name, str):
            raise WorldError(self.source, "", f"a position is named by a string, got {name!r}")
        if name in self.index:
            return name
        if self.landmarks.get(name) in self.index:
            return self.landmarks[name]
        known = ", ".join(self.positions)
        raise WorldError(self.source, "", f"unknown position {name!r} (known: {known}; "
                         f"landmarks: {', '.join(self.landmarks) or 'none'})")

    def task(self, name: str) -> Task:
        """Return the named task; raise :class:`WorldError` listing the known ones."""
        if not isinstance(name, str):
            raise WorldError(self.source, "", f"a task is named by a string (known: "
                             f"{', '.join(self.tasks)}), got {name!r}")
        try:
            return self.tasks[name.upper()]
        except KeyError:
            raise WorldError(self.source, "", f"unknown task {name!r} "
                             f"(known: {', '.join(self.tasks)})") from None

    def resolve(self, task: str | None = None, start: str | None = None,
                goal: str | None = None) -> Task:
        """A task by name, or an ad-hoc one from ``start``/``goal`` names (refused when
        they are the same position or the goal is out of reach)."""
        if task is not None:
            if start is not None or goal is not None:
                raise WorldError(self.source, "", "give a task or a start and goal, not both")
            return self.task(task)
        if start is None or goal is None:
            given = "a start but no goal" if start is not None else \
                "a goal but no start" if goal is not None else "no task"
            raise WorldError(self.source, "", f"{given}: give a task, or both a start and a "
                             "goal")
        s, g = self.position(start), self.position(goal)
        if s == g:
            raise WorldError(self.source, "", f"start and goal are the same position ({s}); "
                             "the episode would be over before it begins")
        why = self.unreachable(s, g)
        if why:
            raise WorldError(self.source, "", f"goal {g} cannot be reached from {s}: {why}")
        return Task(name=f"{s}-{g}", start=s, goal=g)

    def reachable(self, start: str) -> set[str]:
        """The positions reachable from ``start`` (through doors with ``success > 0``)."""
        links: dict[str, list[str]] = {p: list(ns) for p, ns in self.walk_neighbours.items()}
        for d in self.doors:
            if d.success > 0:
                a, b = d.sides
                links[a].append(b)
                links[b].append(a)
        return component(start, links)

    def unreachable(self, start: str, goal: str) -> str:
        """Why ``goal`` cannot be reached from ``start`` ("" when it can)."""
        if goal in self.reachable(start):
            return ""
        locked = sorted(d.name for d in self.doors if d.success <= 0)
        return ("every way there crosses a door that never opens (success = 0: "
                f"{', '.join(locked)})" if locked else "no way leads there")


def office_problem(world: World, task: Task, locked_is_wall: bool = True) -> str:
    """The world's knowledge as a problem of ``domains/office.pddl``, every door closed; a
    locked door (success 0) is a wall (no ``connects``) unless ``locked_is_wall`` is False."""
    door_sides = {p for d in world.doors for p in d.sides}
    walk = sorted((a, b) for p, ns in world.walk_neighbours.items() for a, b in
                  ((p, n) for n in ns))
    order = world.index.__getitem__
    lines = [
        f"; Generated by `gdq-pddl problem` from {world.name} ({world.description or 'world'}).",
        f"; Task {task.name}: {task.start} -> {task.goal}. Do not edit: regenerate instead.",
        f"(define (problem {world.name}-{task.name.lower()})",
        "  (:domain office)",
        "  (:objects",
        "    " + " ".join(world.positions) + " - position",
        "    " + " ".join(d.name for d in world.doors) + " - door)" if world.doors
        else "    )",
        "  (:init",
        f"    (at {task.start})",
    ]
    lines += [f"    (floor {p})" for p in world.positions if p not in door_sides]
    for a, b in sorted(walk, key=lambda e: (order(e[0]), order(e[1]))):
        lines.append(f"    (walkway {a} {b})")
    for d in world.doors:
        a, b = d.sides
        lines += [f"    (door-side {a} {d.name})", f"    (door-side {b} {d.name})"]
        if d.success > 0 or not locked_is_wall:  # knowledge: a locked door is a wall
            lines += [f"    (connects {d.name} {a} {b})", f"    (connects {d.name} {b} {a})"]
        lines.append(f"    (closed {d.name})")
    lines[-1] += ")"
    lines += [f"  (:goal (at {task.goal})))", ""]
    return "\n".join(lines)


def component(start: str, links: Mapping[str, Iterable[str]]) -> set[str]:
    """The nodes reachable from ``start`` over ``links`` (breadth first)."""
    seen, queue = {start}, deque([start])
    while queue:
        for n in links[queue.popleft()]:
            if n not in seen:
                seen.add(n)
                queue.append(n)
    return seen
