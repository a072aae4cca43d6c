"""Figures that say what they mean (issue 39): the switch curves do not smooth across the
switch, the pairs heatmap has one colour scale for wins and losses, the area heatmaps mark
the irrelevant areas, the Q map does not paint the goal as the worst place, and a routes
panel with no arrow says why."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from gdq_pddl.analysis import figures
from gdq_pddl.analysis.figures import FigureOptions, _smooth
from gdq_pddl.analysis.pairs import Differences, heatmap, symmetric_top
from gdq_pddl.analysis.study import Study
from gdq_pddl.envs.evaluate import Route, RouteSummary
from gdq_pddl.envs.render import MapPainter
from gdq_pddl.experiments.pairs import PairRuns
from gdq_pddl.learners import office_task_context
from tests.analysis.synthetic import write_output


def test_smoothing_starts_again_at_the_switch() -> None:
    x = np.arange(1, 11)
    matrix = np.array([[0.0] * 5 + [10.0] * 5])
    across = _smooth(matrix, x, 4, None)
    apart = _smooth(matrix, x, 4, 6)
    assert across[0, 5] == pytest.approx(2.5)  # three episodes of the old task mixed in
    assert apart[0, 5] == 10.0 and apart[0, 4] == 0.0
    np.testing.assert_array_equal(apart[0, :5], 0.0)
    np.testing.assert_array_equal(apart[0, 5:], 10.0)
    assert _smooth(matrix, x, 1, 6) is matrix


def test_switch_figure_has_no_value_mixing_both_tasks(tmp_path) -> None:
    out = write_output(tmp_path)
    study = Study.open(out)
    seen = []
    original = figures._bands

    def spy(*args, **kwargs):
        seen.append(kwargs.get("restart"))
        return original(*args, **kwargs)

    figures._bands = spy
    try:
        figures.switch_curves(study, tmp_path / "f", FigureOptions(formats=("png",), dpi=30))
    finally:
        figures._bands = original
    switches = [study.switch_episode(e) for e in study.switch_experiments]
    assert seen and all(r is not None for r in seen)
    assert sorted(set(seen)) == sorted(set(switches))


def _pairs(means: list[float]) -> tuple[PairRuns, Differences]:
    positions = ("p0", "p1", "p2")
    pairs = ("a", "b")
    facts = {"a": {"start": "p0", "goal": "p1"}, "b": {"start": "p1", "goal": "p2"}}
    res = PairRuns(pairs, ("GDQ", "Q-learning"), np.zeros((2, 2, 1)), facts, {}, positions)
    m = np.array(means)
    diff = Differences("Q-learning", m, np.full(2, 0.01), m - 0.02, m + 0.02,
                       np.array(["loss" if v < 0 else "win" for v in means]))
    return res, diff


def test_pairs_heatmap_has_one_scale_for_wins_and_losses() -> None:
    res, diff = _pairs([-0.24, 22.3])
    ax = Figure().add_subplot()
    heatmap(ax, res, diff)
    image = ax.get_images()[0].get_array()
    loss, win = image[0, 1, :3], image[1, 2, :3]
    # a small loss is pale, a large win is deep: far from white against near white
    assert np.abs(1 - loss).sum() < 0.2 < np.abs(1 - win).sum()
    assert symmetric_top(np.array([[np.nan, -0.24], [22.3, np.nan]])) == 22.3
    assert symmetric_top(np.array([[np.nan]])) == 1.0
    assert symmetric_top(np.array([[-3.0, 2.0]])) == 3.0


def test_area_heatmap_marks_the_irrelevant_areas(tmp_path, office) -> None:
    study = Study.open(write_output(tmp_path, switches=False, robot=False))
    irrelevant = study.truth("tasks", "C").irrelevant_areas
    assert irrelevant
    painter = MapPainter(office)
    ax = Figure().add_subplot()
    painter.draw_map(ax, "#eeeeee", 80, ["black"] * len(office.positions), areas=True,
                     irrelevant=irrelevant)
    labels = [t.get_text() for t in ax.texts if t.get_text().startswith("area ")]
    marked = {int(t.split()[1]) for t in labels if "(irrelevant)" in t}
    assert marked == set(irrelevant)
    filled = [p for p in ax.patches if p.get_fill()]
    assert len(filled) == len(irrelevant)


def test_q_map_draws_the_goal_apart(office) -> None:
    painter = MapPainter(office)
    context = office_task_context(office, "C")
    q = np.full((context.n_states, context.n_actions), 5.0)
    q[:, 0] = 8.0
    ax = Figure().add_subplot()
    mapping = painter.draw_q(ax, q, goal="p17")
    stars = [c for c in ax.collections if c.get_label().startswith("goal")]
    assert len(stars) == 1
    assert mapping.norm.vmin == 8.0  # every position but the goal is worth 8 here
    # the goal is white, not the colour of the lowest value
    colours = ax.collections[0].get_facecolors()
    goal_index = office.positions.index("p17")
    np.testing.assert_allclose(colours[goal_index], (1.0, 1.0, 1.0, 1.0))


def test_empty_route_panel_says_why(tmp_path) -> None:
    study = Study.open(write_output(tmp_path, switches=False, robot=False))
    stuck = Route(("p0",), False, "stuck")
    summary = RouteSummary({0: stuck}, (), "stuck", 1, stuck)
    drawn = []
    original_summary, original_save = Study.route_summary, figures.save_all
    Study.route_summary = lambda self, exp, method, task: summary
    figures.save_all = lambda fig, *args, **kwargs: drawn.append(fig) or []
    try:
        figures.task_routes(study, tmp_path / "f", FigureOptions(formats=("png",), dpi=30))
    finally:
        Study.route_summary, figures.save_all = original_summary, original_save
    texts = [t.get_text() for ax in drawn[0].axes for t in ax.texts]
    said = [t for t in texts if t.startswith("no arrows")]
    assert len(said) == len(study.methods("tasks"))
    assert all("p0" in t and figures.EMPTY_ROUTE["stuck"] in t for t in said)
