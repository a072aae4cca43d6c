"""Pictures of a world: a text map (``ansi``) and an image (``rgb_array``) of a
:class:`Frame`, the map panels of reports and Q tables (:meth:`MapPainter.draw_map`,
``draw_route``, ``draw_q``), and any text as an image (:func:`text_image`). The map is a
(deterministic) Kamada-Kawai layout of the position graph.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world_types import Task, World

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure

MOVES = ("goto", "approach", "gothrough")
"""The verbs whose position is where the robot goes."""


@dataclass(frozen=True)
class Frame:
    """One moment of an episode, by name."""

    world: World
    task_name: str
    robot: str
    goal: str
    open_doors: frozenset[str]
    step: int
    cause: str = ""
    action: str = ""
    """The action that led to this frame (``""`` at the start of an episode)."""


def _label(frame: Frame, p: str) -> str:
    marks = ("@" if p == frame.robot else "") + ("*" if p == frame.goal else "")
    door = frame.world.door_at.get(p)
    return marks + p + ("" if door is None else
                        f"[{door.name} {'open' if door.name in frame.open_doors else 'closed'}]")


def ansi(frame: Frame) -> str:
    """A text map: one line per area listing its positions (``@`` the robot, ``*`` the
    goal, a door side with its door), then the doors."""
    w = frame.world
    status = f", {frame.cause}" if frame.cause else ""
    lines = [f"{w.name} task {frame.task_name}: robot {frame.robot}, goal {frame.goal}, "
             f"step {frame.step}/{w.step_limit}{status}"]
    listed: set[str] = set()
    for number in sorted(w.areas):
        members = w.areas[number]
        listed.update(members)
        lines.append(f"area {number}: " + "  ".join(_label(frame, p) for p in members))
    rest = [p for p in w.positions if p not in listed]
    if rest:
        lines.append("no area: " + "  ".join(_label(frame, p) for p in rest))
    doors = [f"{d.name} {d.sides[0]}|{d.sides[1]} "
             f"{'open' if d.name in frame.open_doors else 'closed'}" for d in w.doors]
    if doors:
        lines.append("doors: " + ", ".join(doors))
    lines.append("(@ robot, * goal)")
    return "\n".join(lines) + "\n"


def text_image(text: str, size: tuple[int, int] = (640, 480)) -> np.ndarray:
    """``text`` in monospace on white, wrapped at (breaking) spaces and cut with ``...``,
    as a ``uint8[H, W, 3]`` image of a fixed ``(W, H)`` in pixels (as a video needs)."""
    from matplotlib.figure import Figure  # start-up time: matplotlib loads when drawing

    lines = [part for line in text.splitlines() for part in textwrap.wrap(line, 76) or [""]]
    rows = size[1] // 12 - 1
    fig = Figure(figsize=(size[0] / 80, size[1] / 80), dpi=80)
    fig.text(0.01, 0.99, "\n".join(lines[:rows - 1] + ["..."] if len(lines) > rows else lines),
             family="monospace", fontsize=9, va="top")
    return _pixels(fig)


def _pixels(fig: Figure) -> np.ndarray:
    """``fig`` drawn (Agg) as a fresh ``uint8[H, W, 3]`` array."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # start-up time, as above

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()


ROBOT, GOAL, FLOOR, DOOR_SIDE = "#d62728", "#2ca02c", "#dddddd", "#bbbbff"
OPEN, CLOSED = "#2ca02c", "#d62728"


def caption(frame: Frame) -> tuple[str, str]:
    """The title of a frame's image (the task, the step and the action taken, or
    ``start``; why the episode ended) and its second line, what was just done."""
    status = f" ({frame.cause})" if frame.cause else ""
    title = (f"task {frame.task_name}: robot at {frame.robot}, goal {frame.goal}, "
             f"step {frame.step}/{frame.world.step_limit}{status}")
    done = f"action taken: {frame.action}" if frame.action else "start of the episode"
    return title, done


LEGEND = [("o", ROBOT, "robot"), ("o", DOOR_SIDE, "door side"), ("o", FLOOR, "position"),
          ("ring", GOAL, "goal"), ("-", OPEN, "door open"), (":", CLOSED, "door closed")]
"""The legend of a frame: (marker, colour, label)."""


