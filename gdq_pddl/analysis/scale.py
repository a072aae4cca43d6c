"""Figure and REPORT.md of the scale experiment (:mod:`gdq_pddl.experiments.scale`):
each measure per building and per size over its buildings (the definitions:
``templates/scale.md.j2``)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import NullFormatter

from gdq_pddl.analysis.figures import method_colour, save_all
from gdq_pddl.analysis.writer import render, table_text
from gdq_pddl.experiments import scale
from gdq_pddl.learners import registry
from gdq_pddl.outputs import write_text

REFERENCE = registry.REFERENCE  # the method every other one is compared with, run by run
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")  # a building seed's, in every panel


def _names(results: list[scale.BuildingResult]) -> tuple[list[str], list[str]]:
    """Every method, and those compared with :data:`REFERENCE` (none when it did not run)."""
    names = registry.order(n for r in results for n in r.returns)
    return names, [n for n in names if n != REFERENCE] if REFERENCE in names else []


def _first_label(episodes: int) -> str:
    """What the early-learning measure averages over, in a run of ``episodes``."""
    first = scale.FIRST
    return f"first {first} episodes" if episodes > first else f"{episodes} episodes (all)"


def make_scale_report(results: list[scale.BuildingResult], runs: int, episodes: int, out: Path
                      ) -> list[Path]:
    """``scale.png``, ``scale.pdf`` and ``REPORT.md`` in ``out``; returns the paths."""
    return [*save_all(draw(results, episodes), out, "scale"),
            report(results, runs, episodes, out)]


def draw(results: list[scale.BuildingResult], episodes: int) -> Figure:
    """The figure: episodes to convergence, GDQ minus each other method in mean return over
    the first episodes (when GDQ ran) and env steps/s against size; each building its own
    marker, a line through each size's value over all its buildings."""
    names, others = _names(results)
    sizes = scale.by_size(results)
    seeds = list(dict.fromkeys(r.seed for r in results))
    fig = Figure(figsize=(15 if others else 10, 4.6))
    axes = fig.subplots(1, 3 if others else 2)
    ax, bx = axes[0], axes[-1]

    def panel(axis, name: str, i: int, n: int, value: Callable, whole: Callable,
              open_at: float | None = None) -> None:
        """One method in one panel: per building ``value(r) -> (y, err)``, over the size's
        buildings ``whole(group) -> y``; a None ``y`` is drawn open at ``open_at``."""
        colour, shift = method_colour(name), 10 ** (0.018 * (i - (n - 1) / 2))
        for r in results:
            y, err = value(r)
            marker = MARKERS[seeds.index(r.seed) % len(MARKERS)]
            x = r.positions * shift
            if y is None:
                axis.plot(x, open_at, marker, color=colour, fillstyle="none", ms=6)
            else:
                axis.errorbar(x, y, yerr=err, fmt=marker, color=colour, ms=5, capsize=2,
                              lw=0.8)
        ys = [whole(g) for g in sizes.values()]
        axis.plot([n_ * shift for n_ in sizes], [np.nan if y is None else y for y in ys],
                  "-", color=colour, lw=1.2, label=name)

    for i, name in enumerate(names):
        panel(ax, name, i, len(names), lambda r, m=name: (scale.convergence([r], m)[0], None),
              lambda g, m=name: scale.convergence(g, m)[0], open_at=episodes * (1.04 + 0.025 * i))
        panel(bx, name, i, len(names), lambda r, m=name: (scale.steps_per_s([r], m), None),
              lambda g, m=name: scale.steps_per_s(g, m))
    for j, name in enumerate(others):
        panel(axes[1], name, j, len(others),
              lambda r, m=name: scale.paired_interval(r, REFERENCE, m),
              lambda g, m=name: scale.paired_difference(g, REFERENCE, m)[0])
    ax.axhline(episodes, color="grey", lw=0.5, ls="--")
    ax.set_ylim(bottom=0, top=episodes * (1.08 + 0.025 * len(names)))
    ax.set(xscale="log", xlabel="positions", ylabel="episodes to convergence",
           title=f"open markers: not converged in {episodes} episodes")
    bx.set(xscale="log", yscale="log", xlabel="positions", ylabel="env steps / s (one core)")
    if others:
        cx = axes[1]
        cx.axhline(0, color="black", lw=0.6)
        cx.set(xscale="log", xlabel="positions",
               ylabel=f"{REFERENCE} minus method, mean return",
               title=f"{_first_label(episodes)}, paired runs (mean, 95% t-interval)")
        cx.set_yscale("symlog", linthresh=10)
        cx.legend(fontsize=8, title=f"{REFERENCE} minus", title_fontsize=8)
    handles = [Line2D([], [], color="grey", ls="none", marker=MARKERS[k % len(MARKERS)],
                          label=f"building seed {s}") for k, s in enumerate(seeds)]
    ax.legend(fontsize=8, loc="center left")
    bx.legend(handles=handles, fontsize=8, loc="lower left")
    for axis in axes:
        axis.set_xticks(list(sizes), [str(n) for n in sizes])
        axis.xaxis.set_minor_formatter(NullFormatter())
    fig.tight_layout()
    return fig


