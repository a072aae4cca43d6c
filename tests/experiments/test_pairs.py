"""``gdq-pddl pairs``: every cell recomputed from the raw units, resumable, jobs-independent."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from gdq_pddl.analysis.pairs import differences
from gdq_pddl.analysis.writer import number
from gdq_pddl.cli import main
from gdq_pddl.experiments import pairs as pairs_module
from gdq_pddl.experiments.pairs import PairRuns
from gdq_pddl.world import load_world

PAIRS = ("p3->p13", "p10->p0", "P1->P3")  # the last is task A, by its landmarks
SMALL = ["--pairs", " ".join(PAIRS), "--method", "GDQ", "DARLING", "--runs", "2",
         "--episodes", "20"]
CANONICAL = ["p3->p13", "p10->p0", "p14->p17"]  # the office's order: by start, then goal
T_975_DF1 = math.tan(math.pi * (0.975 - 0.5))  # Student's t with 1 df is Cauchy


def pairs_cli(out: Path, *extra: str, jobs: str = "1") -> int:
    return main(["pairs", *SMALL, "--jobs", jobs, "--out", str(out), *extra])


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("pairs") / "out"
    assert pairs_cli(out) == 0
    return out


def read_csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def unit_means(out: Path, pair: str, method: str) -> np.ndarray:
    """Per-run mean returns straight from the unit files."""
    key = pair.replace("->", "_to_")
    return np.array([np.load(out / "units" / f"pairs__{key}__{method}__run{r}.npz")["returns"]
                     .mean() for r in range(2)])


def test_all_pairs_sample_and_parse():
    office = load_world(None)
    everything = pairs_module.all_pairs(office)
    assert len(everything) == len(set(everything)) == 19 * 18
    assert pairs_module.parse_pairs(office, ["p10->p0, p3->p13", "P1->P3", "p3->p13"]) == \
        CANONICAL
    sample = pairs_module.sample_pairs(office, 5, seed=3)
    assert sample == pairs_module.sample_pairs(office, 5, seed=3)
    assert len(set(sample)) == 5 and set(sample) <= set(everything)
    assert sample == [p for p in everything if p in sample]


def test_the_command_writes_results_tables_figure_and_report(folder):
    for name in ("config.json", "runs.csv", "optimal.json", "REPORT.md", "tables/pairs.csv",
                 "tables/pairs.md", "figures/pairs.png", "figures/pairs.pdf"):
        assert (folder / name).stat().st_size > 0, name
    assert not (folder / "episodes.csv").exists()
    assert (folder / "figures" / "pairs.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = (folder / "REPORT.md").read_text()
    assert "](figures/pairs.png)" in report
    assert "p14->p17 (task A)" in report and "tasks A-D only" in report
    config = json.loads((folder / "config.json").read_text())
    assert [e["name"] for e in config["experiments"]] == ["pairs"] * 3
    assert [e["schedule"] for e in config["experiments"]] == [[[p, 20]] for p in CANONICAL]
    units = sorted(p.name for p in (folder / "units").glob("*.npz"))
    assert len(units) == 3 * 2 * 2
    assert set(np.load(folder / "units" / units[0]).files) == {"returns", "success"}


def plan_length(capsys, start: str, goal: str, *world: str) -> int:
    """The length ``gdq-pddl plan`` reports (what a user sees)."""
    capsys.readouterr()
    assert main(["plan", "--start", start, "--goal", goal, "--json", *world]) == 0
    return json.loads(capsys.readouterr().out)["length"]


def test_every_table_cell_is_recomputed_from_the_units(folder, capsys):
    from gdq_pddl.envs.solve import optimal_value

    office = load_world(None)
    rows = read_csv(folder / "tables" / "pairs.csv")
    assert [r["pair"] for r in rows] == CANONICAL
    md = (folder / "tables" / "pairs.md").read_text().splitlines()[2:]
    outcomes = []
    for row, md_row in zip(rows, md, strict=True):
        pair = row["pair"]
        start, goal = pair.split("->")
        assert float(row["v_star"]) == pytest.approx(
            optimal_value(office, office.resolve(start=start, goal=goal)), abs=1e-12)
        assert int(row["shortest_plan"]) == plan_length(capsys, start, goal)
        assert row["tuning"] == ("A" if pair == "p14->p17" else "")
        gdq, darling = unit_means(folder, pair, "GDQ"), unit_means(folder, pair, "DARLING")
        for name, x in (("GDQ", gdq), ("DARLING", darling)):
            assert float(row[f"mean_{name}"]) == pytest.approx(x.mean(), abs=1e-12)
            assert float(row[f"se_{name}"]) == pytest.approx(x.std(ddof=1) / np.sqrt(2),
                                                             abs=1e-12)
        d = gdq - darling  # paired: run r against run r
        mean, se = d.mean(), d.std(ddof=1) / np.sqrt(2)
        low, high = mean - T_975_DF1 * se, mean + T_975_DF1 * se
        assert float(row["diff_DARLING"]) == pytest.approx(mean, abs=1e-12)
        assert float(row["diff_se_DARLING"]) == pytest.approx(se, abs=1e-12)
        assert float(row["ci_low_DARLING"]) == pytest.approx(low, abs=1e-9)
        assert float(row["ci_high_DARLING"]) == pytest.approx(high, abs=1e-9)
        expected = "win" if low > 0 else "loss" if high < 0 else "tie"
        assert row["outcome_DARLING"] == expected
        outcomes.append(expected)
        cells = [c.strip() for c in md_row.strip("|").split("|")]
        assert cells[4:] == [f"{gdq.mean():.2f} ({gdq.std(ddof=1) / np.sqrt(2):.2f})",
                             f"{darling.mean():.2f} ({darling.std(ddof=1) / np.sqrt(2):.2f})",
                             f"{mean:+.2f} ({se:.2f}) {expected}"]
    # the summary: mean of the per-pair differences and the counts, as the report gives them
    report = (folder / "REPORT.md").read_text()
    diffs = [float(r["diff_DARLING"]) for r in rows]
    ses = [float(r["diff_se_DARLING"]) for r in rows]
    counts = [outcomes.count(o) for o in ("win", "tie", "loss")]
    line = (f"| DARLING | 3 | {np.mean(diffs):+.2f} ({np.sqrt(np.sum(np.square(ses))) / 3:.2f})"
            f" | {counts[0]} | {counts[1]} | {counts[2]} |")
    assert line in report
    untuned = [i for i, r in enumerate(rows) if not r["tuning"]]
    assert (f"| DARLING, excluding A-D | 2 | {np.mean([diffs[i] for i in untuned]):+.2f} "
            in report)


def test_runs_csv_holds_each_runs_exact_mean(folder):
    rows = read_csv(folder / "runs.csv")
    assert len(rows) == 3 * 2 * 2
    for r in rows:
        x = unit_means(folder, r["pair"], r["method"])[int(r["run"])]
        assert float(r["mean_return"]) == x  # repr round-trips exactly
        assert r["episodes"] == "20"


def test_resume_after_an_interrupt_gives_identical_results(folder, tmp_path, monkeypatch):
    from gdq_pddl.cli.__init__ import EXIT_INTERRUPTED

    real, ran = pairs_module.run_pair_unit, []

    def interrupted(unit):
        if len(ran) == 5:
            raise KeyboardInterrupt
        ran.append(unit.key)
        return real(unit)

    monkeypatch.setattr(pairs_module, "run_pair_unit", interrupted)
    cut = tmp_path / "cut"
    assert pairs_cli(cut) == EXIT_INTERRUPTED
    assert len(list((cut / "units").glob("*.npz"))) == 5 and not (cut / "runs.csv").exists()
    ran.clear()
    monkeypatch.setattr(pairs_module, "run_pair_unit", lambda u: ran.append(u.key) or real(u))
    assert pairs_cli(cut, "--resume") == 0
    assert len(ran) == 12 - 5  # only what was missing
    for name in ("runs.csv", "optimal.json", "tables/pairs.csv", "tables/pairs.md",
                 "REPORT.md"):
        assert (cut / name).read_bytes() == (folder / name).read_bytes(), name


def test_any_number_of_jobs_gives_identical_results(folder, tmp_path):
    two = tmp_path / "two"
    assert pairs_cli(two, jobs="2") == 0
    for name in ("runs.csv", "optimal.json", "tables/pairs.csv", "REPORT.md"):
        assert (two / name).read_bytes() == (folder / name).read_bytes(), name
    for path in (folder / "units").glob("*.npz"):  # the workers ran the pairs' unit too
        one, other = np.load(path), np.load(two / "units" / path.name)
        assert sorted(one.files) == sorted(other.files) == ["returns", "success"]
        assert all(np.array_equal(one[k], other[k]) for k in one.files)


def test_report_regenerates_a_pairs_folder(folder, tmp_path, capsys):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(folder, copy)
    shutil.rmtree(copy / "figures")
    shutil.rmtree(copy / "tables")
    (copy / "REPORT.md").unlink()
    assert main(["report", str(copy)]) == 0
    assert "REPORT.md" in capsys.readouterr().out
    for name in ("REPORT.md", "tables/pairs.csv", "tables/pairs.md"):
        assert (copy / name).read_bytes() == (folder / name).read_bytes(), name
    assert (copy / "figures" / "pairs.png").exists() and (copy / "figures" / "pairs.pdf").exists()


@pytest.mark.parametrize(("argv", "message"), [
    (["--pairs", "p3->p99"], "--pairs: p3->p99: office.toml (built in): unknown position 'p99'"),
    (["--pairs", "p3->p13 p4->p4"], "--pairs: p4->p4: start and goal are the same position (p4)"),
    (["--pairs", "p3-p13"], "--pairs: 'p3-p13' is not START->GOAL"),
    (["--pairs", "p3->p13", "--sample", "2"], "give --pairs or --sample, not both"),
    (["--sample", "400"], "--sample: 400 is not between 1 and 342"),
])
def test_bad_input_is_one_clear_line(capsys, tmp_path, argv, message):
    assert main(["pairs", *argv, "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"gdq-pddl: error: {message}"), err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "x").exists()


TINY = """
[world]
name = "tiny"
step_limit = 6
r_max = 10.0
positions = ["a", "b", "c", "d"]
adjacency = [["a", "b"], ["b", "c"], ["c", "d"]]

