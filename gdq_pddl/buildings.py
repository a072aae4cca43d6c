"""Generated office-like buildings of any size, as world files (``gdq-pddl building``).

From ``numpy.random.default_rng(seed)``: corridor rows joined by short corridors, rooms
of 3-8 positions behind doors (some with a second door), fire doors in corridors; ``K``
doors in all (default ``positions // 8``), one area per room and corridor segment. Tasks
A, B, C join far rooms; a door on a task's shortest route that another route avoids is
made "most difficult" (as the office's Task C). ``step_limit = r_max = ceil(2.5 L)``,
``L`` the tasks' longest shortest plan.
"""

from __future__ import annotations

import itertools
import math
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gdq_pddl.errors import WorldError
from gdq_pddl.limits import check_memory
from gdq_pddl.outputs import output_folder, write_text
from gdq_pddl.resources import domain_text
from gdq_pddl.world import parse_world
from gdq_pddl.world_types import Task, World, office_problem

DOOR_KINDS: tuple[tuple[str, float, float, float], ...] = (
    # label, success, stuck, how often
    ("easiest", 0.95, 0.0, 0.35),
    ("easy", 0.9, 0.0, 0.55),
    ("difficult", 0.8, 0.2, 0.1),
    ("difficult", 0.6, 0.2, 0.0),
    ("most difficult", 0.6, 0.4, 0.0),
)
"""Door kinds as in the office: label, success and stuck probabilities, and the weight of
the random draw (doors that jam are rare: a long route crosses many; the "most difficult"
kind is placed on purpose by :func:`_tasks`)."""

MIN_POSITIONS = 40
POSITION_BYTES = 2000
"""Memory per position while a building is generated and validated (measured: 1.2 kB)."""
STEP_FACTOR = 2.5


@dataclass
class Building:
    """A generated building before it becomes a world file."""

    name: str
    positions: list[str] = field(default_factory=list)
    edges: list[tuple[str, str]] = field(default_factory=list)
    doors: dict[str, dict] = field(default_factory=dict)
    areas: dict[int, list[str]] = field(default_factory=dict)
    rooms: list[list[str]] = field(default_factory=list)
    landmarks: dict[str, str] = field(default_factory=dict)
    tasks: dict[str, tuple[str, str]] = field(default_factory=dict)
    step_limit: int = 20
    description: str = ""

    def add(self, area: int) -> str:
        p = f"p{len(self.positions)}"
        self.positions.append(p)
        self.areas.setdefault(area, []).append(p)
        return p


def generate(positions: int, seed: int = 0, doors: int | None = None) -> Building:
    """A building of exactly ``positions`` positions (WorldError: the numbers cannot)."""
    if positions < MIN_POSITIONS:
        raise WorldError("building", "positions", f"need at least {MIN_POSITIONS}, got {positions}")
    check_memory(positions * POSITION_BYTES, f"positions = {positions:,}: generating the "
                 "building", "give fewer positions")
    k = positions // 8 if doors is None else doors
    if not 5 <= k <= positions:  # rooms for the tasks' 3 landmarks, a fire door, a second
        # room door; and each door brings a position of its own (a stub, a side)
        raise WorldError("building", "doors", f"need 5 to {positions} doors (at most one per "
                                              f"position), got {k}")
    if seed < 0:
        raise WorldError("building", "seed", f"must be >= 0, got {seed}")
    rng = np.random.default_rng(seed)
    n_fire = max(1, round(k / 6))
    n_second = max(1, round(k / 6))
    n_rooms = k - n_fire - n_second
    sizes = rng.integers(3, 9, size=n_rooms)
    stubs = n_rooms + n_second + 2 * n_fire
    corridor = positions - stubs - int(sizes.sum())
    need = 8 * max(2, round(math.sqrt(max(corridor, 1) / 4)))
    while corridor < need and sizes.max() > 3:  # too many room positions: shrink rooms
        sizes[int(np.argmax(sizes))] -= 1
        corridor += 1
    if corridor < need:
        raise WorldError("building", "doors", f"{k} doors are too many for {positions} "
                                              "positions")
    b = Building(name=f"building-{positions}-s{seed}")
    rows = _corridors(b, rng, corridor, n_fire, k)
    _rooms(b, rng, rows, sizes, n_second)
    _tasks(b, rng)
    b.description = (f"generated building: {positions} positions, {len(b.doors)} doors, "
                     f"{len(b.areas)} areas (seed {seed})")
    assert len(b.positions) == positions
    return b


