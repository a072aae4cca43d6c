"""Outputs a person can read back: policies by name, PDDL runs with their learning curves
and milestones, no office columns in a PDDL run, `report` on old and new folders, and
the documented defaults taken from the code."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import pytest

from gdq_pddl.analysis.stats import first_positive
from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.writer import milestone_str
from gdq_pddl.cli import build_parser, main
from gdq_pddl.experiments import DEFAULT_METHODS
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import load_world
from tests.helpers import REPO_ROOT as ROOT

KEYS = ["--domain", str(ROOT / "domains" / "keys.pddl"),
        "--problem", str(ROOT / "problems" / "keys-1.pddl"),
        "--dynamics", str(ROOT / "gdq_pddl" / "data" / "dynamics" / "keys.toml")]
SMALL = ["--method", "GDQ-code", "Q-learning", "--episodes", "60", "--runs", "2",
         "--jobs", "1"]


def rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def pddl_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("pddl") / "out"
    assert main(["run", *KEYS, *SMALL, "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def office_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("office") / "out"
    assert main(["run", "--task", "C", *SMALL, "--out", str(out)]) == 0
    return out


def test_office_policies_name_states_and_actions(office_run):
    spaces = LearnerSpaces(load_world(None))
    policy = rows(office_run / "policies.csv")
    assert len(policy) == 2 * 2 * spaces.n_states
    for r in policy:
        assert r["state_name"] == spaces.state_name(int(r["state"]))
        assert r["action_name"] == spaces.action_name(int(r["action"]))
    assert {r["state_name"] for r in policy} >= {"p0", "p1 (door open)", "p1 (door closed)"}


def test_pddl_policies_name_states_and_actions(pddl_run):
    from gdq_pddl.envs.pddl_env import PDDLInstance

    instance = PDDLInstance.from_files(*KEYS[1::2])
    policy = rows(pddl_run / "policies.csv")
    assert len(policy) == 2 * 2 * instance.n_states
    for r in policy:
        s, a = int(r["state"]), int(r["action"])
        assert r["state_name"] == " ".join(sorted(instance.atoms(s)))
        assert r["action_name"] == instance.action_name(a)
    start = next(r for r in policy if r["state"] == "0")
    assert "(at c11)" in start["state_name"]
    assert re.fullmatch(r"\(\S+( \S+)*\)", start["action_name"])


def test_pddl_episodes_have_no_office_area_columns(pddl_run, office_run):
    with (pddl_run / "episodes.csv").open() as fh:
        header = next(csv.reader(fh))
    assert header == ["experiment", "method", "task", "run", "episode", "return", "steps",
                      "success"]
    with (office_run / "episodes.csv").open() as fh:
        assert [c for c in next(csv.reader(fh)) if c.startswith("area_")] == \
            [f"area_{k}" for k in range(1, 8)]


def test_pddl_run_has_the_learning_curves_and_the_milestones_table(pddl_run):
    assert (pddl_run / "figures" / "learning_curves_run.png").stat().st_size > 1000
    assert (pddl_run / "figures" / "learning_curves_run.pdf").exists()
    report = (pddl_run / "REPORT.md").read_text()
    assert "![learning curves, run](figures/learning_curves_run.png)" in report
    assert "| Method | runs | mean return (SE) | last 10% (SE) | success rate | " \
           "MA50 > 0 at episode |" in report
    ep = Study.open(pddl_run)
    for method in ("GDQ-code", "Q-learning"):
        line = next(x for x in report.splitlines() if x.startswith(f"| {method} |")
                    or x.startswith(f"| **{method}** |"))
        milestone = first_positive(ep.matrix("return", "run", method, "keys-1"), 50)
        assert line.endswith(f"| {milestone_str(milestone)} |")
    assert "GDQ-code - Q-learning" in report  # the comparisons, as the office gets them
    assert "shortest plan: 8 actions" in report


def test_report_redraws_old_and_new_pddl_folders(pddl_run, tmp_path, capsys):
    """An old folder: area columns of zeros in episodes.csv, no names in policies.csv."""
    old = tmp_path / "old"
    old.mkdir()
    for name in ("config.json", "optimal.json"):
        (old / name).write_bytes((pddl_run / name).read_bytes())
    episodes = rows(pddl_run / "episodes.csv")
    areas = [f"area_{k}" for k in range(1, 8)]
    with (old / "episodes.csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, [*episodes[0], *areas])
        writer.writeheader()
        writer.writerows({**r, **dict.fromkeys(areas, "0")} for r in episodes)
    with (old / "policies.csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, ["experiment", "method", "task", "run", "state", "action"],
                                extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows(pddl_run / "policies.csv"))
    for folder in (old, pddl_run):
        (folder / "REPORT.md").unlink(missing_ok=True)
        assert main(["report", str(folder)]) == 0
        assert "MA50 > 0 at episode" in (folder / "REPORT.md").read_text()
        assert (folder / "figures" / "learning_curves_run.png").exists()
    assert (old / "REPORT.md").read_text() == (pddl_run / "REPORT.md").read_text()


def test_report_still_reads_an_office_folder(office_run):
    assert main(["report", str(office_run)]) == 0
    assert "## Methods compared" in (office_run / "REPORT.md").read_text()


def run_defaults() -> dict:
    import argparse

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return vars(sub.choices["run"].parse_args([]))


def test_run_help_and_domains_doc_state_the_real_defaults(capsys):
    defaults = run_defaults()
    assert defaults["method"] == list(DEFAULT_METHODS)
    methods = " ".join(DEFAULT_METHODS)
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert f"(default: {methods};" in help_text
    assert f"default {defaults['episodes']})" in help_text
    doc = " ".join((ROOT / "docs" / "domains.md").read_text(encoding="utf-8").split())
    stated = re.search(r"By default `run` compares `([^`]*)` over (\d+) runs of (\d+) "
                       r"episodes", doc)
    assert stated, "docs/domains.md no longer states run's defaults"
    assert stated.group(1) == methods
    assert (int(stated.group(2)), int(stated.group(3))) == (defaults["runs"],
                                                             defaults["episodes"])
