"""``gdq-pddl plan --figure FILE`` draws the plans on the office's map."""

from __future__ import annotations

import matplotlib.image

from tests.helpers import cli


def test_plan_figure_draws_the_plans(capsys, tmp_path):
    path = tmp_path / "plans.png"
    code, out = cli(capsys, "plan", "--task", "C", "--figure", path)
    assert code == 0 and "2 plan(s) of length 8" in out and f"figure: {path}" in out
    image = matplotlib.image.imread(path)
    assert image.shape[0] > 500 and image.shape[1] > 500


def test_plan_figure_is_refused_where_there_is_no_map(capsys, tmp_path):
    code, out = cli(capsys, "plan", "--problem", "keys-1", "--figure", tmp_path / "x.png")
    assert code == 2 and "--figure is for an office task" in out
    code, out = cli(capsys, "plan", "--task", "C", "--figure", tmp_path)
    assert code == 2 and "is a folder" in out
    assert not (tmp_path / "x.png").exists()