class MapPainter:
    """Draws frames of one world as ``uint8[H, W, 3]`` images with matplotlib (Agg)."""

    def __init__(self, world: World, size: tuple[float, float] = (6.0, 6.0),
                 dpi: int = 80) -> None:
        import networkx as nx  # start-up time: loaded only when a map is drawn

        self.world, self.size, self.dpi = world, size, dpi
        graph = nx.Graph()
        graph.add_nodes_from(world.positions)
        graph.add_edges_from(world.edges)
        layout = nx.kamada_kawai_layout(graph) if len(world.positions) > 1 else {
            p: np.zeros(2) for p in world.positions}
        self.xy = {p: np.asarray(layout[p], dtype=float) for p in world.positions}

    def __call__(self, frame: Frame) -> np.ndarray:
        """Render ``frame``; returns a fresh ``uint8[H, W, 3]`` array."""
        from matplotlib.figure import Figure  # start-up time, as above

        w, xy = self.world, self.xy
        fig = Figure(figsize=self.size, dpi=self.dpi)
        ax = fig.add_axes((0.02, 0.09, 0.96, 0.81))
        ax.set_axis_off()
        door_edges = {frozenset(d.sides): d for d in w.doors}
        for a, b in w.edges:
            door = door_edges.get(frozenset((a, b)))
            colour, width, style = ("#888888", 1.5, "-") if door is None else \
                (OPEN, 4.0, "-") if door.name in frame.open_doors else (CLOSED, 4.0, ":")
            ax.plot(*zip(xy[a], xy[b], strict=True), color=colour, lw=width, ls=style,
                    zorder=1)
            if door is not None:
                mid = (xy[a] + xy[b]) / 2
                ax.text(*mid, door.name, fontsize=8, ha="center", va="center", zorder=4,
                        bbox={"fc": "white", "ec": colour, "boxstyle": "round,pad=0.15"})
        for p in w.positions:
            face = ROBOT if p == frame.robot else DOOR_SIDE if p in w.door_at else FLOOR
            edge, lw = (GOAL, 3.5) if p == frame.goal else ("#444444", 1.0)
            ax.scatter(*xy[p], s=500, c=face, edgecolors=edge, linewidths=lw, zorder=2)
            ax.text(*xy[p], p, fontsize=8, ha="center", va="center", zorder=3,
                    color="white" if p == frame.robot else "black")
        self._legend(fig)
        title, done = caption(frame)
        fig.text(0.5, 0.975, title, ha="center", va="top", fontsize=10)
        fig.text(0.5, 0.935, done, ha="center", va="top", fontsize=10, weight="bold",
                 color="#1f4e79")
        ax.margins(0.08)
        return _pixels(fig)

    @staticmethod
    def _legend(fig: Figure) -> None:
        """:data:`LEGEND` along the bottom of ``fig``."""
        from matplotlib.lines import Line2D  # start-up time, as above

        handles = []
        for marker, colour, label in LEGEND:
            if marker in ("-", ":"):
                handles.append(Line2D([], [], color=colour, lw=3, ls=marker, label=label))
            else:
                ring = marker == "ring"
                handles.append(Line2D([], [], ls="", marker="o", markersize=9, label=label,
                                      markerfacecolor="white" if ring else colour,
                                      markeredgecolor=colour if ring else "#444444",
                                      markeredgewidth=2.5 if ring else 1.0))
        fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=7, frameon=False,
                   bbox_to_anchor=(0.5, 0.0), handlelength=1.6, columnspacing=1.2)

    def draw_q(self, ax: Axes, q: np.ndarray, masks: np.ndarray | None = None,
               norm: Normalize | None = None, cmap: str = "viridis",
               goal: str | None = None) -> ScalarMappable:
        """Draw a Q table (``float[n_states, n_actions]``) on ``ax``: positions coloured by
        ``max_a Q`` (``norm``: default their range), an arrow to where the greedy action
        leads (:func:`greedy_target`; a cross: nowhere). Returns the mapping for a colorbar.
        ``goal``: the task's goal position, where episodes end and Q stays 0; it is drawn
        as a gold star outside the colour scale, not as the place worth least."""
        from matplotlib.cm import ScalarMappable  # start-up time, as above
        from matplotlib.colors import Normalize

        spaces = LearnerSpaces(self.world)
        values = np.array([max(q[spaces.state(p, is_open)].max() for is_open in (False, True))
                           for p in self.world.positions])
        scaled = np.array([p != goal for p in self.world.positions])
        if norm is None:
            low, high = float(values[scaled].min()), float(values[scaled].max())
            norm = Normalize(low, high if high > low else low + 1.0)
        mapping = ScalarMappable(norm=norm, cmap=cmap)
        colours = mapping.to_rgba(values)
        colours[~scaled] = (1.0, 1.0, 1.0, 1.0)
        self.draw_map(ax, colours, 260,
                      ["white" if v < 0.5 and s else "black"
                       for v, s in zip(norm(values), scaled, strict=True)])
        if goal is not None:
            ax.scatter(*self.xy[goal], s=700, marker="*", color="#e6a700", edgecolors="black",
                       lw=0.8, zorder=5, label="goal (episode ends: no value)")
        for p in self.world.positions:
            if p == goal:
                continue
            greedy = greedy_target(spaces, q, p, masks)
            if greedy == "":
                ax.scatter(*self.xy[p], s=500, marker="x", color="#d62728", lw=1.5, zorder=4)
            elif greedy is not None:
                self.draw_route(ax, (p, greedy), "#d62728", 1.8)
        return mapping

    def draw_map(self, ax: Axes, colours: object, sizes: object, text: Sequence[str],
                 task: Task | None = None, alpha: float = 1.0, areas: bool = False,
                 irrelevant: Sequence[int] = ()) -> None:
        """The world on ``ax``: corridors thin grey, doors thick dotted brown with their
        names, each position a marker (``colours``, ``sizes``) with its number in ``text``
        colours, the ``task``'s start ringed blue and its goal green; ``areas``: each area
        a dashed circle labelled with its number, those in ``irrelevant`` shaded grey and
        labelled so."""
        w, xy = self.world, self.xy
        door_edges = {frozenset(d.sides) for d in w.doors}
        for a, b in w.edges:
            door = frozenset((a, b)) in door_edges
            ax.plot(*zip(xy[a], xy[b], strict=True), color="#8c564b" if door else "#999999",
                    lw=3.0 if door else 1.2, ls=":" if door else "-", alpha=alpha, zorder=1)
        for d in w.doors:
            ax.text(*(xy[d.sides[0]] + xy[d.sides[1]]) / 2, d.name, fontsize=6, ha="center",
                    va="bottom", color="#8c564b", zorder=5, in_layout=False)
        pts = np.array([xy[p] for p in w.positions])
        ax.scatter(pts[:, 0], pts[:, 1], s=sizes, c=colours, edgecolors="#333333",
                   linewidths=0.6, zorder=3)
        for p, colour in zip(w.positions, text, strict=True):
            ax.text(*xy[p], p[1:] if p[1:].isdigit() else p, fontsize=5, ha="center",
                    va="center", zorder=6, color=colour, in_layout=False)
        if task is not None:
            ax.scatter(*np.array([xy[task.start], xy[task.goal]]).T, s=420, facecolors="none",
                       edgecolors=["#1f77b4", "#2ca02c"], lw=2.2, zorder=4)
        if areas:
            self._outline_areas(ax, frozenset(irrelevant))
        ax.set_axis_off()
        ax.set_aspect("equal")
        ax.margins(0.1)

    def _outline_areas(self, ax: Axes, irrelevant: frozenset[int] = frozenset()) -> None:
        from matplotlib.patches import Circle  # start-up time, as above

        span = np.ptp(np.array(list(self.xy.values())), axis=0).max() or 1.0
        for area, positions in sorted(self.world.areas.items()):
            if not positions:
                continue
            pts = np.array([self.xy[p] for p in positions])
            centre = pts.mean(axis=0)
            radius = np.linalg.norm(pts - centre, axis=1).max() + 0.035 * span
            off = area in irrelevant
            ax.add_patch(Circle(centre, radius, fill=off, fc="#e3e3e3", ls="--", lw=0.8,
                                ec="#555555", zorder=0.5 if off else 2, in_layout=False))
            ax.text(centre[0], centre[1] + radius,
                    f"area {area}" + (" (irrelevant)" if off else ""), fontsize=6,
                    ha="center", va="bottom", color="#333333", zorder=6, in_layout=False)

    def draw_route(self, ax: Axes, positions: Sequence[str], colour: str,
                   lw: float = 2.2) -> None:
        """Arrows from each position of ``positions`` to the next (repeats skipped)."""
        for a, b in zip(positions[:-1], positions[1:], strict=True):
            if a != b:
                ax.annotate("", xy=self.xy[b], xytext=self.xy[a], zorder=4, in_layout=False,
                            arrowprops={"arrowstyle": "-|>", "color": colour, "lw": lw,
                                        "shrinkA": 7, "shrinkB": 7})

    def draw_plans(self, ax: Axes, routes: Sequence[Sequence[str]], task: Task | None = None,
                   labels: Sequence[str] | None = None) -> None:
        """The world on ``ax`` with each route of ``routes`` (positions, as
        :func:`plan_route` gives them) drawn as arrows in a colour of its own, side by side
        where routes share a corridor, and a legend (``labels``: default "plan k, n
        moves")."""
        self._plain_map(ax, task)
        span = np.ptp(np.array(list(self.xy.values())), axis=0).max() or 1.0
        colours = ("#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9",
                   "#000000", "#882255", "#999933", "#332288", "#44aa99", "#aa4499")
        for k, route in enumerate(routes):
            colour = colours[k % len(colours)]
            shift = (k - (len(routes) - 1) / 2) * min(0.012, 0.04 / len(routes)) * span
            for a, b in zip(route[:-1], route[1:], strict=True):
                if a == b:
                    continue
                d = self.xy[b] - self.xy[a]
                normal = np.array([-d[1], d[0]]) / (np.linalg.norm(d) or 1.0) * shift
                ax.annotate("", xy=self.xy[b] + normal, xytext=self.xy[a] + normal, zorder=4,
                            in_layout=False,
                            arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 2.0,
                                        "shrinkA": 9, "shrinkB": 9})
            label = labels[k] if labels is not None else \
                f"plan {k + 1}: {' > '.join(route)}"
            ax.plot([], [], color=colour, lw=2.0, label=label)
        if routes:
            ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), fontsize=8,
                      frameon=False)

    def _plain_map(self, ax: Axes, task: Task | None) -> None:
        """The world on ``ax`` at a size to read: corridors grey, doors dotted brown with
        their names, each position by its name, the ``task``'s start ringed blue and its
        goal green."""
        w, xy = self.world, self.xy
        door_of = {frozenset(d.sides): d.name for d in w.doors}
        for a, b in w.edges:
            door = door_of.get(frozenset((a, b)))
            ax.plot(*zip(xy[a], xy[b], strict=True), color="#999999" if door is None else
                    "#8c564b", lw=1.2 if door is None else 3.0, ls="-" if door is None else ":",
                    zorder=1)
            if door is not None:
                ax.text(*(xy[a] + xy[b]) / 2, door, fontsize=8, ha="center", va="center",
                        color="#8c564b", zorder=5, in_layout=False,
                        bbox={"fc": "white", "ec": "none", "pad": 0.5})
        for p in w.positions:
            ax.scatter(*xy[p], s=330, c=FLOOR, edgecolors="#333333", linewidths=0.6, zorder=3)
            ax.text(*xy[p], p, fontsize=7, ha="center", va="center", zorder=6,
                    in_layout=False)
        if task is not None:
            ax.scatter(*np.array([xy[task.start], xy[task.goal]]).T, s=600,
                       facecolors="none", edgecolors=["#1f77b4", "#2ca02c"], lw=2.5, zorder=4)
        ax.set_axis_off()
        ax.set_aspect("equal")
        ax.margins(0.08)


