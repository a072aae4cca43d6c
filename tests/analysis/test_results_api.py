"""``gdq_pddl.load_results``: the tidy DataFrame, its checks against config.json, any
number of areas, and the interquartile mean over tasks with stratified bootstrap CIs."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats as sps

import gdq_pddl
from gdq_pddl.analysis import make_all
from gdq_pddl.analysis.stats import iqm_ci
from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.tables import area_table
from gdq_pddl.cli import main
from gdq_pddl.errors import ResultsError
from gdq_pddl.experiments.results import load_results

METHODS = ("GDQ", "Q-learning")
RUNS, EPISODES = 3, 40


def write_folder(out: Path, tasks: tuple[str, ...] = ("C",), areas: int = 7,
                 v_star: float = 10.0, planner: str = "graph") -> Path:
    """A ``gdq-pddl run``-like folder: experiment ``run``, ``tasks`` one after another
    (one config entry per task), ``areas`` area columns (0: none, as a PDDL problem)."""
    rng = np.random.default_rng(3)
    out.mkdir(parents=True, exist_ok=True)
    header = ["experiment", "method", "task", "run", "episode", "return", "steps", "success",
              *[f"area_{k}" for k in range(1, areas + 1)]]
    rows = []
    for task in tasks:
        for m in METHODS:
            level = 8.0 if m == "GDQ" else -5.0
            for run in range(RUNS):
                for e in range(1, EPISODES + 1):
                    visits = [int(rng.integers(0, 3)) for _ in range(areas)]
                    rows.append(["run", m, task, run, e, f"{level + rng.normal():.3f}", 5,
                                 int(level > 0), *visits])
    with (out / "episodes.csv").open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)
    (out / "config.json").write_text(json.dumps({"experiments": [
        {"name": "run", "schedule": [[t, EPISODES]], "methods": list(METHODS), "runs": RUNS,
         "world": "office", "seed": 0, "planner": planner} for t in tasks]}))
    (out / "optimal.json").write_text(json.dumps({t: {"v_star": v_star} for t in tasks}))
    return out


def test_load_results_is_one_row_per_episode_with_the_documented_columns(tmp_path):
    out = write_folder(tmp_path / "o")
    df = gdq_pddl.load_results(out)
    assert gdq_pddl.load_results is load_results
    assert isinstance(df, pd.DataFrame) and len(df) == len(METHODS) * RUNS * EPISODES
    assert list(df.columns[:8]) == ["experiment", "method", "task", "run", "episode", "return",
                                    "steps", "success"]
    assert {df[c].dtype.name for c in ("experiment", "method", "task")} == {"category"}
    assert {df[c].dtype.name for c in ("run", "episode", "steps", "success")} == {"int64"}
    assert df["return"].dtype == np.float64
    assert df.equals(load_results(out / "episodes.csv"))  # the folder or the file
    means = df.groupby("method", observed=True)["return"].mean()
    assert means["GDQ"] > 0 > means["Q-learning"]


def test_any_number_of_area_columns_is_read_and_reported(tmp_path):
    out = write_folder(tmp_path / "o", areas=9)
    df = load_results(out)
    assert [c for c in df.columns if c.startswith("area_")] == [f"area_{k}" for k in
                                                                range(1, 10)]
    study = Study.open(out)
    assert study.areas == tuple(range(1, 10)) and study.has_areas("run")
    assert study.area_visits("run", "GDQ", "C").shape == (RUNS, EPISODES, 9)
    totals = study.area_visits("run", "GDQ", "C").sum(axis=1)
    assert totals[:, 8].tolist() == df[(df.method == "GDQ")].groupby("run")["area_9"].sum(
        ).tolist()


def test_a_folder_without_area_columns_has_no_areas(tmp_path):
    out = write_folder(tmp_path / "o", areas=0)
    study = Study.open(out)
    assert study.areas == () and not study.has_areas("run")
    assert study.task("run", "C") is None  # no map: nothing is looked up in a world
    assert area_table(study).frame.empty


def _rewrite(path: Path, change) -> None:
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(change(lines)))


@pytest.mark.parametrize(("name", "change", "message"), [
    ("truncated", lambda lines: lines[:-7], r"experiment 'run' \(D x 40\), method "
     r"'Q-learning', run 2 has 33 episodes, config.json says 40"),
    ("duplicated", lambda lines: [*lines, lines[5]], r"line 482 repeats an episode "
     r"\(experiment run, method GDQ, task C, run 0, episode 5\)"),
    ("renamed", lambda lines: [lines[0]] + [line.replace(",Q-learning,", ",Dyna-Q,")
                                            for line in lines[1:]],
     r"method 'Dyna-Q' of experiment 'run' was never run \(config.json: 'run' ran GDQ, "
     r"Q-learning\)"),
    ("run beyond", lambda lines: [lines[0]] + [line.replace(",C,2,", ",C,7,")
                                               for line in lines[1:]],
     r"run 7 of experiment 'run', config.json says 3 runs"),
])
def test_results_that_contradict_the_config_are_refused(tmp_path, capsys, name, change,
                                                        message):
    out = write_folder(tmp_path / "o", tasks=("C", "D"))
    assert len(load_results(out)) == 2 * len(METHODS) * RUNS * EPISODES  # as written: fine
    _rewrite(out / "episodes.csv", change)
    with pytest.raises(ResultsError, match=message) as err:
        load_results(out)
    assert str(err.value).startswith(str(out / "episodes.csv"))
    assert main(["report", str(out)]) == 2
    text = capsys.readouterr().err
    assert text.count("\n") == 1 and "Traceback" not in text and str(out) in text
    assert not (out / "REPORT.md").exists()
    assert len(load_results(out, check=False))  # the unchecked read still works


def _cells(line: str, **change) -> str:
    """A CSV line of episodes.csv with some of its first five cells changed."""
    cells = line.rstrip("\n").split(",")
    for name, value in change.items():
        cells[("experiment", "method", "task", "run", "episode").index(name)] = str(value)
    return ",".join(cells) + "\n"


def _moved(lines: list[str]) -> list[str]:
    """Run 0's last episode of task C (GDQ) moved to run 1 as its 41st: 39 and 41."""
    i = next(i for i, line in enumerate(lines) if line.startswith("run,GDQ,C,0,40,"))
    return lines[:i] + [_cells(lines[i], run=1, episode=41)] + lines[i + 1:]


