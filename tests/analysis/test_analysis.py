"""Figures, tables and report from a small synthetic experiment output folder."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from gdq_pddl.abstraction import OfficeAbstraction, build_plan_table
from gdq_pddl.analysis import figures, make_all, write_report
from gdq_pddl.analysis.figures import FigureOptions, make_figures
from gdq_pddl.analysis.stats import compare, first_positive, moving_average, verdict
from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.tables import area_table, make_tables
from gdq_pddl.envs.evaluate import walk_policy
from gdq_pddl.envs.model import compile_model, full_state
from gdq_pddl.envs.render import MapPainter
from gdq_pddl.envs.solve import solve
from gdq_pddl.experiments.probes import optinit_values
from gdq_pddl.experiments.results import load_config
from gdq_pddl.planning import PlanningProblem, get_planner
from gdq_pddl.resources import domain_text
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import builtin_world, load_world
from gdq_pddl.world_types import World, office_problem

METHODS = ("GDQ", "GDQ-code", "DARLING", "Dyna-Q", "Q-learning")
ROBOT_METHODS = ("GDQ", "GDQ-literal", "GDQ-code", "Dyna-Q")  # robot_experiment's default
QUALITY = {"GDQ": 1.0, "GDQ-code": 0.9, "DARLING": 0.6, "Dyna-Q": 0.4, "Q-learning": 0.2}
V_STAR = {"A": 14.6, "B": 15.7, "C": 11.5, "D": 11.4, "E": 14.6}
RELEVANT = {"A": [2, 4, 6, 7], "B": [4, 7], "C": [1, 2, 3, 6], "D": [1, 3, 4, 7],
            "E": [4, 6, 7]}
PAPER_IRR = {"A": [1, 2, 3], "B": [1, 2, 3, 6], "C": [4, 5, 7], "D": [2, 5], "E": []}
ROUTE = {"A": [4, 7, 6], "B": [4, 7], "C": [1, 3, 2, 6], "D": [1, 3, 4, 7], "E": [6, 7, 4]}
RUNS, EPISODES = 2, 60
SWITCH_AT = EPISODES + 1
HEADER = ["experiment", "method", "task", "run", "episode", "return", "steps", "success",
          *[f"area_{k}" for k in range(1, 8)]]


def optimal_policy(world: World, task: str) -> dict[int, int]:
    """Learner policy from the true optimal policy at step 0 (only the local door open)."""
    model = compile_model(world)
    sol = solve(model, world.index[world.task(task).goal])
    spaces = LearnerSpaces(world)
    out = {}
    for s, (p, is_open) in enumerate(spaces.states):
        door = world.door_at.get(p)
        fs = full_state(world, p, frozenset({door.name}) if door and is_open else frozenset())
        out[s] = int(sol.policy[0, fs])
    return out


def plan_policy(world: World, task: str) -> dict[int, int]:
    """Learner policy: the first action of the first shortest graph plan from each state."""
    ab = OfficeAbstraction(world)
    problem = PlanningProblem.from_texts(domain_text(), office_problem(world, world.task(task)))
    table = build_plan_table(ab, problem, get_planner("graph"), ab.goal(world.task(task).goal))
    return {s: plans[0][0][1] for s in range(ab.n_states) if (plans := table.plans_from(s))}


def _episode(rng: np.random.Generator, q: float, episode: int, task: str, v_star: float,
             r_max: float, route_from: int) -> tuple[float, int, int, list[int]]:
    """One fake episode: return rising with quality ``q``; area visits on the task's route
    (off-route areas visited with a probability that falls with ``q``)."""
    level = -r_max + (v_star + r_max) * q * (1 - np.exp(-episode / 10))
    ret = float(level + rng.normal(0, r_max / 10))
    areas = [0] * 7
    for a in ROUTE[task] if episode >= route_from else RELEVANT[task]:
        areas[a - 1] += int(rng.integers(1, 3))
    for a in range(1, 8):
        if a not in RELEVANT[task] and rng.random() < (1.05 - q) * 0.8:
            areas[a - 1] += int(rng.integers(1, 4))
    success = int(ret > 0)
    return ret, sum(areas), success, areas


def write_output(out: Path, worse_task: str | None = None, switches: bool = True,
                 robot: bool = True, worse_method: str = "GDQ") -> Path:
    """A synthetic output folder; GDQ (and GDQ-code) are best unless ``worse_task`` makes
    ``worse_method`` worst there."""
    rng = np.random.default_rng(7)
    world, robot_world = load_world(), builtin_world("office_robot")
    out.mkdir(parents=True, exist_ok=True)
    rows: list[list] = []

    def quality(method: str, task: str) -> float:
        return 0.05 if method == worse_method and task == worse_task else QUALITY[method]

    def add(exp: str, method: str, task: str, run: int, ep: int, local: int, v: float,
            r_max: float, route_from: int) -> None:
        ret, steps, success, areas = _episode(rng, quality(method, task), local, task, v,
                                              r_max, route_from)
        rows.append([exp, method, task, run, ep, f"{ret:.3f}", steps, success, *areas])

    for method in METHODS:
        route_from = 20 if method.startswith("GDQ") else 10**6
        for task in "ABCD":
            for run in range(RUNS):
                for e in range(1, EPISODES + 1):
                    add("tasks", method, task, run, e, e, V_STAR[task], 20.0, route_from)
        if switches:
            for second in "DE":
                for run in range(RUNS):
                    for e in range(1, 2 * EPISODES + 1):
                        task = "C" if e < SWITCH_AT else second
                        local = e if task == "C" else e - SWITCH_AT + 1
                        add(f"switch-C-{second}", method, task, run, e, local,
                            V_STAR[task], 20.0, route_from)
    if robot:
        for method in ROBOT_METHODS:
            for run in range(RUNS):
                for e in range(1, 31):
                    if method.startswith("GDQ"):
                        ret, success = 900.0 - 600 * np.exp(-e / 5) + rng.normal(0, 20), 1
                        areas = [0, 2, 2, 0, 0, 2, 0] if e > 10 else [0, 1, 2, 0, 0, 2, 1]
                    else:
                        ret, success, areas = -1000.0 - rng.uniform(0, 200), 0, [0, 0, 3, 2,
                                                                                0, 0, 0]
                    rows.append(["robot", method, "X", run, e, f"{ret:.3f}", sum(areas),
                                 success, *areas])
    with (out / "episodes.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(HEADER)
        w.writerows(rows)

    policies: list[list] = []
    good, short = optimal_policy(world, "C"), plan_policy(world, "C")
    for method in METHODS:
        for run in range(RUNS):
            pol = good if method.startswith("GDQ") or (method == "DARLING" and run == 0) \
                else short
            policies += [["tasks", method, "C", run, s, a] for s, a in pol.items()]
    if robot:
        good_x = optimal_policy(robot_world, "X")
        for run in range(RUNS):
            policies += [["robot", "GDQ", "X", run, s, a] for s, a in good_x.items()]
            policies += [["robot", "GDQ-code", "X", run, s, a] for s, a in good_x.items()]
            policies += [["robot", "Dyna-Q", "X", run, s, 0] for s in good_x]
    with (out / "policies.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["experiment", "method", "task", "run", "state", "action"])
        w.writerows(policies)

    optimal = {t: {"v_star": V_STAR[t], "relevant_areas": RELEVANT[t],
                   "irrelevant_areas_paper": PAPER_IRR[t], "optimal_route_areas": ROUTE[t]}
               for t in "ABCDE"}
    # the runner's layout: one entry per experiment (tasks: one per task), versions
    entries = [{"name": "tasks", "schedule": [[t, EPISODES]], "methods": list(METHODS),
                "runs": RUNS, "world": "office", "seed": 1} for t in "ABCD"]
    entries += [{"name": f"switch-C-{t}", "schedule": [["C", EPISODES], [t, EPISODES]],
                 "methods": list(METHODS), "runs": RUNS, "world": "office", "seed": 1}
                for t in "DE" if switches]
    if robot:
        entries.append({"name": "robot", "schedule": [["X", 30]], "methods": list(ROBOT_METHODS),
                        "runs": RUNS, "world": "office_robot", "seed": 1})
        optimal["X@office_robot"] = {"v_star": 900.0, "relevant_areas": [2, 3, 6],
                                     "irrelevant_areas_paper": []}
    config = {"experiments": entries, "versions": {"gdq_pddl": "test"},
              "unknown_key": {"ignored": True}}
    (out / "optimal.json").write_text(json.dumps(optimal))
    (out / "config.json").write_text(json.dumps(config))
    return out


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


# --- an experiment no paper section covers (gdq-pddl run) ---------------------------

RUN_METHODS = ("Q-learning", "DARLING-code", "GDQ", "Dyna-Q", "DARLING", "GDQ-code")
RUN_QUALITY = {**QUALITY, "DARLING-code": 0.5}
RUN_RUNS, RUN_EPISODES = 3, 120


def write_run_output(out: Path, methods: tuple[str, ...] = RUN_METHODS) -> Path:
    """A synthetic ``gdq-pddl run --task C`` folder (experiment ``run``), laid out as the
    runner writes it."""
    rng = np.random.default_rng(11)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for method in methods:
        for run in range(RUN_RUNS):
            for e in range(1, RUN_EPISODES + 1):
                ret, steps, success, areas = _episode(rng, RUN_QUALITY[method], e, "C",
                                                      V_STAR["C"], 20.0, 10**6)
                rows.append(["run", method, "C", run, e, f"{ret:.3f}", steps, success,
                             *areas])
    with (out / "episodes.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(HEADER)
        w.writerows(rows)
    (out / "optimal.json").write_text(json.dumps(
        {"C": {"world": "office", "start": "p0", "goal": "p17", "v_star": V_STAR["C"],
               "relevant_areas": RELEVANT["C"], "irrelevant_areas_paper": PAPER_IRR["C"]}}))
    (out / "config.json").write_text(json.dumps(
        {"experiments": [{"name": "run", "schedule": [["C", RUN_EPISODES]],
                          "methods": list(methods), "runs": RUN_RUNS, "world": "office",
                          "seed": 0}], "versions": {"gdq_pddl": "test"}}))
    return out


def _methods_section(text: str) -> str:
    start = text.index("## Methods compared")
    end = text.find("\n## ", start + 1)
    return text[start:end if end >= 0 else None]


def _expected_row(returns: np.ndarray, success: np.ndarray, window: int = 50) -> str:
    """The section's table cells of one method, computed here with plain numpy."""
    runs, n = returns.shape
    tail = max(1, n // 10)
    means, lasts = returns.mean(axis=1), returns[:, n - tail:].mean(axis=1)

    def se(x: np.ndarray) -> float:
        return x.std(ddof=1) / np.sqrt(x.size)

    curve = returns.mean(axis=0)
    ma = np.convolve(curve, np.ones(window) / window, mode="valid")  # ends at episode k+w
    hits = np.flatnonzero(ma > 0)
    per_run = [np.flatnonzero(np.convolve(r, np.ones(window) / window, "valid") > 0)
               for r in returns]
    reached = [h[0] + window for h in per_run if h.size]
    milestone = (f"{hits[0] + window} ({np.mean(reached):.4g}; {len(reached)}/{runs})"
                 if hits.size else f"n/a (n/a; 0/{runs})")
    return (f"{runs} | {means.mean():.2f} ({se(means):.2f}) | {lasts.mean():.2f} "
            f"({se(lasts):.2f}) | {success.mean():.1%} | {milestone} |")


def _read_matrices(out: Path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Method -> (returns, success) as ``[runs, episodes]``, straight from the CSV."""
    cells: dict[str, dict[tuple[int, int], tuple[float, float]]] = {}
    with (out / "episodes.csv").open(newline="") as f:
        for r in csv.DictReader(f):
            cells.setdefault(r["method"], {})[(int(r["run"]), int(r["episode"]))] = (
                float(r["return"]), float(r["success"]))
    out_m = {}
    for method, c in cells.items():
        runs = sorted({k[0] for k in c})
        eps = sorted({k[1] for k in c})
        arr = np.array([[c[(r, e)] for e in eps] for r in runs])
        out_m[method] = (arr[..., 0], arr[..., 1])
    return out_m


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    out = write_run_output(tmp_path_factory.mktemp("run"))
    return out, write_report(out).read_text()


def test_run_experiment_gets_a_methods_section_with_numbers_from_the_csv(run_folder):
    out, text = run_folder
    section = _methods_section(text)
    assert "### run: task C" in section
    assert f"V* = {V_STAR['C']:.2f}" in section
    rows = re.findall(r"^\| (\*\*)?([A-Za-z-]+)(?:\*\*)? \| (\d+ \|.*)$", section, re.M)
    names = [name for _, name, _ in rows]
    # a row per method, in METHOD_ORDER (DARLING-code after DARLING)
    assert names == ["GDQ", "GDQ-code", "DARLING", "DARLING-code", "Dyna-Q", "Q-learning"]
    data = _read_matrices(out)
    for _, method, cells in rows:
        assert cells == _expected_row(*data[method]), method
    best = max(data, key=lambda m: data[m][0].mean(axis=1).mean())
    assert [name for b, name, _ in rows if b] == [best]


def test_methods_section_compares_each_gdq_variant_with_each_baseline(run_folder):
    out, text = run_folder
    section = _methods_section(text)
    data = _read_matrices(out)
    for variant in ("GDQ", "GDQ-code"):
        assert f"- **{variant}**, all episodes: {variant} " in section
        assert f"- **{variant}**, last 10% of episodes: {variant} " in section
        for baseline in ("DARLING", "DARLING-code", "Dyna-Q", "Q-learning"):
            for tail, expect in ((0, "all episodes"), (RUN_EPISODES - RUN_EPISODES // 10,
                                                      "last 10%")):
                a = data[variant][0][:, tail:].mean(axis=1)
                b = data[baseline][0][:, tail:].mean(axis=1)
                c = compare(a, b, variant, baseline)
                assert f"  - {c.describe()}" in section, (variant, baseline, expect)
    # the fake GDQ-code is far better than Q-learning; baselines are never tested as "a"
    assert re.search(r"GDQ-code - Q-learning = \+[\d.]+ .*: better", section)
    assert not any(f"{b} - " in section for b in ("DARLING", "Dyna-Q", "Q-learning"))


def test_a_folder_without_paper_experiments_gets_the_run_report(run_folder):
    _, text = run_folder
    assert text.startswith("# Run report\n")
    assert "no GDQ runs in the data" not in text and "**Summary.**" not in text
    assert "Welch's t-test (two-sided) and a percentile bootstrap 95% CI" in text
    assert "planner `?`; world `office`" in text  # what produced it, from config.json


def test_methods_section_without_gdq_says_so(tmp_path):
    out = write_run_output(tmp_path, methods=("DARLING", "DARLING-code", "Q-learning"))
    text = write_report(out).read_text()
    section = _methods_section(text)
    assert "No GDQ variant ran on this task: nothing to compare." in section
    assert re.findall(r"^\| (?:\*\*)?(DARLING-code|DARLING|Q-learning)", section, re.M) == [
        "DARLING", "DARLING-code", "Q-learning"]


def test_paper_experiments_get_no_methods_section(full):
    out, _ = full
    text = (out / "REPORT.md").read_text()
    assert "Methods compared" not in text
    assert text.count("**Summary.** GDQ, knowledge as a prior model (`GDQ`): ") == 1


@pytest.fixture(scope="module")
def real_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short real run (one for the tests below: each reads it, make_all rewrites it)."""
    from gdq_pddl.experiments import Experiment, run_experiments

    exp = Experiment("run", (("C", 60),), runs=2, methods=("GDQ-code", "Q-learning"))
    return run_experiments([exp], tmp_path_factory.mktemp("real"), jobs=1, progress=False)


def test_methods_section_on_a_real_run(real_run):
    out = real_run
    section = _methods_section(write_report(out).read_text())
    v_star = json.loads((out / "optimal.json").read_text())["C"]["v_star"]
    assert f"V* = {v_star:.2f}" in section
    assert "| **GDQ-code** | 2 |" in section or "| GDQ-code | 2 |" in section
    assert "  - GDQ-code - Q-learning = " in section


def test_a_run_experiment_gets_its_learning_curves_linked_from_the_report(real_run):
    out = real_run
    paths = make_all(out)
    assert out / "figures" / "learning_curves_run.png" in paths
    assert "![learning curves, run](figures/learning_curves_run.png)" in (
        out / "REPORT.md").read_text()
