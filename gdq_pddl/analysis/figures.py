"""Figures of an output folder, PNG and PDF (matplotlib ``Figure`` objects, no pyplot).

Each takes a :class:`~gdq_pddl.analysis.study.Study` and a target folder and returns the
paths it wrote (none when its experiment is missing); a method has one colour everywhere.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.colors import PowerNorm
from matplotlib.figure import Figure
from scipy.special import stdtrit  # t's quantile: scipy.stats costs 0.6 s of start-up

from gdq_pddl.analysis.stats import mean_se, moving_average
from gdq_pddl.analysis.study import Study, curves_stem, slug
from gdq_pddl.envs.render import map_painter
from gdq_pddl.experiments.results import ROBOT_EXPERIMENT, TASKS_EXPERIMENT
from gdq_pddl.learners import registry
from gdq_pddl.outputs import save_figure

INTERVAL = "95% t-interval over runs"
"""What the curves' bands are: over the runs' smoothed curves, mean +- t(0.975, runs - 1)
x standard error."""


def method_line(method: str) -> object:
    """The line style of ``method``'s curves: its learner's dashes in the registry (GDQ's
    and DARLING's variants apart from the learner they read like), solid otherwise."""
    pattern = registry.dashes(method)
    return (0, pattern) if pattern else "-"


def method_colour(method: str) -> str:
    """The colour of ``method`` in every figure (its learner's in the registry: Okabe and
    Ito's colour-blind-safe palette, GDQ's variants apart; a method with settings or an
    unknown name: a stable extra colour)."""
    return registry.colour(method)


@dataclass(frozen=True)
class FigureOptions:
    """How figures are drawn."""

    window: int = 50
    """Moving-average window of learning curves, in episodes."""
    after_switch: int = 250
    """Episodes after a goal change the switch figure's lower row shows."""
    formats: tuple[str, ...] = ("png", "pdf")
    dpi: int = 120


def save_all(fig: Figure, out_dir: Path, stem: str, opts: FigureOptions = FigureOptions()
             ) -> list[Path]:
    """Save ``fig`` as ``out_dir/stem.<format>`` for each of ``opts.formats``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for ext in opts.formats:
        path = out_dir / f"{stem}.{ext}"
        save_figure(fig, path, dpi=opts.dpi)
        paths.append(path)
        # the first save laid the figure out; keep that layout for the other formats
        # rather than solving it again (constrained layout is most of a save's time)
        fig.set_layout_engine("none")
    return paths


def grid(n: int, width: float = 5.0, height: float = 3.6, max_cols: int = 2,
         maps: bool = False, right: float = 0.0) -> tuple[Figure, list[Axes]]:
    """``n`` panels of ``width`` x ``height`` inches, at most ``max_cols`` a row, the unused
    cells of the last row hidden; constrained layout, or for ``maps`` a fixed one (map
    panels have no ticks, and solving the layout over hundreds of position labels is
    slow): 0.45 in for the title, 0.3 in above and below each panel for its texts and
    ``right`` inches on the right for a colorbar."""
    cols = max(1, min(n, max_cols))
    rows = math.ceil(n / cols)
    wide, high = width * cols + right, height * rows + 0.45 * maps
    fig = Figure(figsize=(wide, high), layout=None if maps else "constrained")
    axes = fig.subplots(rows, cols, squeeze=False)
    if maps:
        fig.subplots_adjust(0.05 / wide, 0.3 / high, 1 - (0.05 + right) / wide,
                            1 - 0.75 / high, wspace=0.1 / (width - 0.1),
                            hspace=0.6 / (height - 0.6))
    flat = list(axes.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


def _bands(ax: Axes, study: Study, exp: str, window: int, title: str, task: str | None = None,
           scale: float = 1.0, markers: bool = False, xlabel: str = "episode",
           ylabel: str = "return (cumulative reward)", restart: int | None = None
           ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per method: each run's return curve smoothed by a trailing average, then their mean
    over runs with its 95% t-interval (:data:`INTERVAL`; ``markers``: also a dot per
    episode), in a gridded panel titled ``title``; returns (x, low, high) per method.
    ``restart``: the average starts again at that episode (a goal switch), so no
    smoothed value mixes episodes of both sides."""
    ax.set_title(title, fontsize=10)
    ax.set(xlabel=xlabel, ylabel=ylabel)
    ax.grid(alpha=0.3)
    out = []
    for method in study.methods(exp):
        matrix = study.matrix("return", exp, method, task) / scale
        if not matrix.size:
            continue
        n, x = matrix.shape[0], np.unique(study.rows(exp, method, task)["episode"])
        smooth = _smooth(matrix, x, window, restart)
        mean, se = mean_se(smooth)
        se = se * (stdtrit(n - 1, 0.975) if n > 1 else 0.0)
        colour = method_colour(method)
        ax.plot(x, mean, color=colour, lw=1.4, ls=method_line(method),
                label=f"{method} (n={n})")
        ax.fill_between(x, mean - se, mean + se, color=colour, alpha=0.2, lw=0)
        if markers:
            ax.plot(x, mean, "o", ms=2.5, color=colour)
        out.append((x, mean - se, mean + se))
    return out


def _smooth(matrix: np.ndarray, x: np.ndarray, window: int, restart: int | None
            ) -> np.ndarray:
    """Trailing ``window``-episode average of each row of ``matrix`` (columns: episodes
    ``x``), started again at episode ``restart`` if there is one."""
    if window <= 1:
        return matrix
    if restart is None:
        return moving_average(matrix, window, full_only=False)
    after = x >= restart
    out = np.empty_like(matrix, dtype=float)
    for side in (~after, after):
        if side.any():
            out[:, side] = moving_average(matrix[:, side], window, full_only=False)
    return out


def _task_title(study: Study, experiment: str, task: str) -> str:
    t = study.task(experiment, task)
    return f"Task {task}: {t.start} -> {t.goal}" if t is not None else f"problem {task}"


def learning_curves(study: Study, out_dir: Path, opts: FigureOptions = FigureOptions(),
                    fraction_of_vstar: bool = False,
                    experiment: str = TASKS_EXPERIMENT) -> list[Path]:
    """Return per episode (or return / V*) of each task of ``experiment`` (the paper's
    tasks A-D by default), mean over runs with its 95% interval, smoothed. Return / V*
    is drawn from -0.1 to 1.1, where the methods that learn can be told apart."""
    exp = experiment
    if not study.has(exp):
        return []
    tasks = study.tasks(exp)
    fig, axes = grid(len(tasks))
    for ax, task in zip(axes, tasks, strict=True):
        v_star = study.v_star(exp, task)
        _bands(ax, study, exp, opts.window, _task_title(study, exp, task), task,
               v_star if fraction_of_vstar else 1.0,
               ylabel="return / V*" if fraction_of_vstar else "return (cumulative reward)")
        ref = 1.0 if fraction_of_vstar else v_star
        if not math.isnan(ref):
            ax.axhline(ref, color="black", ls="--", lw=0.8,
                       label="V*" if not fraction_of_vstar else "V* (= 1)")
        if fraction_of_vstar:
            ax.set_ylim(-0.1, 1.1)
    axes[0].legend(fontsize=7, loc="lower right")
    what = "return / V* (below -0.1 off the axis)" if fraction_of_vstar else \
        "return per episode"
    sep = "\n" if len(tasks) == 1 else ": "  # one panel is too narrow for one line
    fig.suptitle(f"{what}{sep}mean, {INTERVAL}, {opts.window}-episode moving average",
                 fontsize=11)
    stem = "fraction_of_vstar" if fraction_of_vstar else "learning_curves"
    if exp != TASKS_EXPERIMENT:
        stem = curves_stem(exp) if not fraction_of_vstar else f"{stem}_{slug(exp)}"
    return save_all(fig, out_dir, stem, opts)


def switch_curves(study: Study, out_dir: Path, opts: FigureOptions = FigureOptions()
                  ) -> list[Path]:
    """Each switch experiment (C->D, C->E): return over the whole run with a line at the
    switch (top), and the episodes around the switch at a readable scale (bottom: from
    50 before to ``opts.after_switch`` after, the tested statistic's span)."""
    exps = study.switch_experiments
    if not exps:
        return []
    fig, axes = grid(2 * len(exps), max_cols=len(exps))
    for k, exp in enumerate(exps):
        switch = study.switch_episode(exp)
        for ax, zoom in ((axes[k], False), (axes[len(exps) + k], True)):
            what = f"first {opts.after_switch} episodes after the switch" if zoom else \
                f"task {' -> '.join(study.tasks(exp))}"
            seen = []
            for x, low, high in _bands(ax, study, exp, opts.window, f"{exp}: {what}",
                                       restart=switch):
                if zoom and switch is not None:
                    near = (x >= switch - 50) & (x <= switch + opts.after_switch)
                    seen += [np.nanmin(low[near]), np.nanmax(high[near])]
            if switch is not None:
                ax.axvline(switch - 0.5, color="black", ls=":", lw=1.0, label="switch")
                if zoom:
                    ax.set_xlim(switch - 50, switch + opts.after_switch)
                    pad = 0.05 * (max(seen) - min(seen)) if seen else 0.0
                    ax.set_ylim(min(seen) - pad, max(seen) + pad) if seen else None
    axes[0].legend(fontsize=7, loc="lower right")
    sep = "\n" if len(exps) == 1 else ": "  # one column is too narrow for one line
    fig.suptitle(f"goal change{sep}mean, {INTERVAL}, {opts.window}-episode moving average "
                 "started again at the switch", fontsize=11)
    return save_all(fig, out_dir, "switch_curves", opts)


def visit_heatmaps(study: Study, out_dir: Path, opts: FigureOptions = FigureOptions()
                   ) -> list[Path]:
    """Per task (and for the robot task): one map panel per method, each position coloured
    and sized by its area's visits summed over a run, mean over runs (the CSV counts areas,
    not positions, so all positions of an area share a value)."""
    paths: list[Path] = []
    for exp in (TASKS_EXPERIMENT, ROBOT_EXPERIMENT):
        if not study.has(exp) or not study.has_areas(exp):
            continue
        world = study.world(exp)
        painter = map_painter(world)
        for task in study.tasks(exp):
            irrelevant = study.truth(exp, task).irrelevant_areas
            means = {m: np.nanmean(np.nansum(v, axis=1), axis=0) for m in study.methods(exp)
                     if (v := study.area_visits(exp, m, task)).size}
            if not means:
                continue
            top = max(float(np.max(m)) for m in means.values()) or 1.0
            norm = PowerNorm(gamma=0.5, vmin=0.0, vmax=top)  # keep small counts visible
            cmap = colormaps["magma_r"]
            fig, axes = grid(len(means), 3.6, 3.6, 3, maps=True, right=1.3)
            wide = fig.get_figwidth()
            for ax, (method, mean) in zip(axes, means.items(), strict=True):
                by_area = dict(zip(study.areas, mean, strict=True))
                values = np.array([by_area.get(world.area_of.get(p, -1), 0.0)
                                   for p in world.positions])
                painter.draw_map(ax, cmap(norm(values)), 60 + 400 * np.sqrt(values / top),
                                 ["white" if v > 0.3 * top else "black" for v in values],
                                 study.task(exp, task), 0.6, areas=True,
                                 irrelevant=irrelevant)
                ax.set_title(method, fontsize=10, color=method_colour(method), y=1.0)
            fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), cax=fig.add_axes(
                (1 - 1.15 / wide, 0.2, 0.15 / wide, 0.55)),
                label="area visits per run (mean; square-root colour scale)")
            robot = "robot " if exp == ROBOT_EXPERIMENT else ""
            fig.suptitle(f"{robot}{_task_title(study, exp, task)}: visits per area "
                         "(blue ring start, green ring goal; grey discs: irrelevant areas, "
                         "which the optimal policy visits with probability < 0.05)",
                         fontsize=10, wrap=True)
            paths += save_all(fig, out_dir, f"heatmap_{robot.replace(' ', '_')}{slug(task)}",
                              opts)
    return paths


