"""benchmarks/support_table.py: which files a folder gives, what constructs a domain's text
uses, and a measured row (slow: one ``gdq-pddl run``)."""

from __future__ import annotations

import argparse
import importlib.util
import shutil
import sys

import pytest

from tests.helpers import REPO_ROOT

SHIPPED = REPO_ROOT / "gdq_pddl" / "data"
_spec = importlib.util.spec_from_file_location("support_table",
                                               REPO_ROOT / "benchmarks" / "support_table.py")
support_table = sys.modules.setdefault("support_table", importlib.util.module_from_spec(_spec))
_spec.loader.exec_module(support_table)

COMBINED = """(define (domain flip)
  (:requirements :probabilistic-effects :rewards)
  (:predicates (on ?x) (thing ?x))
  (:action push :parameters (?x)
    :effect (and (decrease (reward) 1)
                 (forall (?y) (when (thing ?y) (probabilistic 1/2 (on ?y)))))))
(define (problem flip-1) (:domain flip) (:objects a b)
  (:init (thing a)) (:goal (on a)) (:goal-reward 5) (:metric maximize (reward)))
"""


def test_a_folder_gives_its_first_problem_with_domain_pddl(tmp_path):
    for name in ("domain.pddl", "p02.pddl", "p01.pddl"):
        source = {"domain.pddl": "lift.pddl", "p01.pddl": "lift-1.pddl",
                  "p02.pddl": "lift-2.pddl"}[name]
        folder = "domains" if name == "domain.pddl" else "problems"
        shutil.copy(SHIPPED / folder / source, tmp_path / name)
    case = support_table.find_case(str(tmp_path))
    assert (case.domain.name, case.problem.name) == ("domain.pddl", "p01.pddl")
    assert support_table.find_case(str(tmp_path / "p02.pddl")).problem.name == "p02.pddl"


def test_a_file_with_domain_and_problem_is_both_and_its_constructs_are_named(tmp_path):
    (tmp_path / "p01.pddl").write_text(COMBINED)
    case = support_table.find_case(str(tmp_path))
    assert case.domain == case.problem == tmp_path / "p01.pddl"
    assert support_table.constructs(case) == (
        "1 actions; probabilistic, when, forall, probabilistic under forall, "
        "reward effects, goal-reward")


def test_a_domain_the_reader_refuses_is_named_with_the_readers_line(tmp_path):
    (tmp_path / "p01.pddl").write_text(COMBINED.replace("(probabilistic 1/2 (on ?y))",
                                                        "(oneof (on ?y) (thing ?y))"))
    case = support_table.find_case(str(tmp_path))
    assert support_table.constructs(case).startswith("refused by the reader: ")
    assert "oneof" in support_table.constructs(case)


def test_a_folder_without_any_domain_or_problem_is_an_error(tmp_path):
    (tmp_path / "notes.pddl").write_text("; nothing defined here\n")
    with pytest.raises(SystemExit, match="no problem file"):
        support_table.find_case(str(tmp_path))


def test_a_folder_with_a_domain_and_no_problem_gets_a_row_of_its_constructs(tmp_path):
    """The IPPC-2006 blocksworld, tireworld and zenotravel: a domain published without
    its problems still says what it uses, and that it was not run."""
    (tmp_path / "domain.pddl").write_text(COMBINED.split("(define (problem")[0])
    case = support_table.find_case(str(tmp_path))
    assert (case.domain.name, case.problem) == ("domain.pddl", None)
    assert support_table.constructs(case) == (
        "1 actions; probabilistic, when, forall, probabilistic under forall, reward effects")
    args = argparse.Namespace(method=["Q-learning"], episodes=3, runs=1, seed=1, budget=1.0)
    assert support_table.measure(case, args) == ("not run: no problem file", "", 0.0)


def test_a_domain_beside_a_problems_folder_gives_its_first_problem(tmp_path):
    shutil.copy(SHIPPED / "domains" / "lift.pddl", tmp_path / "domain.pddl")
    (tmp_path / "problems").mkdir()
    for name, source in (("p02.pddl", "lift-2.pddl"), ("p01.pddl", "lift-1.pddl")):
        shutil.copy(SHIPPED / "problems" / source, tmp_path / "problems" / name)
    case = support_table.find_case(str(tmp_path))
    assert (case.domain, case.problem) == (tmp_path / "domain.pddl",
                                           tmp_path / "problems" / "p01.pddl")


def test_the_table_names_a_domain_without_problems_and_prints_no_command(tmp_path, capsys):
    (tmp_path / "domain.pddl").write_text(COMBINED.split("(define (problem")[0])
    out = tmp_path / "table.md"
    assert support_table.main([str(tmp_path), "--out", str(out)]) == 0
    text = out.read_text()
    assert f"| {tmp_path.name} | - | 1 actions; " in text
    assert "| not run: no problem file | - | - |" in text
    assert "gdq-pddl run" not in text


@pytest.mark.slow
def test_a_measured_row_reads_the_runs_output(tmp_path):
    (tmp_path / "p01.pddl").write_text(COMBINED)
    args = argparse.Namespace(method=["Q-learning"], episodes=3, runs=1, seed=1, budget=300.0)
    how, figures, wall = support_table.measure(support_table.find_case(str(tmp_path)), args)
    assert how.startswith("enumerated, ") and "V\\* " in how
    assert figures.startswith("Q-learning ") and "%)" in figures
    assert wall > 0
