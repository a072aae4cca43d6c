"""The command line: plans, problems, planners, and clear errors."""

from __future__ import annotations

import json

import pytest

from gdq_pddl.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize(("task", "length", "n_plans"),
                         [("A", 5, 1), ("B", 4, 1), ("C", 8, 2), ("D", 9, 3)])
def test_plan_lengths_and_plan_counts_of_the_paper_tasks(capsys, task, length, n_plans):
    code, out, _ = run(capsys, "plan", "--task", task, "--json")
    data = json.loads(out)
    assert code == 0
    assert data["length"] == length
    assert len(data["plans"]) == n_plans
    assert len({tuple(p["actions"]) for p in data["plans"]}) == n_plans


def test_plan_json_maps_each_step_to_a_learner_pair(capsys):
    code, out, _ = run(capsys, "plan", "--start", "p0", "--goal", "p17", "--json")
    plans = json.loads(out)["plans"]
    assert code == 0
    assert {p["learner"][0]["action"] for p in plans} == {"approach p1", "approach p2"}
    for p in plans:
        assert len(p["learner"]) == len(p["actions"])
        assert p["learner"][0]["state"] == "p0"


@pytest.mark.parametrize(("start", "goal", "length"), [("p17", "p14", 5), ("p3", "p5", 1),
                                                       ("p0", "p1", 1), ("P4", "P2", 9)])
def test_other_start_goal_pairs(capsys, start, goal, length):
    code, out, _ = run(capsys, "plan", "--start", start, "--goal", goal, "--json")
    assert code == 0 and json.loads(out)["length"] == length


def test_tolerance_adds_longer_plans(capsys):
    _, out, _ = run(capsys, "plan", "--task", "C", "--tolerance", "0.3", "--json")
    lengths = sorted({len(p["actions"]) for p in json.loads(out)["plans"]})
    assert lengths == [8, 9, 10]


def test_human_listing(capsys):
    code, out, _ = run(capsys, "plan", "--task", "C")
    assert code == 0
    assert "2 plan(s) of length 8" in out and "learner: p0 -> approach p2" in out


@pytest.mark.parametrize(("argv", "message"), [
    (["plan", "--start", "p0", "--goal", "p99"], "unknown position 'p99'"),
    (["plan", "--task", "Z"], "unknown task 'Z'"),
    (["plan", "--task", "C", "--planner", "nope"], "known: "),
    (["plan"], "give --task"),
    (["plan", "--start", "p3", "--goal", "p3"], "the same position"),
])
def test_bad_input_is_one_clear_message(capsys, argv, message):
    code, _, err = run(capsys, *argv)
    assert code == 2
    assert message in err and "Traceback" not in err


def test_malformed_domain_names_file_and_line(capsys, tmp_path):
    bad = tmp_path / "bad.pddl"
    bad.write_text("(define (domain office)\n  (:requirements :strips)\n  (:predicates (at ?p)\n")
    code, _, err = run(capsys, "plan", "--task", "C", "--domain", str(bad))
    assert code == 2
    assert f"{bad}:3: " in err and "never closed" in err


def test_unreachable_goal_is_a_no_plan_status(capsys, tmp_path):
    from gdq_pddl.resources import data_file

    problem = tmp_path / "cut.pddl"
    text = data_file("problems", "keys-1.pddl").read_text(encoding="utf-8")
    for edge in ("(adj c25 c35)", "(adj c34 c35)"):  # no way into the goal cell
        text = text.replace(edge, "")
    problem.write_text(text)
    code, out, err = run(capsys, "plan", "--domain", str(data_file("domains", "keys.pddl")),
                         "--problem", str(problem), "--json")
    assert code == 1
    assert json.loads(out)["status"] == "no-plan" and "no plan" in err


def test_a_world_with_a_position_cut_off_is_refused(capsys, tmp_path):
    world = tmp_path / "cut.toml"
    from gdq_pddl.resources import world_text

    text = world_text("office").replace('["p7", "p17"], ', "").replace('["p10", "p17"],', "")
    world.write_text(text.replace('["p17", "p18"],', ""))
    code, _, err = run(capsys, "plan", "--start", "p0", "--goal", "p17", "--world", str(world))
    assert code == 2
    assert f"{world}: world.adjacency: position(s) p17 cut off" in err


def test_problem_command_writes_the_shipped_file(capsys):
    from gdq_pddl.resources import problem_text

    code, out, _ = run(capsys, "problem", "--task", "D")
    assert code == 0 and out == problem_text("D")
    code, out, _ = run(capsys, "problem", "--start", "p3", "--goal", "p13")
    assert "(at p3)" in out and "(:goal (at p13))" in out


def test_planners_lists_the_builtin_backends(capsys):
    code, out, _ = run(capsys, "planners", "--json")
    names = {p["name"]: p for p in json.loads(out)}
    assert code == 0
    assert {"graph", "pyperplan", "clingo"} <= names.keys()
    assert names["graph"]["usable"] is True
    assert all(set(p) == {"name", "usable", "reason"} for p in names.values())