[doors.door]
sides = ["b", "c"]
success = 0.9
stuck = 0.0

[areas]
1 = ["a", "b"]
2 = ["c", "d"]

[tasks.C]
start = "d"
goal = "a"
"""


def test_a_world_file_gives_its_own_pairs(tmp_path, capsys):
    world = tmp_path / "tiny.toml"
    world.write_text(TINY, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["pairs", "--world", str(world), "--method", "GDQ", "Q-learning", "--runs", "2",
                 "--episodes", "5", "--jobs", "1", "--out", str(out)]) == 0
    rows = read_csv(out / "tables" / "pairs.csv")
    assert [r["pair"] for r in rows] == [f"{s}->{g}" for s in "abcd" for g in "abcd" if s != g]
    assert [r["pair"] for r in rows if r["tuning"]] == ["d->a"]  # its task C
    facts = json.loads((out / "optimal.json").read_text())
    for pair, f in facts.items():
        assert f["shortest_plan"] == plan_length(capsys, f["start"], f["goal"], "--world",
                                                 str(world)), pair
    report = (out / "REPORT.md").read_text()
    assert f"--world {world}" in report and "d->a (task C)" in report


def test_one_method_gives_a_table_and_no_comparison(tmp_path):
    out = tmp_path / "one"
    assert main(["pairs", "--pairs", "p3->p13", "--method", "Q-learning", "--runs", "2",
                 "--episodes", "5", "--jobs", "1", "--out", str(out)]) == 0
    assert read_csv(out / "tables" / "pairs.csv")[0].keys() >= {"mean_Q-learning", "v_star"}
    assert "nothing to compare" in (out / "REPORT.md").read_text()
    assert not (out / "figures" / "pairs.png").exists()


def runs_of(d: np.ndarray) -> PairRuns:
    """A PairRuns whose GDQ minus baseline is ``d[pair, run]`` (baseline all 0)."""
    means = np.stack([d, np.zeros_like(d)], axis=1)
    pairs = tuple(f"p{i}->q" for i in range(len(d)))
    facts = {p: {"start": f"p{i}", "goal": "q", "tuning": None} for i, p in enumerate(pairs)}
    return PairRuns(pairs, ("GDQ", "DARLING"), means, facts, {}, ())


def test_win_tie_loss_rule_on_hand_made_differences():
    d = np.array([[1.0, 1.1, 0.9], [-1.0, 1.0, 0.5], [-2.0, -2.1, -1.9], [3.0, 3.0, 3.0]])
    diff = differences(runs_of(d), "DARLING")
    assert list(diff.outcome) == ["win", "tie", "loss", "win"]
    t = 4.302652729911275  # t(0.975, 2 df)
    assert diff.low[0] == pytest.approx(1.0 - t * 0.1 / np.sqrt(3))
    single = differences(runs_of(d[:, :1]), "DARLING")  # one run: no interval
    assert list(single.outcome) == ["tie"] * 4 and np.isnan(single.se).all()
    assert number(float("nan")) == "n/a" and number(0.5, sign=True) == "+0.50"


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (4, 3), elements=st.floats(-50, 50)))
def test_swapping_the_two_methods_swaps_wins_and_losses(d):
    ahead = differences(runs_of(d), "DARLING")
    behind = differences(runs_of(-d), "DARLING")
    swap = {"win": "loss", "loss": "win", "tie": "tie"}
    assert [swap[o] for o in ahead.outcome] == list(behind.outcome)
    assert np.allclose(ahead.mean, -behind.mean) and np.allclose(ahead.se, behind.se)
    assert ((ahead.low <= ahead.mean) & (ahead.mean <= ahead.high)).all()
