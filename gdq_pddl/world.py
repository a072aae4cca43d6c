"""The world file: an office building as data (reality for the simulator).

A world file is TOML (see ``gdq_pddl/data/office.toml`` for the annotated original). It
lists positions, their undirected adjacency, doors (two sides each, a success and a
stuck probability, optional per-door costs), per-verb action costs, areas, landmarks and
tasks. :func:`load_world` validates all of it and names the file and the key on every
error, so a user editing a door never meets a traceback.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

from gdq_pddl.errors import WorldError
from gdq_pddl.resources import world_text

VERBS: tuple[str, ...] = ("goto", "approach", "opendoor", "gothrough", "stay")
"""The action verbs, in the order of the learner's action index (verb-major)."""

DOOR_VERBS = ("opendoor", "gothrough")

COST_KINDS = {"const": 0, "uniform": 1, "normal": 2}
"""Numeric codes of cost distributions, as the compiled simulator reads them."""


@dataclass(frozen=True)
class CostDist:
    """The cost of one action: a constant, ``uniform(a, b)`` or ``normal(a, b)`` clipped at 0."""

    kind: str = "const"
    a: float = 1.0
    b: float = 0.0

    @property
    def mean(self) -> float:
        """Expected cost (for the normal, of the unclipped distribution)."""
        return (self.a + self.b) / 2 if self.kind == "uniform" else self.a


@dataclass(frozen=True)
class Door:
    """A door between two positions (its sides) with its dynamics."""

    name: str
    sides: tuple[str, str]
    success: float
    stuck: float
    label: str = ""
    costs: Mapping[str, CostDist] = field(default_factory=dict)
    """Per-verb cost overrides for the door's own actions (opendoor, gothrough)."""


@dataclass(frozen=True)
class Task:
    """A navigation task: reach ``goal`` from ``start`` (both position names)."""

    name: str
    start: str
    goal: str
    irrelevant_areas: tuple[int, ...] = ()
    """Areas the paper calls irrelevant to this task (empty where it says nothing)."""


@dataclass(frozen=True)
class World:
    """A validated world. Build one with :func:`load_world`."""

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

    def position(self, name: str) -> str:
        """Resolve a position or landmark name; raise :class:`WorldError` if unknown."""
        if name in self.index:
            return name
        if name in self.landmarks:
            return self.landmarks[name]
        known = ", ".join(self.positions)
        raise WorldError(self.source, "", f"unknown position {name!r} (known: {known}; "
                         f"landmarks: {', '.join(self.landmarks) or 'none'})")

    def task(self, name: str) -> Task:
        """Return the named task; raise :class:`WorldError` listing the known ones."""
        try:
            return self.tasks[name.upper()]
        except KeyError:
            raise WorldError(self.source, "", f"unknown task {name!r} "
                             f"(known: {', '.join(self.tasks)})") from None

    def resolve(self, task: str | None = None, start: str | None = None,
                goal: str | None = None) -> Task:
        """A task by name, or an ad-hoc one from ``start``/``goal`` names."""
        if task is not None:
            if start is not None or goal is not None:
                raise WorldError(self.source, "", "give a task or a start and goal, not both")
            return self.task(task)
        if start is None or goal is None:
            raise WorldError(self.source, "", "give a task, or both a start and a goal")
        s, g = self.position(start), self.position(goal)
        return Task(name=f"{s}-{g}", start=s, goal=g)


def load_world(path: str | Path | None = None) -> World:
    """Load and validate a world file; ``None`` loads the shipped office.

    Raises :class:`WorldError` naming the file and key of the first problem found.
    """
    if path is None:
        return parse_world(world_text("office"), source="office.toml (built in)")
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise WorldError(str(path), "", f"cannot read: {exc.strerror}") from None
    return parse_world(text, source=str(path))


def builtin_world(name: str) -> World:
    """Load a world file shipped with the package (``office`` or ``office_robot``)."""
    return parse_world(world_text(name), source=f"{name}.toml (built in)")


