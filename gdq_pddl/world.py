"""The world file (TOML, ``gdq_pddl/data/office.toml`` annotated): an office building as
data. :func:`load_world` validates it, naming the file and key of every error, into a
:class:`~gdq_pddl.world_types.World`; its knowledge is ``domains/office.pddl`` with
:func:`~gdq_pddl.world_types.office_problem`, its reality :meth:`World.dynamics
<gdq_pddl.world_types.World.dynamics>`. The types and ``office_problem`` live in
:mod:`gdq_pddl.world_types` and are importable from here too.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from gdq_pddl.dynamics import Checks, CostDist, read_toml
from gdq_pddl.errors import WorldError
from gdq_pddl.inputs import read_text
from gdq_pddl.resources import check_name_or_path, is_shipped_name, resolve, world_text
from gdq_pddl.spaces import VERBS
from gdq_pddl.world_types import DOOR_VERBS, Door, Task, World, component, office_problem

__all__ = ["DEFAULT_TASK", "DOOR_VERBS", "KEYS", "LABEL", "PDDL_NAME", "Door", "Task", "World",
           "as_world", "builtin_world", "load_world", "office_problem", "parse_world",
           "pick_task"]


KEYS: dict[str, tuple[str, ...]] = {
    "": ("world", "costs", "doors", "areas", "landmarks", "tasks"),
    "world": ("name", "description", "step_limit", "r_max", "navigation_success",
              "positions", "adjacency", "forbidden_areas"),
    "door": ("sides", "success", "stuck", "label", "cost"),
    "task": ("start", "goal", "irrelevant_areas"),
}
"""The keys each table of a world file may have."""

PDDL_NAME = re.compile(r"[a-z][a-z0-9_-]*")
"""A position or door name: a PDDL object, lower case (PDDL ignores case)."""

LABEL = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*")
"""A world or task name (it goes into PDDL problem names, file names and CSV columns)."""


def load_world(path: str | Path | None = None) -> World:
    """Load and validate a world file (``None``: the shipped office)."""
    if path is None:
        return builtin_world("office")
    path = Path(path)
    return parse_world(read_text(path, lambda src, msg: WorldError(src, "", msg)),
                       source=str(path))


def builtin_world(name: str) -> World:
    """Load a world file shipped with the package (``office`` or ``office_robot``)."""
    return parse_world(world_text(name), source=f"{name}.toml (built in)")


DEFAULT_TASK = "C"


def as_world(world: str | Path | World | None) -> World:
    """A :class:`World` from a world, a file path, a shipped name, or ``None`` (office)."""
    if world is None:
        return load_world(None)
    if isinstance(world, World):
        return world
    check_name_or_path("world", world, ", or a World")
    if is_shipped_name(world):
        resolve("world", world)  # an unknown name: the error listing the shipped ones
        return builtin_world(str(world))
    return load_world(world)


def pick_task(world: World, task: str | None, start: str | None, goal: str | None) -> Task:
    """The task to run (:meth:`World.resolve`), by default ``C`` or the world's first."""
    if task is None and start is None and goal is None:
        task = next(iter(world.tasks)) if world.tasks and DEFAULT_TASK not in world.tasks \
            else DEFAULT_TASK
    return world.resolve(task=task, start=start, goal=goal)


def parse_world(text: str, source: str = "<string>") -> World:
    """Validate the TOML ``text`` of a world file; ``source`` names it in errors."""
    return _WorldChecks(source, read_toml(text, source)).world()