@pytest.mark.parametrize(("change", "message"), [
    (lambda lines: lines[:5] + [_cells(lines[5], episode=99999)] + lines[6:],
     r"line 6: episode 99999 of experiment 'run', task 'C', run 0: config.json schedules "
     r"episodes 1 to 40 of it"),
    (_moved, r"line \d+: episode 41 of experiment 'run', task 'C', run 1: config.json "
             r"schedules episodes 1 to 40"),
    (lambda lines: lines[:5] + [_cells(lines[5], task="E")] + lines[6:],
     r"line 6: task 'E' of experiment 'run' was never scheduled \(config.json: 'run' "
     r"scheduled C, D\)"),
    (lambda lines: [*lines, _cells(lines[5], task="E")],
     r"line 482: task 'E' of experiment 'run' was never scheduled"),
    (lambda lines: [*lines, _cells(lines[5], experiment="other")],
     r"line 482: method 'GDQ' of experiment 'other' was never run"),
])
def test_every_row_is_checked_against_the_config(tmp_path, change, message):
    """An episode outside its run's schedule, a row moved to another run, a task the run
    never scheduled (in place of another, or added): refused naming the line."""
    out = write_folder(tmp_path / "o", tasks=("C", "D"))
    _rewrite(out / "episodes.csv", change)
    with pytest.raises(ResultsError, match=message) as err:
        load_results(out)
    assert str(err.value).startswith(str(out / "episodes.csv"))


def test_a_missing_episode_names_its_run(tmp_path):
    """A row deleted: the run short of an episode is named, with the config's count."""
    out = write_folder(tmp_path / "o")
    _rewrite(out / "episodes.csv", lambda lines: [line for line in lines
                                                  if not line.startswith("run,GDQ,C,1,17,")])
    with pytest.raises(ResultsError, match=r"experiment 'run' \(C x 40\), method 'GDQ', run "
                                           r"1 has 39 episodes, config.json says 40"):
        load_results(out)