def parse_world(text: str, source: str = "<string>") -> World:
    """Validate the TOML ``text`` of a world file; ``source`` names it in errors."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise WorldError(source, "", f"not valid TOML: {exc}") from None
    return _Validator(source, raw).world()


class _Validator:
    """Checks one parsed TOML document and builds the :class:`World`."""

    def __init__(self, source: str, raw: dict[str, Any]) -> None:
        self.source, self.raw = source, raw

    def fail(self, key: str, message: str) -> WorldError:
        return WorldError(self.source, key, message)

    def get(self, table: Mapping[str, Any], key: str, path: str, kind: type | tuple,
            default: Any = ...) -> Any:
        if key not in table:
            if default is ...:
                raise self.fail(path, "missing")
            return default
        value = table[key]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, kind) or isinstance(value, bool) and kind is not bool:
            names = (kind,) if isinstance(kind, type) else kind
            name = " or ".join(k.__name__ for k in names)
            raise self.fail(path, f"expected {name}, got {value!r}")
        return value

    def probability(self, table: Mapping[str, Any], key: str, path: str) -> float:
        value = self.get(table, key, path, float)
        if not 0.0 <= value <= 1.0:
            raise self.fail(path, f"a probability must be in [0, 1], got {value}")
        return value

    def pos(self, name: Any, path: str) -> str:
        if not isinstance(name, str) or name not in self.positions:
            raise self.fail(path, f"unknown position {name!r}")
        return name

    def cost(self, value: Any, path: str) -> CostDist:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            if value < 0:
                raise self.fail(path, f"a cost must be >= 0, got {value}")
            return CostDist("const", float(value))
        if not isinstance(value, dict):
            raise self.fail(path, f"expected a number or a table with 'dist', got {value!r}")
        dist = value.get("dist")
        if dist == "uniform":
            low = self.get(value, "low", f"{path}.low", float)
            high = self.get(value, "high", f"{path}.high", float)
            if not 0 <= low <= high:
                raise self.fail(path, f"need 0 <= low <= high, got low={low} high={high}")
            return CostDist("uniform", low, high)
        if dist == "normal":
            mean = self.get(value, "mean", f"{path}.mean", float)
            sd = self.get(value, "sd", f"{path}.sd", float)
            if sd < 0 or mean < 0:
                raise self.fail(path, f"need mean >= 0 and sd >= 0, got {mean}, {sd}")
            return CostDist("normal", mean, sd)
        raise self.fail(f"{path}.dist", f"expected 'uniform' or 'normal', got {dist!r}")

    def world(self) -> World:
        w = self.get(self.raw, "world", "world", dict)
        names = self.get(w, "positions", "world.positions", list)
        for i, p in enumerate(names):
            if not isinstance(p, str) or not p:
                raise self.fail(f"world.positions[{i}]", f"expected a name, got {p!r}")
        if len(set(names)) != len(names):
            dup = sorted({p for p in names if names.count(p) > 1})
            raise self.fail("world.positions", f"duplicate positions {dup}")
        self.positions = tuple(names)
        forbidden = self.forbidden_positions(w)
        edges = self.edges(w, forbidden)
        doors = self.doors(edges, forbidden)
        areas = self.areas(forbidden)
        landmarks = self.landmarks()
        kept = tuple(p for p in self.positions if p not in forbidden)
        world = World(
            name=self.get(w, "name", "world.name", str, "world"),
            source=self.source,
            positions=kept,
            edges=edges,
            doors=doors,
            areas=areas,
            landmarks=landmarks,
            tasks={},
            costs=self.costs(),
            step_limit=self.step_limit(w),
            r_max=self.get(w, "r_max", "world.r_max", float, 20.0),
            navigation_success=self.probability(w, "navigation_success",
                                                "world.navigation_success")
            if "navigation_success" in w else 0.95,
            description=self.get(w, "description", "world.description", str, ""),
        )
        object.__setattr__(world, "tasks", self.tasks(world, forbidden))
        return world

    def step_limit(self, w: Mapping[str, Any]) -> int:
        limit = self.get(w, "step_limit", "world.step_limit", int, 20)
        if limit < 1:
            raise self.fail("world.step_limit", f"must be >= 1, got {limit}")
        return limit

    def forbidden_positions(self, w: Mapping[str, Any]) -> frozenset[str]:
        areas = self.get(self.raw, "areas", "areas", dict, {})
        out: set[str] = set()
        for i, a in enumerate(self.get(w, "forbidden_areas", "world.forbidden_areas", list, [])):
            if str(a) not in areas:
                raise self.fail(f"world.forbidden_areas[{i}]", f"unknown area {a!r}")
            out.update(areas[str(a)])
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
            if not isinstance(d, dict):
                raise self.fail(key, f"expected a table, got {d!r}")
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
            if a in forbidden or b in forbidden:
                continue
            if frozenset((a, b)) not in edge_set:
                raise self.fail(f"{key}.sides", f"{a} and {b} are not adjacent")
            out.append(Door(name, (a, b), success, stuck,
                            self.get(d, "label", f"{key}.label", str, ""), costs))
        return tuple(out)

    def areas(self, forbidden: frozenset[str]) -> dict[int, tuple[str, ...]]:
        out: dict[int, tuple[str, ...]] = {}
        owner: dict[str, str] = {}
        for name, members in self.get(self.raw, "areas", "areas", dict, {}).items():
            key = f"areas.{name}"
            try:
                number = int(name)
            except ValueError:
                raise self.fail(key, "area names must be whole numbers") from None
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
        return {k: self.pos(v, f"landmarks.{k}") for k, v in table.items()}

    def costs(self) -> dict[str, CostDist]:
        table = self.get(self.raw, "costs", "costs", dict, {})
        for verb in table:
            if verb not in VERBS:
                raise self.fail(f"costs.{verb}",
                                f"unknown verb; expected one of {', '.join(VERBS)}")
        return {v: self.cost(table.get(v, 1.0), f"costs.{v}") for v in VERBS}

    def tasks(self, world: World, forbidden: frozenset[str]) -> dict[str, Task]:
        out = {}
        for name, t in self.get(self.raw, "tasks", "tasks", dict, {}).items():
            key = f"tasks.{name}"
            if not isinstance(t, dict):
                raise self.fail(key, f"expected a table, got {t!r}")
            ends = []
            for end in ("start", "goal"):
                value = self.get(t, end, f"{key}.{end}", str)
                p = world.landmarks.get(value, value)
                if p not in world.index:
                    why = "is in a forbidden area" if p in forbidden else "is not a position"
                    raise self.fail(f"{key}.{end}", f"{value!r} {why} (nor a landmark)")
                ends.append(p)
            irr = self.get(t, "irrelevant_areas", f"{key}.irrelevant_areas", list, [])
            for a in irr:
                if a not in world.areas:
                    raise self.fail(f"{key}.irrelevant_areas", f"unknown area {a!r}")
            out[name.upper()] = Task(name.upper(), ends[0], ends[1], tuple(irr))
        return out
