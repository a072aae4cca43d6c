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
    ("truncated", lambda lines: lines[:-7], r"method 'Q-learning' has 233 episodes, "
     r"config.json says 240 \(3 runs x 80\)"),
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
