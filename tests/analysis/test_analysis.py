"""The paper's figures, tables and report from a small synthetic experiment output folder
(tests/analysis/synthetic.py): verdicts that flip with the data, skipped sections,
OptInit values, routes; and the statistics, policy walks and config reading they rest
on. A run no paper section covers: test_run_report.py."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from gdq_pddl.analysis import figures, make_all, write_report
from gdq_pddl.analysis.figures import FigureOptions, make_figures
from gdq_pddl.analysis.stats import compare, first_positive, moving_average, verdict
from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.tables import area_table, make_tables
from gdq_pddl.envs.evaluate import walk_policy
from gdq_pddl.envs.render import MapPainter
from gdq_pddl.experiments.probes import optinit_values
from gdq_pddl.experiments.results import load_config
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import load_world
from tests.analysis.synthetic import (
    EPISODES,
    METHODS,
    ROBOT_METHODS,
    RUNS,
    SWITCH_AT,
    optimal_policy,
    plan_policy,
    write_output,
)


@pytest.fixture(scope="module")
def full(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[Path]]:
    out = write_output(tmp_path_factory.mktemp("full"))
    return out, make_all(out)


def _report_verdicts(text: str) -> dict[str, str]:
    return {m.group(2): m.group(3) for m in re.finditer(
        r"^\| (I|II|III) \| (.+?) \| \*\*(.+?)\*\* \|", text, re.M)}


def _code_verdicts(text: str) -> dict[str, str]:
    """The GDQ-code column of the verdict table."""
    return {m.group(2): m.group(3) for m in re.finditer(
        r"^\| (I|II|III) \| (.+?) \| \*\*.+?\*\* \| \*\*(.+?)\*\* \|", text, re.M)}


def test_episodes_load_into_run_by_episode_matrices(full):
    out, _ = full
    ep = Study.open(out)
    assert ep.experiments == ["robot", "switch-C-D", "switch-C-E", "tasks"]
    assert ep.methods("tasks") == list(METHODS)
    assert ep.tasks("switch-C-D") == ["C", "D"]
    m = ep.matrix("return", "tasks", "GDQ", "C")
    assert m.shape == (RUNS, EPISODES) and not np.isnan(m).any()
    assert ep.area_visits("tasks", "GDQ", "C").shape == (RUNS, EPISODES, 7)
    assert ep.matrix("return", "switch-C-E", "DARLING").shape == (RUNS, 2 * EPISODES)
    assert ep.matrix("return", "nope", "GDQ").size == 0
    assert Study.open(out).switch_episode("switch-C-D") == SWITCH_AT


def test_figures_are_written_as_png_and_pdf(full):
    _, paths = full
    pngs = [p for p in paths if p.suffix == ".png"]
    assert len(pngs) >= 6
    assert all(p.stat().st_size > 1000 for p in pngs)
    assert {p.with_suffix(".pdf") for p in pngs} <= set(paths)
    names = {p.stem for p in pngs}
    assert {"learning_curves", "switch_curves", "fraction_of_vstar", "heatmap_C",
            "routes_C", "robot_returns"} <= names


def test_bold_cells_are_the_minima_of_irrelevant_areas(full):
    out, _ = full
    table = area_table(Study.open(out))
    assert table.irrelevant_paper["D"] == (2, 5)
    assert table.irrelevant_computed["D"] == (2, 5, 6)
    for task in "ABCD":
        rows = table.frame.loc[task]
        irrelevant = set(table.irrelevant_paper[task]) | set(table.irrelevant_computed[task])
        for area in table.areas:
            lowest = rows[f"area_{area}_mean"].round(1).min()
            for method, r in rows.iterrows():
                expect = area in irrelevant and round(r[f"area_{area}_mean"], 1) == lowest
                assert r[f"area_{area}_bold"] == expect, (task, area, method)
        assert rows[[f"area_{a}_bold" for a in table.areas]].to_numpy().any()
    md = (out / "tables" / "area_visits.md").read_text()
    tex = (out / "tables" / "area_visits.tex").read_text()
    assert "**" in md and r"\mathbf" in tex and r"\toprule" in tex
    with (out / "tables" / "area_visits.csv").open() as f:
        assert len(list(csv.DictReader(f))) == 4 * len(METHODS)


def test_report_has_a_verdict_per_hypothesis_and_task(full):
    out, _ = full
    text = (out / "REPORT.md").read_text()
    verdicts = _report_verdicts(text)
    for task in "ABCD":
        assert verdicts[f"Task {task}"] == "holds"
        assert any(k.startswith(f"Task {task}, paper") for k in verdicts)
        assert any(k.startswith(f"Task {task}, computed") for k in verdicts)
    assert sum(k.startswith("switch-C-") for k in verdicts) == 2
    assert set(verdicts.values()) <= {"holds", "does not hold", "mixed"}
    assert "Welch p" in text and "95% CI" in text and "n = 2 vs 2 runs" in text
    assert "![learning curves" in text and "(figures/learning_curves.png)" in text
    assert "| GDQ | 2/2 (100%)" in text  # both GDQ runs' greedy route is 1->3->2->6
    assert "| Q-learning | 0/2 (0%)" in text
    assert "Dyna-Q reached the goal at least once within 30 trials in 0 of 2 runs" in text
    assert "Skipped" not in text
    assert "| robot | office_robot | X x 30 | GDQ, GDQ-literal, GDQ-code, Dyna-Q | 2 | 1 |" in text
    robot = text[text.index("## Robot protocol"):]
    assert all(f"| {m} | 2 |" in robot for m in ROBOT_METHODS)
    assert "V* = 900.0" in text  # read from optimal.json's X@office_robot


def test_verdict_flips_when_gdq_is_worse(tmp_path):
    out = write_output(tmp_path, worse_task="B", switches=False, robot=False)
    text = write_report(out).read_text()
    verdicts = _report_verdicts(text)
    assert verdicts["Task B"] == "does not hold"
    assert verdicts["Task A"] == "holds"


def test_missing_experiments_are_skipped_with_a_note(tmp_path):
    out = write_output(tmp_path, switches=False, robot=False)
    paths = make_figures(out, FigureOptions(formats=("png",), dpi=50))
    assert not any(p.stem in ("switch_curves", "robot_returns") for p in paths)
    assert make_tables(out)
    text = write_report(out).read_text()
    assert "Hypothesis III: skipped, no switch experiment" in text
    assert "Robot protocol: skipped, the robot experiment is missing" in text
    assert "Task C" in _report_verdicts(text)


def test_only_a_robot_run_still_reports(tmp_path):
    out = write_output(tmp_path)
    with (out / "episodes.csv").open() as f:
        rows = [r for r in csv.reader(f) if r[0] in ("experiment", "robot")]
    with (out / "episodes.csv").open("w", newline="") as f:
        csv.writer(f).writerows(rows)
    (out / "optimal.json").unlink()
    (out / "config.json").write_text("{}")
    text = write_report(out).read_text()
    assert "the tasks experiment (A-D) is missing" in text
    assert "## Robot protocol" in text


def test_bare_experiment_names_are_read_with_defaults(tmp_path):
    (tmp_path / "config.json").write_text(json.dumps(
        {"experiments": ["tasks", "robot"], "other": 1}))
    cfg = load_config(tmp_path)
    assert cfg.experiment("tasks") == {"name": "tasks"} and not cfg.planned()
    assert cfg.world_spec("tasks") == "office" and cfg.world_spec("robot") == "office_robot"
    assert load_config(tmp_path / "nowhere").world_spec("tasks") == "office"


def test_walking_policies_finds_the_routes():
    world = load_world()
    good = walk_policy(world, optimal_policy(world, "C"), "p0", "p17")
    assert good.reached_goal and good.areas(world) == (1, 3, 2, 6)
    short = walk_policy(world, plan_policy(world, "C"), "p0", "p17")
    assert short.reached_goal and short.areas(world) in {(1, 2, 6), (1, 3, 6)}
    assert walk_policy(world, {}, "p0", "p17").end == "no-policy"
    stay = {s: 0 for s in range(LearnerSpaces(world).n_states)}  # goto p0: no-op or loop
    assert not walk_policy(world, stay, "p0", "p17").reached_goal


def test_statistics():
    rng = np.random.default_rng(0)
    better = compare(rng.normal(5, 1, 10), rng.normal(0, 1, 10), "GDQ", "B")
    worse = compare(rng.normal(0, 1, 10), rng.normal(5, 1, 10), "GDQ", "B")
    same = compare(np.array([1.0, 1.0]), np.array([1.0, 1.0]), "GDQ", "B")
    assert better.outcome == "better" and better.ci_low > 0 and better.p < 0.05
    assert worse.outcome == "worse"
    assert same.outcome == "inconclusive"
    assert verdict([better, better]) == "holds"
    assert verdict([better, same]) == "mixed"
    assert verdict([better, worse]) == "does not hold"
    assert verdict([same]) == "does not hold"
    ma = moving_average(np.arange(1.0, 6.0), 2)
    assert np.isnan(ma[0]) and ma[1:].tolist() == [1.5, 2.5, 3.5, 4.5]
    assert first_positive(np.array([[-1.0, -1, 3, 3, -1]]), 2).per_run == (3.0,)
    assert np.isnan(first_positive(-np.ones((1, 10)), 3).on_mean_curve)


def test_gdq_code_verdict_flips_when_its_data_flip(tmp_path):
    out = write_output(tmp_path, worse_task="B", switches=False, robot=False,
                       worse_method="GDQ-code")
    text = write_report(out).read_text()
    code, paper = _code_verdicts(text), _report_verdicts(text)
    assert code["Task B"] == "does not hold" and code["Task A"] == "holds"
    assert paper["Task B"] == "holds"  # GDQ's data did not change
    assert "- **Task B, GDQ-code: does not hold**: GDQ-code " in text
    held_paper = sum(v == "holds" for v in paper.values())
    held_code = sum(v == "holds" for v in code.values())
    summary = re.search(r"^\*\*Summary\.\*\* GDQ, knowledge as a prior model \(`GDQ`\): "
                        r"(\d+) of (\d+) cases hold; "
                        r"authors'-code GDQ \(`GDQ-code`\): (\d+) of (\d+) cases hold\.$",
                        text, re.M)
    assert summary is not None
    assert (int(summary[1]), int(summary[3])) == (held_paper, held_code)
    assert int(summary[2]) == len(paper) == int(summary[4]) == len(code)


def test_why_section_reports_measured_optinit_values(full):
    out, _ = full
    text = (out / "REPORT.md").read_text()
    why = text[text.index("## Why the paper's GDQ read literally fails here"):
               text.index("## Robot protocol")]
    # the office: R_max 20, gamma 0.95 -> 20 / 0.05 = 400 and 0.95 * 400 = 380
    assert "R_max = 20, gamma = 0.95" in why and "R_max / (1 - gamma) = 400" in why
    assert "| GDQ-literal | 400 | 380 | 95 |" in why
    # GDQ: the return of a shortest plan (8 actions on Task C) if every action worked
    v8 = -sum(0.95 ** k for k in range(7)) + 0.95 ** 7 * 20
    assert f"| GDQ | {v8:.4g} | " in why
    assert "| GDQ-code | 20 | 0 | 95 |" in why
    # the step-limit shares come from episodes.csv (the fake GDQ mostly succeeds)
    rows = Study.open(out).rows("tasks", "GDQ")
    share = np.mean((rows["steps"] == 20) & (rows["success"] == 0))
    assert f"| GDQ | {share:.1%} |" in why


def test_optinit_values_follow_the_hyperparameters(tmp_path):
    out = write_output(tmp_path, switches=False, robot=False)
    config = json.loads((out / "config.json").read_text())
    for e in config["experiments"]:
        e["hyper"] = {"alpha": 0.1, "gamma": 0.9, "epsilon": 0.1}
    (out / "config.json").write_text(json.dumps(config))
    study = Study.open(out)
    init = optinit_values(study.config, "tasks", study.world("tasks"), study.task("tasks", "C"))
    assert init.gamma == 0.9 and init.r_max == 20.0
    greedy, median, _ = init.values["GDQ-literal"]
    assert greedy == pytest.approx(20 / 0.1) and median == pytest.approx(0.9 * 20 / 0.1)


def test_route_figure_and_table_use_the_same_most_common_route(tmp_path):
    out = write_output(tmp_path, switches=False, robot=False)
    world = load_world()
    # three runs of Q-learning: two take a shortest plan, one the optimal route
    with (out / "policies.csv").open() as f:
        rows = [r for r in csv.reader(f)]
    good, short = optimal_policy(world, "C"), plan_policy(world, "C")
    rows += [["tasks", "Q-learning", "C", 2, s, a] for s, a in good.items()]
    with (out / "policies.csv").open("w", newline="") as f:
        csv.writer(f).writerows(rows)
    study = Study.open(out)
    summary = study.route_summary("tasks", "Q-learning", "C")
    short_areas = walk_policy(world, short, "p0", "p17").areas(world)
    assert summary.runs == 3 and summary.count == 2 and summary.areas == short_areas
    assert summary.example.areas(world) == summary.areas
    drawn = []
    original = MapPainter.draw_route
    MapPainter.draw_route = lambda self, ax, positions, colour: drawn.append(tuple(positions))
    try:
        figures.task_routes(study, tmp_path / "figs", FigureOptions(formats=("png",), dpi=40))
    finally:
        MapPainter.draw_route = original
    by_method = dict(zip([m for m in study.methods("tasks")
                          if study.route_summary("tasks", m, "C")], drawn, strict=True))
    assert world.area_of  # routes are compared in area terms, as in the table
    text = write_report(out).read_text()
    for method, positions in by_method.items():
        s = study.route_summary("tasks", method, "C")
        assert positions == s.example.positions
        areas = "->".join(map(str, s.areas))
        assert re.search(rf"^\| {re.escape(method)} \| [^|]+ \| {re.escape(areas)} "
                         rf"\({s.end}, {s.count} runs?\) \|", text, re.M), method


def test_paper_experiments_get_no_methods_section(full):
    out, _ = full
    text = (out / "REPORT.md").read_text()
    assert "Methods compared" not in text
    assert text.count("**Summary.** GDQ, knowledge as a prior model (`GDQ`): ") == 1


def test_the_ground_truth_table_gives_the_goal_probabilities_beside_v_star(tmp_path):
    out = write_output(tmp_path, switches=False, robot=False)
    optimal = json.loads((out / "optimal.json").read_text())
    optimal["A"] |= {"goal_v_star_policy": 0.95, "goal_within_limit": 0.96,
                     "goal_no_limit": 1.0, "goal_no_limit_exact": True}
    (out / "optimal.json").write_text(json.dumps(optimal))
    make_all(out)
    text = (out / "REPORT.md").read_text()
    truth = text[text.index("## Ground truth"):]
    assert "| V* | goal: V*'s policy / no limit |" in truth
    assert re.search(r"^\| A \| .+? \| [\d.]+ \| 0\.950 / 1\.000 \|", truth, re.M)
    assert re.search(r"^\| B \| .+? \| [\d.]+ \| – \|", truth, re.M)


def test_a_report_of_fewer_runs_than_the_paper_says_so_first(tmp_path, monkeypatch):
    """`reproduce --quick` (3 runs) must not read as a failed reproduction: the report's
    first lines say it is a first look and what few runs do to the verdicts."""
    from gdq_pddl.analysis import report

    out = write_output(tmp_path, switches=False, robot=False)
    head = write_report(out).read_text().splitlines()[:6]
    note = next((line for line in head if line.startswith("**A first look")), None)
    assert note is not None, head
    assert f"{RUNS} runs**, of {EPISODES} episodes" in note and "little power" in note
    assert "not a failed reproduction" in note and "`gdq-pddl reproduce`" in note
    assert head.index(note) < next(i for i, h in enumerate(head) if h.startswith("**Summary"))
    assert "--quick" not in note  # not the quick protocol's size
    monkeypatch.setattr(report, "QUICK_SIZE", (EPISODES, RUNS))
    assert "(`gdq-pddl reproduce --quick`)" in write_report(out).read_text()
    monkeypatch.setattr(report, "PAPER_SIZE", (EPISODES, RUNS))  # as many runs as the paper
    assert "A first look" not in write_report(out).read_text()