EMPTY_ROUTE = {"stuck": "its first action does nothing there",
               "no-policy": "it has no action there",
               "loop": "its first action leads back to the start",
               "limit": "it ran out of steps"}
"""Why a greedy route has no arrow, by how the walk ended (:class:`Route`'s ``end``)."""


def task_routes(study: Study, out_dir: Path, opts: FigureOptions = FigureOptions(),
                experiment: str = TASKS_EXPERIMENT, task: str = "C") -> list[Path]:
    """The route each method's final greedy policy takes (most common over runs)."""
    if study.policies is None or not study.has(experiment) or \
            study.task(experiment, task) is None:
        return []
    world = study.world(experiment)
    painter = map_painter(world)
    best = study.truth(experiment, task).optimal_route_areas
    panels = [(m, s) for m in study.methods(experiment)
              if (s := study.route_summary(experiment, m, task)) is not None]
    if not panels:
        return []
    fig, axes = grid(len(panels), 3.6, 3.8, 3, maps=True)
    for ax, (method, summary) in zip(axes, panels, strict=True):
        painter.draw_map(ax, "#eeeeee", 80, ["black"] * len(world.positions),
                         study.task(experiment, task), 0.5)
        painter.draw_route(ax, summary.example.positions, method_colour(method))
        if len(set(summary.example.positions)) < 2:
            why = EMPTY_ROUTE.get(summary.end, summary.end)
            ax.text(0.5, 0.5, f"no arrows: the greedy policy never leaves "
                    f"{summary.example.positions[0]}\n({why})",
                    transform=ax.transAxes, ha="center", va="center", fontsize=8,
                    color=method_colour(method), zorder=7,
                    bbox={"fc": "white", "ec": method_colour(method), "alpha": 0.9})
        areas = "->".join(map(str, summary.areas)) or "(none)"
        ax.set_title(f"{method}: {summary.count}/{summary.runs} runs take this route",
                     fontsize=9, color=method_colour(method), y=1.0)
        ax.text(0.5, -0.02, f"areas {areas} ({summary.end}); optimal route: "
                f"{summary.on_route(world, best)}/{summary.runs} runs", transform=ax.transAxes,
                ha="center", va="top", fontsize=7)
    fig.suptitle(f"{_task_title(study, experiment, task)}: most common final greedy route "
                 f"per method (optimal: areas {'->'.join(map(str, best))})", fontsize=10)
    stem = f"routes_{'robot_' if experiment == ROBOT_EXPERIMENT else ''}{slug(task)}"
    return save_all(fig, out_dir, stem, opts)