def report(results: list[scale.BuildingResult], runs: int, episodes: int, out: Path) -> Path:
    """REPORT.md: the definitions, the buildings, and a table per measure (a row per
    building and, in bold, per size over all its buildings; a column per method)."""
    names, others = _names(results)
    seeds = list(dict.fromkeys(r.seed for r in results))
    first = _first_label(episodes)
    groups = []
    for n, group in scale.by_size(results).items():
        groups += [(f"{r.positions} / seed {r.seed}", [r]) for r in group]
        groups += [(f"**{n} / all {len(group)}**", group)] if len(group) > 1 else []

    def table(columns: list[str], cell: Callable[[list[scale.BuildingResult], str], str]) -> str:
        return table_text([[label, *(cell(g, c) for c in columns)] for label, g in groups],
                          ["positions / building", *columns])

    def conv(group: list[scale.BuildingResult], name: str) -> str:
        med, n, total = scale.convergence(group, name)
        return f"{med:.0f} ({n}/{total})" if med is not None else f"> {episodes} (0/{total})"

    def diff(group: list[scale.BuildingResult], name: str) -> str:
        return "{:+.1f} ± {:.1f}".format(*scale.paired_difference(group, REFERENCE, name))

    buildings = table_text([[
        f"{r.positions} / seed {r.seed}", r.doors, f"{r.n_states} x {r.n_actions}",
        r.plan_length, r.step_limit, f"{r.r_max:g}", f"{r.v_ref:.1f}", f"{r.r_fail:g}",
        f"{r.threshold:.1f}", f"{r.context_s:.1f}"] for r in results], [
        "positions / building", "doors", "learner states x actions", "L", "step limit",
        "r_max", "V_ref", "R_fail", "threshold", "plan tables (s)"])
    tables = {"conv": table(names, conv), "diff": table(others, diff) if others else "",
              "first": table(names, lambda g, m: f"{scale.first_means(g, m).mean():.1f}"),
              "all": table(names, lambda g, m: format(np.concatenate(
                  [r.returns[m].mean(axis=1) for r in g]).mean(), ".1f")),
              "success": table(names, lambda g, m: format(np.mean(
                  [r.success[m][:, -100:].mean() for r in g]), ".2f")),
              "speed": table(names, lambda g, m: f"{scale.steps_per_s(g, m):,.0f}")}
    path = out / "REPORT.md"
    write_text(path, render("scale.md.j2", seeds=seeds, runs=runs, episodes=episodes,
                            window=scale.WINDOW, fraction=scale.FRACTION,
                            tolerance=f"{1 + scale.TOLERANCE:g}",
                            first=first, reference=REFERENCE, buildings=buildings,
                            tables=tables))
    return path