@pytest.mark.parametrize(("content", "key"), [
    ("{not json", "not JSON"), ("[1, 2]", "a JSON list"), ('{"experiments": 3}', "experiments"),
    ('{"experiments": [{"name": "run", "schedule": [["C", 40]], "methods": ["GDQ"]}]}',
     "experiments[0].runs is 'missing'"),
    ('{"experiments": [{"name": "run", "schedule": [["C", "x"]], "methods": ["GDQ"], '
     '"runs": 3}]}', "experiments[0].schedule"),
    ('{"experiments": [{"name": "run", "schedule": [["C", 40]], "methods": "GDQ", '
     '"runs": 3}]}', "experiments[0].methods"),
    ('{"experiments": [7]}', "experiments[0] is 7"),
])
def test_a_damaged_config_is_refused_not_ignored(tmp_path, capsys, content, key):
    """A config.json that cannot be read turned every check off: now it is refused, by
    load_results and report, naming the file and the key."""
    out = write_folder(tmp_path / "o")
    (out / "config.json").write_text(content)
    with pytest.raises(ResultsError, match="damaged") as err:
        load_results(out)
    assert str(out / "config.json") in str(err.value) and key in str(err.value)
    assert main(["report", str(out)]) == 2
    text = capsys.readouterr().err
    assert text.count("\n") == 1 and key in text and "Traceback" not in text


def test_report_on_a_killed_run_says_how_to_finish_it(tmp_path, capsys):
    """A run killed before it wrote episodes.csv: config.json and some units."""
    out = write_folder(tmp_path / "o")
    (out / "episodes.csv").unlink()
    (out / "units").mkdir()
    (out / "units" / "run__C__GDQ__run0.npz").write_bytes(b"")
    assert main(["report", str(out)]) == 2
    text = capsys.readouterr().err
    assert "did not finish" in text and "1 of 6 runs saved" in text and "--resume" in text
    with pytest.raises(ResultsError, match="did not finish"):
        load_results(out)


def test_iqm_is_the_mean_of_the_middle_half():
    x = np.array([0.0, 1, 2, 3, 4, 5, 6, 100])
    assert iqm_ci([x[:3], x[3:]])[0] == pytest.approx(np.mean([2, 3, 4, 5]))


def test_iqm_interval_resamples_runs_within_each_task():
    # every task's runs are identical: a stratified bootstrap draws every task's runs from
    # that task only, so each resample has the same scores and the interval is a point;
    # resampling the pooled runs would mix the tasks and give a wide interval
    scores = [np.full(5, 0.0), np.full(5, 1.0), np.full(5, 2.0), np.full(5, 10.0)]
    point, low, high = iqm_ci(scores)
    assert point == pytest.approx(sps.trim_mean(np.concatenate(scores), 0.25))
    assert low == pytest.approx(point) and high == pytest.approx(point)
    rng = np.random.default_rng(0)
    noisy = [rng.normal(mu, 1.0, 10) for mu in (0.0, 1.0, 2.0, 3.0)]
    point, low, high = iqm_ci(noisy)
    assert low < point < high and high - low < 1.5
    assert np.isnan(iqm_ci([np.array([1.0]), np.array([2.0, 3.0])])[1])  # a single run


def test_a_run_over_several_tasks_reports_the_iqm(tmp_path):
    out = write_folder(tmp_path / "o", tasks=("C", "D", "E"), areas=0)
    make_all(out)
    text = (out / "REPORT.md").read_text()
    assert "**Over the 3 tasks** (C, D, E)" in text
    study = Study.open(out)
    scores = [study.returns("run", "GDQ", t).mean(axis=1) / 10.0 for t in "CDE"]
    point, low, high = iqm_ci(scores)
    assert f"| GDQ | 3 | {point:.2f} | [{low:.2f}, {high:.2f}] |" in text


@pytest.mark.parametrize("planner", ["graph", "pyperplan"])
def test_the_report_names_the_planner_and_warns_of_one_plan_backends(tmp_path, planner):
    out = write_folder(tmp_path / "o", areas=0, planner=planner)
    make_all(out)
    text = (out / "REPORT.md").read_text()
    kind = "every shortest plan" if planner == "graph" else "one plan"
    assert f"Planner `{planner}` ({kind} per query); DARLING and GDQ-code use the plans " \
           "within (1 + 0.3) x the shortest" in text
    assert ("**Warning:** `pyperplan` returns one plan per query" in text) == (
        planner == "pyperplan")