def _corridors(b: Building, rng: np.random.Generator, n: int, n_fire: int,
               doors: int) -> list[list[str]]:
    """Corridor rows and links of ``n`` positions (``doors``: for the message)."""
    n_rows = max(2, round(math.sqrt(n / 4)))
    n_links = sum(int(rng.integers(2, 4)) for _ in range(n_rows - 1))
    link_len = rng.integers(1, 4, size=n_links)
    row_total = n - int(link_len.sum())
    weights = rng.uniform(0.8, 1.2, size=n_rows)
    lengths = np.floor(weights / weights.sum() * row_total).astype(int)
    lengths[: row_total - lengths.sum()] += 1
    # each fire door goes into a row or a link (a link holds at most one); a row holds one
    # per position at least 2 from its ends, and a fire door drawn for a full row goes
    # where there is room instead (no draw: every building that fitted stays the same)
    row_fires = np.zeros(n_rows, dtype=int)
    room_left = np.maximum(lengths - 4, 0)
    link_fire = np.zeros(n_links, dtype=bool)
    for _ in range(n_fire):
        slot = int(rng.integers(0, n_rows + n_links))
        if slot >= n_rows and not link_fire[slot - n_rows]:
            link_fire[slot - n_rows] = True
            continue
        row = slot % n_rows if room_left[slot % n_rows] else int(np.argmax(room_left))
        if room_left[row]:
            row_fires[row] += 1
            room_left[row] -= 1
        elif not link_fire.all():
            link_fire[int(np.argmin(link_fire))] = True
        else:
            raise WorldError("building", "doors", f"{doors} doors are too many: their {n_fire} "
                                                  f"fire doors do not fit in the corridors' {n} "
                                                  "positions")
    area = 1
    rows: list[list[str]] = []
    for r, length in enumerate(lengths):
        fires = set(rng.choice(np.arange(2, length - 2), size=row_fires[r],
                               replace=False).tolist())
        row: list[str] = []
        seg_left = int(rng.integers(4, 9))
        for i in range(length):
            new_area = seg_left == 0 or i in fires
            if new_area:
                area += 1
                seg_left = int(rng.integers(4, 9))
            p = b.add(area)
            if i in fires:
                _door_between(b, row[-1], p, area - 1, area)
            elif row:
                b.edges.append((row[-1], p))
            row.append(p)
            seg_left -= 1
        rows.append(row)
        area += 1
    gaps = np.sort(rng.integers(0, n_rows - 1, size=n_links))
    gaps[: n_rows - 1] = np.arange(n_rows - 1)  # every pair of rows is joined
    for k, gap in enumerate(np.sort(gaps)):
        upper, lower = rows[gap], rows[gap + 1]
        a = upper[int(rng.integers(0, len(upper)))]
        z = lower[int(rng.integers(0, len(lower)))]
        path = [a, *(b.add(area) for _ in range(int(link_len[k]))), z]
        for i, (x, y) in enumerate(itertools.pairwise(path)):
            if link_fire[k] and i == 0:
                _door_between(b, x, y, area, area)
            else:
                b.edges.append((x, y))
        area += 1
    return rows


def _door_between(b: Building, x: str, y: str, area_x: int, area_y: int) -> None:
    """Put a door, with its two sides as new positions, between ``x`` and ``y``."""
    s1, s2 = b.add(area_x), b.add(area_y)
    b.edges += [(x, s1), (s1, s2), (s2, y)]
    b.doors[f"d{len(b.doors)}"] = {"sides": (s1, s2)}


