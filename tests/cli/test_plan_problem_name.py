"""``--problem FILE:NAME`` (issue 22 item 1): one problem of a file that holds several,
its domain too (IPPC-2008's format) or not, for ``plan`` as for ``run``."""

import json

import pytest

from tests.cli.hostile import refused
from tests.helpers import cli

DOMAIN = """(define (domain switches) (:requirements :typing :probabilistic-effects)
  (:types switch) (:predicates (on ?s - switch))
  (:action flip :parameters (?s - switch) :precondition (not (on ?s))
    :effect (probabilistic 0.9 (on ?s))))
"""

PROBLEMS = """(define (problem one) (:domain switches) (:objects a - switch) (:init)
  (:goal (on a)))
(define (problem two) (:domain switches) (:objects a b - switch) (:init)
  (:goal (and (on a) (on b))))
"""


@pytest.fixture(params=["together", "apart"])
def files(request, tmp_path) -> tuple[list[str], str]:
    """The --domain option (none: the problem file holds it) and the problems' file."""
    if request.param == "together":
        (tmp_path / "all.pddl").write_text(DOMAIN + PROBLEMS)
        return [], str(tmp_path / "all.pddl")
    (tmp_path / "d.pddl").write_text(DOMAIN)
    (tmp_path / "p.pddl").write_text(PROBLEMS)
    return ["--domain", str(tmp_path / "d.pddl")], str(tmp_path / "p.pddl")


@pytest.mark.parametrize("name, length", [("one", 1), ("TWO", 2)])
def test_plan_picks_the_named_problem(capsys, files, name, length):
    domain, path = files
    code, out = cli(capsys, "plan", *domain, "--problem", f"{path}:{name}", "--json")
    assert code == 0, out
    shown = json.loads(out)
    assert shown["length"] == length and len(shown["plans"]) == length  # (flip a) first, or b


def test_plan_without_a_name_lists_the_problems(capsys, files):
    domain, path = files
    code, out = cli(capsys, "plan", *domain, "--problem", path)
    assert code == 2 and "has 2 problems (one, two): pick one by name" in out
    assert f"({path}:one)" in out and "Traceback" not in out
    code, out = cli(capsys, "plan", *domain, "--problem", f"{path}:three")
    assert code == 2 and "no problem named 'three' in this file (it has one, two)" in out


def test_run_reads_the_domain_from_the_problems_file(capsys, tmp_path):
    (tmp_path / "all.pddl").write_text(DOMAIN + PROBLEMS)
    code, out = cli(capsys, "run", "--problem", f"{tmp_path / 'all.pddl'}:two", "--episodes",
                    2, "--runs", 1, "--method", "Q-learning", "--no-report", "--jobs", 1,
                    "--out", tmp_path / "out")
    assert code == 0, out
    assert (tmp_path / "out" / "episodes.csv").read_text().count("\n") == 3  # header, 2


@pytest.mark.parametrize("second", ["one", "ONE"])
def test_two_problems_of_one_name_are_refused_naming_both_lines(capsys, tmp_path, second):
    """``FILE:one`` ran the first of two problems named one; without a name, the advice
    named that spelling. Both now say which lines hold the name twice (issue 38)."""
    (tmp_path / "d.pddl").write_text(DOMAIN)
    text = PROBLEMS.replace("(problem two)", f"(problem {second})")
    (tmp_path / "p.pddl").write_text(text)
    lines = [i for i, line in enumerate(text.splitlines(), 1) if "(define (problem" in line]
    for problem in (f"{tmp_path / 'p.pddl'}:one", str(tmp_path / "p.pddl")):
        code, out = cli(capsys, "plan", "--domain", tmp_path / "d.pddl", "--problem", problem)
        refused(code, out, "two problems are named 'one'", f"lines {lines[0]} and {lines[1]}")
        assert code == 2 and ":one)" not in out, out


def test_an_empty_problem_name_is_said_to_be_empty(capsys, tmp_path):
    (tmp_path / "d.pddl").write_text(DOMAIN)
    (tmp_path / "p.pddl").write_text(PROBLEMS)
    code, out = cli(capsys, "plan", "--domain", tmp_path / "d.pddl", "--problem",
                    f"{tmp_path / 'p.pddl'}:")
    refused(code, out, "name after", "is empty")
    assert code == 2 and "cannot be read" not in out


def test_the_advice_for_a_text_without_a_file_is_the_name():
    from gdq_pddl.errors import PDDLError
    from gdq_pddl.planning import PlanningProblem

    with pytest.raises(PDDLError, match=r"pick one by name \(its name, such as 'one'\)"):
        PlanningProblem.from_texts(DOMAIN, PROBLEMS)
    assert PlanningProblem.from_texts(DOMAIN, PROBLEMS, problem_name="two").problem.name == "two"