def plan_route(spaces: LearnerSpaces, plan: Sequence[tuple[int, int]]) -> list[str]:
    """The positions a plan (learner ``(state, action)`` pairs, as
    :meth:`~gdq_pddl.abstraction.PlanTable.plans_from` lists them) takes the robot
    through: where it starts, then where each move goes (opening a door moves nobody)."""
    if not plan:
        return []
    route = [spaces.states[plan[0][0]][0]]
    for _, a in plan:
        verb, target = spaces.action_parts(a)
        if verb in MOVES and target != route[-1]:
            route.append(target)
    return route


_PAINTERS: dict[int, MapPainter] = {}


def map_painter(world: World) -> MapPainter:
    """The :class:`MapPainter` of ``world``, laid out once per world object (the
    Kamada-Kawai layout is the slow part of a map)."""
    painter = _PAINTERS.get(id(world))
    if painter is None or painter.world is not world:
        painter = _PAINTERS[id(world)] = MapPainter(world)
    return painter


def greedy_target(spaces: LearnerSpaces, q: np.ndarray, position: str,
                  masks: np.ndarray | None = None) -> str | None:
    """Where the greedy action of ``q`` (door closed; or open, if that ties or opens it)
    takes the robot from ``position``: ``""`` if nowhere (``stay``, or out of ``masks``),
    None if no action is preferred."""
    state = spaces.state(position)
    a = _greedy(q[state])
    opens = a is not None and spaces.action_parts(a)[0] == "opendoor"
    if (a is None or opens) and position in spaces.world.door_at:
        inside = spaces.state(position, True)
        b = _greedy(q[inside])
        if b is not None:
            state, a, opens = inside, b, False
    if a is None or opens:
        return None
    verb, target = spaces.action_parts(a)
    if verb not in MOVES or target == position or (masks is not None and not masks[state, a]):
        return ""
    return target


def _greedy(row: np.ndarray) -> int | None:
    """The first action of maximal Q; None when every action ties."""
    return None if row.max() == row.min() else int(row.argmax())