def _rooms(b: Building, rng: np.random.Generator, rows: list[list[str]], sizes: np.ndarray,
           n_second: int) -> None:
    door_sides = {s for d in b.doors.values() for s in d["sides"]}
    corridor = [p for row in rows for p in row if p not in door_sides]
    area = max(b.areas) + 1

    def stub() -> str:
        """A new position off a random corridor position (in its area), joined to it."""
        at = corridor[int(rng.integers(0, len(corridor)))]
        out = b.add(next(a for a, ps in b.areas.items() if at in ps))
        b.edges.append((at, out))
        return out

    for size in sizes:
        door_side = stub()
        room = [b.add(area) for _ in range(int(size))]
        b.edges.append((door_side, room[0]))
        b.doors[f"d{len(b.doors)}"] = {"sides": (door_side, room[0])}
        b.edges += list(zip(room, room[1:], strict=False))
        if size >= 4 and rng.random() < 0.5:
            b.edges.append((room[0], room[2]))
        b.rooms.append(room)
        area += 1
    for i in rng.permutation(len(b.rooms))[:n_second]:  # a second door to some rooms
        door_side, room = stub(), b.rooms[i]  # (of 3 positions at least)
        b.edges.append((door_side, room[-1]))
        b.doors[f"d{len(b.doors)}"] = {"sides": (door_side, room[-1])}
    kinds = rng.choice(len(DOOR_KINDS), size=len(b.doors),
                       p=[k[3] for k in DOOR_KINDS])
    for door, kind in zip(b.doors.values(), kinds, strict=True):
        label, success, stuck, _ = DOOR_KINDS[int(kind)]
        door.update(label=label, success=success, stuck=stuck)


def _graph(b: Building, skip: frozenset[str] = frozenset()) -> dict[str, list[tuple[str, int]]]:
    """Position graph weighted by plan steps: 2 across a door (open + go through)."""
    side_of = {s: name for name, d in b.doors.items() for s in d["sides"]}
    out: dict[str, list[tuple[str, int]]] = {p: [] for p in b.positions}
    for x, y in b.edges:
        if side_of.get(x) is not None and side_of.get(x) == side_of.get(y):
            if side_of[x] in skip:
                continue
            w = 2
        else:
            w = 1
        out[x].append((y, w))
        out[y].append((x, w))
    return out


def _distances(graph: dict[str, list[tuple[str, int]]], source: str) -> dict[str, int]:
    """0-1-2 weighted shortest distances (a small Dijkstra by buckets)."""
    dist = {source: 0}
    buckets: list[deque[str]] = [deque([source])]
    d = 0
    while d < len(buckets):
        while buckets[d]:
            p = buckets[d].popleft()
            if dist[p] != d:
                continue
            for q, w in graph[p]:
                if q not in dist or dist[q] > d + w:
                    dist[q] = d + w
                    while len(buckets) <= d + w:
                        buckets.append(deque())
                    buckets[d + w].append(q)
        d += 1
    return dist


def _route_doors(b: Building, graph, start: str, goal: str) -> list[str]:
    """Doors on one shortest route from ``start`` to ``goal``."""
    dist = _distances(graph, goal)
    side_of = {s: name for name, d in b.doors.items() for s in d["sides"]}
    out, p = [], start
    while p != goal:
        q = min((q for q, w in graph[p] if dist.get(q, math.inf) + w == dist[p]),
                key=b.positions.index)
        if side_of.get(p) is not None and side_of.get(p) == side_of.get(q):
            out.append(side_of[p])
        p = q
    return out