def robot_returns(study: Study, out_dir: Path, opts: FigureOptions = FigureOptions()
                  ) -> list[Path]:
    """Robot protocol: return (cumulative reward) per trial, mean over runs, 95% interval."""
    exp = ROBOT_EXPERIMENT
    if not study.has(exp):
        return []
    fig = Figure(figsize=(6.0, 3.8), layout="constrained")
    ax = fig.subplots()
    tasks = study.tasks(exp)
    _bands(ax, study, exp, 1, f"robot protocol, task {', '.join(tasks)}: mean, {INTERVAL} "
           "(unsmoothed)", markers=True, xlabel="trial",
           ylabel="return (cumulative reward) per trial")
    if len(tasks) == 1:
        ax.axhline(study.v_star(exp, tasks[0]), color="black", ls="--", lw=0.8,
                   label="V*")
    ax.legend(fontsize=7)
    return save_all(fig, out_dir, "robot_returns", opts)


def make_figures(out_dir: str | Path, opts: FigureOptions = FigureOptions(),
                 study: Study | None = None) -> list[Path]:
    """Every figure of an output folder into ``out_dir/figures``, drawn by two processes
    when the machine has two cores (:func:`_draw`)."""
    study = study or Study.open(out_dir)
    target = Path(out_dir) / "figures"
    jobs: list[tuple[Callable[..., list[Path]], dict]] = [
        (learning_curves, {}), (learning_curves, {"fraction_of_vstar": True})]
    jobs += [(learning_curves, {"experiment": exp}) for exp in study.uncovered]
    jobs += [(switch_curves, {}), (visit_heatmaps, {}), (task_routes, {})]
    if study.has(ROBOT_EXPERIMENT):  # its routes on its last task
        jobs.append((task_routes, {"experiment": ROBOT_EXPERIMENT,
                                   "task": study.tasks(ROBOT_EXPERIMENT)[-1]}))
    jobs.append((robot_returns, {}))
    return [path for paths in _draw(jobs, study, target, opts) for path in paths]


_JOBS: tuple = ()
"""What the drawing processes of :func:`_draw` draw (inherited when they fork)."""


def _draw(jobs: list, study: Study, target: Path, opts: FigureOptions) -> list[list[Path]]:
    """Each job's figure, in job order. On two or more cores two forked processes share
    the jobs (a full report's figures take several seconds of matplotlib); the study is
    loaded once, before the fork, and each figure is written by the process that draws
    it, so the files are the same either way."""
    global _JOBS
    if len(jobs) < 2 or (os.cpu_count() or 1) < 2 or mp.get_start_method(True) not in (
            None, "fork"):
        return [job(study, target, opts, **kw) for job, kw in jobs]
    _JOBS = (jobs, study, target, opts)
    try:
        with mp.get_context("fork").Pool(2) as pool:
            return pool.map(_draw_one, range(len(jobs)), chunksize=1)
    finally:
        _JOBS = ()


def _draw_one(i: int) -> list[Path]:
    job, kw = _JOBS[0][i]
    return job(*_JOBS[1:], **kw)
