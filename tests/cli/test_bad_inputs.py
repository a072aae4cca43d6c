"""Hostile inputs, end to end: each is refused with one clear line, never in silence.

Every case runs through the command line (``gdq_pddl.cli.main`` in this process, so the
suite stays fast) and is handled when (issue 12): the exit status is non-zero, no
traceback is printed, and the message names the file, key or value at fault. The world
and dynamics cases also go through the API (``load_world``, ``PDDLInstance``), which must
raise the package's own error with the same names.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from gdq_pddl.errors import GdqError
from gdq_pddl.resources import data_file
from tests.cli.hostile import (
    FAST,
    KEYS_DYNAMICS,
    KEYS_PROBLEM,
    OFFICE,
    edit,
    pddl_files,
    pddl_run,
    refused,
)
from tests.helpers import cli

# --- world files -------------------------------------------------------------------------

CUT_P5 = edit(edit(OFFICE, '["p3", "p5"],', ""), '["p5", "p6"], ["p5", "p8"],', "")
GOAL_BEHIND_LOCKED = edit(edit(edit(
    OFFICE, "success = 0.6\nstuck = 0.4", "success = 0.0\nstuck = 0.0"),
    "success = 0.95\nstuck = 0.0", "success = 0.0\nstuck = 0.0"), '\n  ["p17", "p18"],', "")

WORLDS = {
    "misspelled-world-key": (edit(OFFICE, "navigation_success = 0.95", "navigation_sucess = 0.9"),
                             ["world.navigation_sucess", "navigation_success"]),
    "misspelled-table": (edit(OFFICE, "[world]", "[wrold]"), ["wrold"]),
    "misspelled-door-key": (edit(OFFICE, "success = 0.6\nstuck = 0.2", "sucess = 0.6"),
                            ["doors.d0.sucess"]),
    "misspelled-task-key": (edit(OFFICE, 'goal = "P3"\nirrelevant_areas = [1, 2, 3]',
                                 'goall = "P3"'), ["tasks.A.goall"]),
    "misspelled-cost-key": (edit(OFFICE, "stay = 1.0", 'stay = {dist = "normal", mean = 1, '
                                 "sdd = 1}"), ["costs.stay.sdd"]),
    "unknown-verb": (edit(OFFICE, "stay = 1.0", "wait = 1.0"), ["costs.wait"]),
    "r_max-nan": (edit(OFFICE, "r_max = 20.0", "r_max = nan"), ["world.r_max", "nan"]),
    "r_max-inf": (edit(OFFICE, "r_max = 20.0", "r_max = inf"), ["world.r_max", "inf"]),
    "r_max-negative": (edit(OFFICE, "r_max = 20.0", "r_max = -20.0"), ["world.r_max", "-20"]),
    "r_max-huge": (edit(OFFICE, "r_max = 20.0", "r_max = 1e300"), ["world.r_max"]),
    "cost-inf": (edit(OFFICE, "goto = 1.0", "goto = inf"), ["costs.goto", "inf"]),
    "cost-nan-in-table": (edit(OFFICE, "goto = 1.0", 'goto = {dist = "uniform", low = 1, '
                               "high = nan}"), ["costs.goto.high", "nan"]),
    "probability-nan": (edit(OFFICE, "success = 0.6\nstuck = 0.2", "success = nan"),
                        ["doors.d0.success", "nan"]),
    "navigation-nan": (edit(OFFICE, "navigation_success = 0.95", "navigation_success = nan"),
                       ["world.navigation_success"]),
    "step_limit-float": (edit(OFFICE, "step_limit = 20 ", "step_limit = 20.5 "),
                         ["world.step_limit", "20.5"]),
    "task-case-duplicate": (OFFICE + '\n[tasks.c]\nstart = "p3"\ngoal = "p5"\n',
                            ["tasks.c", "task C"]),
    "task-start-is-goal": (edit(OFFICE, 'start = "P3"\ngoal = "P1"', 'start = "P3"\ngoal = "p17"'),
                           ["tasks.E", "p17"]),
    "area-leading-zero": (edit(OFFICE, '1 = ["p0"', '01 = ["p0"'), ["areas.01"]),
    "area-zero": (edit(OFFICE, '1 = ["p0"', '0 = ["p0"'), ["areas.0"]),
    "forbidden-unknown-area": (edit(OFFICE, 'r_max = 20.0', 'r_max = 20.0\nforbidden_areas = [9]'),
                               ["world.forbidden_areas[0]", "9"]),
    "landmark-named-as-position": (edit(OFFICE, 'P1 = "p14"', 'p1 = "p14"'), ["landmarks.p1"]),
    "position-upper-case": (OFFICE.replace('"p0"', '"P0"'), ["world.positions[0]", "P0"]),
    "irrelevant-area-list": (edit(OFFICE, "irrelevant_areas = [1, 2, 3]\n",
                                  "irrelevant_areas = [[1]]\n"), ["tasks.A.irrelevant_areas"]),
    "position-cut-off": (CUT_P5, ["world.adjacency", "p5", "cut off"]),
    "goal-behind-locked-doors": (GOAL_BEHIND_LOCKED, ["tasks.A.goal", "p17", "d2", "d3"]),
}


@pytest.mark.parametrize("case", list(WORLDS))
def test_bad_world_file_is_refused_by_run(capsys, tmp_path, case):
    text, names = WORLDS[case]
    world = tmp_path / "w.toml"
    world.write_text(text, encoding="utf-8")
    code, out = cli(capsys, "run", "--world", world, "--task", "C", *FAST,
                    "--out", tmp_path / "o")
    refused(code, out, str(world), *names)
    assert not (tmp_path / "o" / "config.json").exists()


@pytest.mark.parametrize("case", list(WORLDS))
def test_bad_world_file_is_refused_by_the_api(tmp_path, case):
    from gdq_pddl.world import load_world

    text, names = WORLDS[case]
    world = tmp_path / "w.toml"
    world.write_text(text, encoding="utf-8")
    with pytest.raises(GdqError) as info:
        load_world(world)
    for name in (str(world), *names):
        assert name in str(info.value)


def test_the_goal_cut_off_by_locked_doors_is_refused_for_an_ad_hoc_task(capsys, tmp_path):
    text = GOAL_BEHIND_LOCKED.split("[tasks.A]")[0]  # no task of the file reaches p17
    world = tmp_path / "w.toml"
    world.write_text(text, encoding="utf-8")
    code, out = cli(capsys, "run", "--world", world, "--start", "p0", "--goal", "p17", *FAST,
                    "--out", tmp_path / "o")
    refused(code, out, str(world), "p17", "d2", "d3")
    from gdq_pddl.envs.office import OfficeEnv

    with pytest.raises(GdqError, match="p17"):
        OfficeEnv(world=world, start="p0", goal="p17")


@pytest.mark.parametrize(("limit", "names"), [
    ("7", ["world.step_limit", "7", "task C", "8 actions"]),
    ("2000000000", ["world.step_limit", "2000000000", "GB"]),
    ("99999999999999", ["world.step_limit", "99999999999999"]),
])
def test_step_limits_no_episode_or_no_memory_allows_are_refused(capsys, tmp_path, limit, names):
    world = tmp_path / "w.toml"
    world.write_text(edit(OFFICE, "step_limit = 20 ", f"step_limit = {limit} "), "utf-8")
    code, out = cli(capsys, "run", "--world", world, "--task", "C", *FAST,
                    "--out", tmp_path / "o")
    refused(code, out, str(world), *names)


def test_non_utf8_world_names_the_file(capsys, tmp_path):
    world = tmp_path / "latin1.toml"
    world.write_bytes(OFFICE.replace('"difficult"', '"schwierig \xe4"').encode("latin-1"))
    code, out = cli(capsys, "plan", "--world", world, "--task", "C")
    refused(code, out, str(world), "UTF-8")
    world.write_bytes(b"\x00\xff\xfe binary")
    code, out = cli(capsys, "run", "--world", world, "--task", "C", *FAST,
                    "--out", tmp_path / "o")
    refused(code, out, str(world))


# --- PDDL problems and dynamics files ---------------------------------------------------

PROBLEMS = {
    "goal-never-true": (edit(KEYS_PROBLEM, "(:goal (at c35))", "(:goal (key-at red c35))"),
                        ["problem.pddl", "(key-at red c35)", "never"]),
    "goal-room-cut-off": (edit(edit(edit(edit(KEYS_PROBLEM, "(adj c25 c35)", ""),
                                          "(adj c34 c35)", ""), "(adj c35 c34)", ""),
                               "(adj c35 c25)", ""), ["problem.pddl", "cannot be reached"]),
    "goal-empty": (edit(KEYS_PROBLEM, "(:goal (at c35))", "(:goal (and))"),
                   ["problem.pddl", "empty"]),
    "goal-two-formulas": (edit(KEYS_PROBLEM, "(:goal (at c35))", "(:goal (at c35) (at c34))"),
                          ["problem.pddl", ":goal"]),
    "empty-atom-in-init": (edit(KEYS_PROBLEM, "(at c11)", "(at c11) ()"),
                           ["problem.pddl:", "()"]),
    "no-init": (KEYS_PROBLEM[:KEYS_PROBLEM.index("  (:init")] + "  (:goal (at c35)))\n",
                ["problem.pddl", ":init"]),
}
GOAL_AT_START = edit(KEYS_PROBLEM, "(:goal (at c35))", "(:goal (at c11))")
DYNAMICS = {
    "r_max-nan": (edit(KEYS_DYNAMICS, "r_max = 20.0", "r_max = nan"), ["dynamics.r_max", "nan"]),
    "r_max-inf": (edit(KEYS_DYNAMICS, "r_max = 20.0", "r_max = inf"), ["dynamics.r_max", "inf"]),
    "r_max-negative": (edit(KEYS_DYNAMICS, "r_max = 20.0", "r_max = -1.0"),
                       ["dynamics.r_max", "-1"]),
    "cost-inf": (edit(KEYS_DYNAMICS, "[actions.pickup]\ncost = 1.0",
                      "[actions.pickup]\ncost = inf"),
                 ["actions.pickup.cost", "inf"]),
    "cost-table-nan": (edit(KEYS_DYNAMICS, "low = 2.0", "low = nan"),
                       ["actions.move.objects.c22.cost.low", "nan"]),
    "cost-table-unknown-key": (edit(KEYS_DYNAMICS, "low = 2.0", "lo = 2.0"),
                               ["actions.move.objects.c22.cost.lo", "unknown key"]),
    "success-nan": (edit(KEYS_DYNAMICS, "success = 0.95", "success = nan"),
                    ["actions.move.success", "nan"]),
    "failure-nested-list": (edit(KEYS_DYNAMICS, "success = 0.95", 'success = 0.95\nfailure = '
                                 '[["move"]]'), ["actions.move.failure"]),
    "step_limit-below-shortest-plan": (edit(KEYS_DYNAMICS, "step_limit = 25", "step_limit = 5"),
                                       ["dynamics.step_limit", "5", "8 actions"]),
}


@pytest.mark.parametrize("case", list(PROBLEMS))
def test_bad_problem_is_refused(capsys, tmp_path, case):
    from gdq_pddl.envs.pddl_env import PDDLInstance

    text, names = PROBLEMS[case]
    files = pddl_files(tmp_path, problem=text)
    code, out = pddl_run(capsys, tmp_path, files)
    refused(code, out, *names)
    assert not (tmp_path / "o" / "config.json").exists()
    with pytest.raises(GdqError) as info:
        PDDLInstance.from_files(*files).model  # noqa: B018
    assert all(n in str(info.value) for n in names)


@pytest.mark.parametrize("case", list(DYNAMICS))
def test_bad_dynamics_is_refused(capsys, tmp_path, case):
    text, names = DYNAMICS[case]
    files = pddl_files(tmp_path, dynamics=text)
    code, out = pddl_run(capsys, tmp_path, files)
    refused(code, out, str(files[2]), *names)


@pytest.mark.parametrize("which", [0, 1, 2])
def test_non_utf8_pddl_inputs_name_the_file(capsys, tmp_path, which):
    files = pddl_files(tmp_path)
    files[which].write_bytes(b"; \xe9t\xe9\n" + files[which].read_bytes())
    code, out = pddl_run(capsys, tmp_path, files)
    refused(code, out, str(files[which]), "UTF-8")


def test_plan_still_answers_no_plan_and_warns_on_an_empty_plan(capsys, tmp_path):
    d, p, _ = pddl_files(tmp_path, problem=GOAL_AT_START)
    code, out = cli(capsys, "plan", "--domain", d, "--problem", p)
    assert code == 0 and "warning" in out and "already holds" in out
    d, p, _ = pddl_files(tmp_path, problem=PROBLEMS["goal-never-true"][0])
    code, out = cli(capsys, "plan", "--domain", d, "--problem", p)
    assert code == 1 and "no plan" in out


# --- numbers in PDDL files ---------------------------------------------------------------

PPDDL_DOMAIN = data_file("domains", "keys-ppddl.pddl").read_text(encoding="utf-8")
PPDDL_PROBLEM = data_file("problems", "keys-ppddl-1.pddl").read_text(encoding="utf-8")
PICKUP = "(not (key-at ?k ?c)) (increase (total-cost) 1)))"
MOVE = "(probabilistic 0.95 (and (at ?to)"
MUD = "(= (move-cost c32 c22) 3.5)"
REWARD = "(:goal-reward 20)"


def _number_case(which: int, old: str, new: str, line: int, *names: str):
    """(domain text, problem text, the edited file's index, its line, what is named)."""
    texts = [PPDDL_DOMAIN, PPDDL_PROBLEM]
    texts[which] = edit(texts[which], old, new)
    return (*texts, which, line, names)


PDDL_NUMBERS = {
    "cost-past-a-float": _number_case(0, PICKUP, PICKUP.replace(" 1)", " 1e400)"), 36, "1e400",
                                      "at most 1e+15"),
    "cost-past-the-cap": _number_case(0, PICKUP, PICKUP.replace(" 1)", " 1e300)"), 36, "1e300"),
    "cost-written-at-length": _number_case(0, PICKUP, PICKUP.replace(" 1)", f" 1{'0' * 120})"),
                                           36, "121 characters"),
    "probability-exponent": _number_case(0, MOVE, MOVE.replace("0.95", "1e-99999999"), 31,
                                         "1e-99999999", "exponent"),
    "probability-written-at-length": _number_case(0, MOVE, MOVE.replace("0.95", "0." + "0" * 200
                                                                        + "95"), 31, "0.000"),
    "function-value-past-a-float": _number_case(1, MUD, MUD.replace("3.5", "1e400"), 94,
                                                "(move-cost c32 c22)", "1e400"),
    "function-value-past-the-cap": _number_case(1, MUD, MUD.replace("3.5", "1e300"), 94,
                                                "(move-cost c32 c22)", "1e300"),
    "function-value-exponent": _number_case(1, MUD, MUD.replace("3.5", "35e-99999999"), 94,
                                            "35e-99999999"),
    "cost-start-past-a-float": _number_case(1, "(at c11)", "(at c11) (= (total-cost) 1e400)", 10,
                                            "(total-cost)", "1e400"),
    "goal-reward-past-a-float": _number_case(1, REWARD, "(:goal-reward 1e400)", 103,
                                             ":goal-reward", "1e400"),
    "goal-reward-past-the-cap": _number_case(1, REWARD, "(:goal-reward 1e300)", 103,
                                             ":goal-reward", "1e300", "1e+300"),
    "goal-reward-largest-float": _number_case(1, REWARD, "(:goal-reward 1.7e308)", 103,
                                              "1.7e308"),
    "function-given-two-values": _number_case(1, MUD, MUD + " (= (move-cost c32 c22) 7)", 94,
                                              "(move-cost c32 c22)", "3.5 (line 94)", "7"),
}


def ppddl_files(tmp_path: Path, domain: str, problem: str) -> tuple[Path, Path]:
    files = (tmp_path / "domain.pddl", tmp_path / "problem.pddl")
    for path, text in zip(files, (domain, problem), strict=True):
        path.write_text(text, encoding="utf-8")
    return files


@pytest.mark.parametrize("case", list(PDDL_NUMBERS))
def test_pddl_numbers_past_the_limits_are_refused_at_their_line(capsys, tmp_path, case):
    from gdq_pddl.envs.pddl_env import PDDLInstance

    domain, problem, which, line, names = PDDL_NUMBERS[case]
    files = ppddl_files(tmp_path, domain, problem)
    where = f"{files[which]}:{line}: "
    t0 = time.perf_counter()
    code, out = cli(capsys, "run", "--domain", files[0], "--problem", files[1], *FAST,
                    "--out", tmp_path / "o")
    refused(code, out, where, *names)
    code, out = cli(capsys, "plan", "--domain", files[0], "--problem", files[1])
    refused(code, out, where, *names)
    with pytest.raises(GdqError) as info:
        PDDLInstance.from_files(*files)
    assert all(n in str(info.value) for n in (where, *names)), str(info.value)
    assert time.perf_counter() - t0 < 10  # 1e-99999999 as a fraction took minutes


def test_pddl_numbers_up_to_the_cap_are_read_and_repeated_values_are_one(tmp_path):
    from gdq_pddl.envs.pddl_env import PDDLInstance
    from gdq_pddl.limits import MAX_NUMBER

    cap = f"{int(MAX_NUMBER)}"
    problem = edit(edit(PPDDL_PROBLEM, REWARD, f"(:goal-reward {cap})"), MUD,
                   MUD + " (= (move-cost c32 c22) 7/2) (= (total-cost) 0)")
    files = ppddl_files(tmp_path, edit(PPDDL_DOMAIN, PICKUP, PICKUP.replace(" 1)", " 1e15)")),
                        problem)
    inst = PDDLInstance.from_files(*files)
    assert inst.dynamics.r_max == MAX_NUMBER
    assert inst.problem.problem.values["(move-cost c32 c22)"] == 3.5
    assert max(c.a for c in inst.costs) == MAX_NUMBER
    files[1].write_text(edit(PPDDL_PROBLEM, REWARD, f"(:goal-reward {int(MAX_NUMBER) + 1})"))
    with pytest.raises(GdqError, match=r"problem.pddl:103: .*1000000000000001"):
        PDDLInstance.from_files(*files)


# --- reality against the knowledge -------------------------------------------------------

KEYS_2 = data_file("problems", "keys-2.pddl").read_text(encoding="utf-8")
NO_MOVE = edit(KEYS_DYNAMICS, "success = 0.95", "success = 0.0")
RED_LOCK_NEVER = edit(KEYS_DYNAMICS, "success = 0.5\nstuck = 0.3", "success = 0.0\nstuck = 1.0")
NO_LOCK = edit(edit(KEYS_DYNAMICS, "[actions.unlock]\nsuccess = 0.9", "[actions.unlock]\n"
                    "success = 0.0"), "success = 0.5\nstuck = 0.3", "success = 0.0")
REALITY = {  # the knowledge has plans, but no episode can reach the goal
    "no-move-ever-works": (KEYS_PROBLEM, NO_MOVE, ["cannot be reached in reality",
                                                   "knowledge has plans", "8 actions",
                                                   "success = 0: actions.move"]),
    "no-lock-ever-opens": (KEYS_PROBLEM, NO_LOCK, ["cannot be reached in reality",
                                                  "actions.unlock"]),
    "the-way-that-works-is-past-the-step-limit": (
        KEYS_2, edit(RED_LOCK_NEVER, "step_limit = 25", "step_limit = 8"),
        ["dynamics.step_limit", "8 is less than", "in reality (9 actions",
         "shortest plan has 7"]),
}


@pytest.mark.parametrize("case", list(REALITY))
def test_a_goal_reality_cannot_reach_is_refused_naming_the_dynamics_file(capsys, tmp_path,
                                                                         case):
    import gymnasium

    from gdq_pddl.envs.pddl_env import PDDLEnv, PDDLInstance

    problem, dynamics, names = REALITY[case]
    files = pddl_files(tmp_path, problem=problem, dynamics=dynamics)
    code, out = pddl_run(capsys, tmp_path, files)
    refused(code, out, str(files[2]), *names)
    assert not (tmp_path / "o" / "config.json").exists()
    for build in (lambda: PDDLInstance.from_files(*files).model, lambda: PDDLEnv(*files),
                  lambda: gymnasium.make("gdq_pddl/PDDL-v0", domain=files[0],
                                         problem=files[1], dynamics=files[2])):
        with pytest.raises(GdqError) as info:
            build()
        assert all(n in str(info.value) for n in (str(files[2]), *names)), str(info.value)


@pytest.mark.parametrize(("problem", "dynamics", "steps"), [
    (KEYS_PROBLEM, RED_LOCK_NEVER, 8),  # the blue door: as short as the red one
    (KEYS_2, RED_LOCK_NEVER, 9),  # the blue door: longer than the red one's 7
    (KEYS_PROBLEM, edit(NO_MOVE, "success = 0.0", 'success = 0.0\nfailure = ["move"]'), 8),
])  # the last: every move fails, and slips into a random move, the intended one included
def test_reality_that_still_reaches_the_goal_runs(tmp_path, problem, dynamics, steps):
    from gdq_pddl.envs.pddl_env import PDDLInstance
    from gdq_pddl.envs.solve import reality_distances

    inst = PDDLInstance.from_files(*pddl_files(tmp_path, problem=problem, dynamics=dynamics))
    assert reality_distances(inst.model)[inst.graph.is_goal].min() == steps  # model built