def _tasks(b: Building, rng: np.random.Generator) -> None:
    graph = _graph(b)
    inner = [room[len(room) // 2] for room in b.rooms]
    probe = inner[int(rng.integers(0, len(inner)))]
    far_a = max(inner, key=_distances(graph, probe).__getitem__)
    dist_a = _distances(graph, far_a)
    far_b = max(inner, key=dist_a.__getitem__)
    dist_b = _distances(graph, far_b)
    third = max((p for p in inner if p not in (far_a, far_b)),
                key=lambda p: min(dist_a[p], dist_b[p]))
    b.landmarks = {"P1": far_a, "P2": far_b, "P3": third}
    b.tasks = {"A": (far_a, far_b), "B": (far_b, far_a), "C": (third, far_a)}
    ends = {p for task in b.tasks.values() for p in task}
    for door in b.doors.values():  # the start and goal rooms' doors never jam
        if door["stuck"] > 0 and any(ends & set(room) for room in b.rooms
                                     if not set(room).isdisjoint(door["sides"])):
            door.update(label="easy", success=0.9, stuck=0.0)
    forced: set[str] = set()
    for start, goal in b.tasks.values():
        route = _route_doors(b, graph, start, goal)
        if forced & set(route):
            continue  # already made non-shortest by another task's door
        for name in route:
            if set(b.doors[name]["sides"]) & {start, goal}:
                continue
            if goal in _distances(_graph(b, frozenset(forced | {name})), start):
                b.doors[name].update(label="most difficult", success=0.6, stuck=0.4)
                forced.add(name)
                break
    longest = max(_distances(graph, s)[g] for s, g in b.tasks.values())
    b.step_limit = math.ceil(STEP_FACTOR * longest)


def to_toml(b: Building) -> str:
    """The world file text of ``b`` (the schema of ``gdq_pddl/data/office.toml``)."""
    q = '"{}"'.format
    lines = [
        f"# {b.description}. Generated by `gdq-pddl building`; regenerate rather than edit.",
        f"# step_limit = ceil({STEP_FACTOR} x the longest shortest plan of the tasks); "
        "r_max = step_limit.",
        "",
        "[world]",
        f"name = {q(b.name)}",
        f"description = {q(b.description)}",
        f"step_limit = {b.step_limit}",
        f"r_max = {float(b.step_limit)}",
        "navigation_success = 0.95",
        "positions = [" + ", ".join(q(p) for p in b.positions) + "]",
        "adjacency = [",
        *(f"  [{q(x)}, {q(y)}]," for x, y in b.edges),
        "]",
        "",
        "[costs]",
        *(f"{v} = 1.0" for v in ("goto", "approach", "opendoor", "gothrough", "stay")),
    ]
    for name, d in b.doors.items():
        lines += ["", f"[doors.{name}]", f"sides = [{q(d['sides'][0])}, {q(d['sides'][1])}]",
                  f"success = {d['success']}", f"stuck = {d['stuck']}",
                  f"label = {q(d['label'])}"]
    lines += ["", "[areas]"]
    lines += [f"{a} = [" + ", ".join(q(p) for p in ps) + "]" for a, ps in sorted(b.areas.items())]
    lines += ["", "[landmarks]", *(f"{k} = {q(v)}" for k, v in b.landmarks.items())]
    for name, (s, g) in b.tasks.items():
        lines += ["", f"[tasks.{name}]", f"start = {q(s)}", f"goal = {q(g)}"]
    return "\n".join(lines) + "\n"


def building_world(positions: int, seed: int = 0, doors: int | None = None) -> World:
    """The validated :class:`World` of a generated building (nothing written)."""
    b = generate(positions, seed, doors)
    return parse_world(to_toml(b), source=f"{b.name}.toml (generated)")


def write_building(out: str | Path, positions: int, seed: int = 0,
                   doors: int | None = None) -> tuple[Path, list[Path]]:
    """Write ``<name>.toml`` (validated first), ``domain.pddl`` and
    ``problems/<name>-<task>.pddl`` to ``out``; returns the world and problem files."""
    b = generate(positions, seed, doors)
    text = to_toml(b)
    world = parse_world(text, source=f"{b.name}.toml (generated)")
    out = output_folder(out)
    output_folder(out / "problems")
    world_path = out / f"{b.name}.toml"
    write_text(world_path, text)
    write_text(out / "domain.pddl", domain_text())
    problems = []
    for task in world.tasks.values():
        path = out / "problems" / f"{b.name}-{task.name.lower()}.pddl"
        write_text(path, office_problem(world, Task(task.name, task.start, task.goal)))
        problems.append(path)
    return world_path, problems