class _WorldChecks(Checks):
    """The world file's own checks on top of :class:`~gdq_pddl.dynamics.Checks`."""

    def pos(self, name: Any, path: str) -> str:
        if not isinstance(name, str) or name not in self.position_set:
            raise self.fail(path, f"unknown position {name!r}")
        return name

    def name(self, value: Any, path: str, pattern: re.Pattern, what: str) -> str:
        if not isinstance(value, str) or not pattern.fullmatch(value):
            raise self.fail(path, f"expected {what}, got {value!r}")
        return value

    def world(self) -> World:
        self.known_keys(self.raw, "", KEYS[""], "table")
        w = self.get(self.raw, "world", "world", dict)
        self.known_keys(w, "world", KEYS["world"])
        names = self.get(w, "positions", "world.positions", list)
        for i, p in enumerate(names):
            self.name(p, f"world.positions[{i}]", PDDL_NAME,
                      "a position name (lower case letters, digits, - and _, from a letter)")
        if len(set(names)) < len(names):
            dup = sorted({p for p in names if names.count(p) > 1})
            raise self.fail("world.positions", f"duplicate positions {dup}")
        if not names:
            raise self.fail("world.positions", "need at least one position")
        self.positions = tuple(names)
        self.position_set = frozenset(names)
        forbidden = self.forbidden_positions(w)
        edges = self.edges(w, forbidden)
        doors = self.doors(edges, forbidden)
        areas = self.areas(forbidden)
        landmarks = self.landmarks()
        kept = tuple(p for p in self.positions if p not in forbidden)
        self.connected(kept, edges)
        world = World(
            name=self.name(self.get(w, "name", "world.name", str, "world"), "world.name", LABEL,
                           "a name of letters, digits, - and _"),
            source=self.source, positions=kept, edges=edges, doors=doors, areas=areas,
            landmarks=landmarks, tasks={}, costs=self.costs(),
            step_limit=self.count(w, "step_limit", "world.step_limit", 20),
            r_max=self.positive(w, "r_max", "world.r_max", 20.0),
            navigation_success=self.probability(w, "navigation_success",
                                                "world.navigation_success")
            if "navigation_success" in w else 0.95,
            description=self.get(w, "description", "world.description", str, ""))
        object.__setattr__(world, "tasks", self.tasks(world, forbidden))
        return world

    def connected(self, kept: tuple[str, ...], edges: tuple) -> None:
        """Refuse positions no adjacency links to the rest (a forgotten edge)."""
        links: dict[str, list[str]] = {p: [] for p in kept}
        for a, b in edges:
            links[a].append(b)
            links[b].append(a)
        order = {p: i for i, p in enumerate(kept)}
        parts, left = [], set(kept)
        while left:
            part = component(min(left, key=order.__getitem__), links)
            parts.append(sorted(part, key=order.__getitem__))
            left -= part
        if len(parts) > 1:
            parts.sort(key=len)
            cut = ", ".join(" ".join(p) for p in parts[:-1])
            raise self.fail("world.adjacency", f"position(s) {cut} cut off from the rest of "
                            f"the world (no adjacency links them to {parts[-1][0]}); add the "
                            "missing edge or remove them")

    def forbidden_positions(self, w: Mapping[str, Any]) -> frozenset[str]:
        areas = self.get(self.raw, "areas", "areas", dict, {})
        out: set[str] = set()
        for i, a in enumerate(self.get(w, "forbidden_areas", "world.forbidden_areas", list, [])):
            members = areas.get(str(a)) if isinstance(a, int) and not isinstance(a, bool) \
                else None
            if not isinstance(members, list):
                raise self.fail(f"world.forbidden_areas[{i}]", f"unknown area {a!r}")
            out.update(p for p in members if isinstance(p, str))
        return frozenset(out)

    def edges(self, w: Mapping[str, Any], forbidden: frozenset[str]) -> tuple:
        out, seen = [], set()
        for i, e in enumerate(self.get(w, "adjacency", "world.adjacency", list)):
            key = f"world.adjacency[{i}]"
            if not isinstance(e, list) or len(e) != 2:
                raise self.fail(key, f"expected a pair of positions, got {e!r}")
            a, b = self.pos(e[0], key), self.pos(e[1], key)
            if a == b:
                raise self.fail(key, f"a position cannot be adjacent to itself ({a})")
            if frozenset((a, b)) in seen:
                raise self.fail(key, f"duplicate edge {a}-{b}")
            seen.add(frozenset((a, b)))
            if a not in forbidden and b not in forbidden:
                out.append((a, b))
        return tuple(out)

    def doors(self, edges: tuple, forbidden: frozenset[str]) -> tuple[Door, ...]:
        table = self.get(self.raw, "doors", "doors", dict, {})
        edge_set = {frozenset(e) for e in edges}
        out, used = [], {}
        for name, d in table.items():
            key = f"doors.{name}"
            self.name(name, key, PDDL_NAME, "a door name (lower case letters, digits, - and "
                      "_, from a letter)")
            if name in self.position_set:
                raise self.fail(key, f"{name} is a position's name; a door needs its own")
            if not isinstance(d, dict):
                raise self.fail(key, f"expected a table, got {d!r}")
            self.known_keys(d, key, KEYS["door"])
            sides = self.get(d, "sides", f"{key}.sides", list)
            if len(sides) != 2 or sides[0] == sides[1]:
                raise self.fail(f"{key}.sides",
                                f"a door needs exactly two distinct sides, got {sides!r}")
            a, b = (self.pos(s, f"{key}.sides") for s in sides)
            for s in (a, b):
                if s in used:
                    raise self.fail(f"{key}.sides", f"{s} is already a side of {used[s]}")
                used[s] = name
            success = self.probability(d, "success", f"{key}.success")
            stuck = self.probability(d, "stuck", f"{key}.stuck") if "stuck" in d else 0.0
            if success + stuck > 1.0 + 1e-12:
                raise self.fail(key, f"success + stuck must be <= 1, got {success} + {stuck}")
            costs = {}
            for verb, value in self.get(d, "cost", f"{key}.cost", dict, {}).items():
                if verb not in DOOR_VERBS:
                    raise self.fail(f"{key}.cost.{verb}",
                                    f"expected one of {', '.join(DOOR_VERBS)}")
                costs[verb] = self.cost(value, f"{key}.cost.{verb}")
            label = self.get(d, "label", f"{key}.label", str, "")
            if a in forbidden or b in forbidden:
                continue
            if frozenset((a, b)) not in edge_set:
                raise self.fail(f"{key}.sides", f"{a} and {b} are not adjacent")
            out.append(Door(name, (a, b), success, stuck, label, costs))
        return tuple(out)

    def areas(self, forbidden: frozenset[str]) -> dict[int, tuple[str, ...]]:
        out: dict[int, tuple[str, ...]] = {}
        owner: dict[str, str] = {}
        for name, members in self.get(self.raw, "areas", "areas", dict, {}).items():
            key = f"areas.{name}"
            if not re.fullmatch(r"[1-9][0-9]*", name):
                raise self.fail(key, "area names must be whole numbers from 1 (no leading 0)")
            number = int(name)
            if number > len(self.positions):
                raise self.fail(key, f"area numbers run from 1 to {len(self.positions)} (the "
                                "number of positions; each area is a column of the "
                                "per-episode area counts)")
            if not isinstance(members, list):
                raise self.fail(key, f"expected a list of positions, got {members!r}")
            for p in members:
                self.pos(p, key)
                if p in owner:
                    raise self.fail(key, f"{p} is already in area {owner[p]}")
                owner[p] = name
            out[number] = tuple(p for p in members if p not in forbidden)
        return out

    def landmarks(self) -> dict[str, str]:
        table = self.get(self.raw, "landmarks", "landmarks", dict, {})
        for k in table:
            if k in self.position_set:
                raise self.fail(f"landmarks.{k}", f"{k} is a position's name; a landmark "
                                "needs its own")
        return {k: self.pos(v, f"landmarks.{k}") for k, v in table.items()}

    def costs(self) -> dict[str, CostDist]:
        table = self.get(self.raw, "costs", "costs", dict, {})
        self.known_keys(table, "costs", VERBS, "verb")
        return {v: self.cost(table.get(v, 1.0), f"costs.{v}") for v in VERBS}

    def tasks(self, world: World, forbidden: frozenset[str]) -> dict[str, Task]:
        out: dict[str, Task] = {}
        for name, t in self.get(self.raw, "tasks", "tasks", dict, {}).items():
            key = f"tasks.{name}"
            self.name(name, key, LABEL, "a task name of letters, digits, - and _")
            if name.upper() in out:
                raise self.fail(key, f"task names ignore case: {name} is task "
                                f"{name.upper()} again")
            if not isinstance(t, dict):
                raise self.fail(key, f"expected a table, got {t!r}")
            self.known_keys(t, key, KEYS["task"])
            ends = []
            for end in ("start", "goal"):
                value = self.get(t, end, f"{key}.{end}", str)
                p = world.landmarks.get(value, value)
                if p not in world.index:
                    why = "is in a forbidden area" if p in forbidden else "is not a position"
                    raise self.fail(f"{key}.{end}", f"{value!r} {why} (nor a landmark)")
                ends.append(p)
            if ends[0] == ends[1]:
                raise self.fail(key, f"start and goal are the same position ({ends[0]}); "
                                "every episode would be over before it begins")
            why = world.unreachable(*ends)
            if why:
                raise self.fail(f"{key}.goal", f"{ends[1]} cannot be reached from "
                                f"{ends[0]}: {why}")
            irr = self.get(t, "irrelevant_areas", f"{key}.irrelevant_areas", list, [])
            for a in irr:
                if not isinstance(a, int) or isinstance(a, bool) or a not in world.areas:
                    raise self.fail(f"{key}.irrelevant_areas", f"unknown area {a!r}")
            out[name.upper()] = Task(name.upper(), ends[0], ends[1], tuple(irr))
        return out
