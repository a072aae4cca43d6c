"""The graded exercises: each grader passes the reference solution, fails the stub and a
plausible wrong answer (with a hint that names the slip); the reference solutions compute
what the learners compute; the command lists, writes the stubs and grades with exit 0, 1
and 2."""

from __future__ import annotations

import importlib
import inspect

import numpy as np
import pytest

from gdq_pddl.exercises import EXERCISES, check, solutions, stub_text, write_stubs
from gdq_pddl.learners import GDQ, office_task_context
from gdq_pddl.learners.gdq import hybrid_backup
from gdq_pddl.learners.learned_model import learned_value, record
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import builtin_world
from tests.helpers import cli

NUMBERS = [e.number for e in EXERCISES]


def stub_function(number: int):
    e = EXERCISES[number - 1]
    module = importlib.import_module(f"gdq_pddl.exercises.stubs.{e.stem}")
    return getattr(module, e.function)


def test_five_exercises_in_the_order_of_the_lesson():
    assert NUMBERS == [1, 2, 3, 4, 5]
    sections = [int(e.section.split()[-1]) for e in EXERCISES]
    assert sections == sorted(sections)


@pytest.mark.parametrize("number", NUMBERS)
def test_the_grader_passes_the_reference_solution(number):
    e = EXERCISES[number - 1]
    verdict = check(number, function=getattr(solutions, e.function))
    assert verdict.passed, verdict.message
    assert verdict.cases >= 6 and "pass" in verdict.message


@pytest.mark.parametrize("number", NUMBERS)
def test_the_grader_fails_the_stub(number):
    verdict = check(number, function=stub_function(number))
    assert not verdict.passed
    assert "not written yet" in verdict.message


@pytest.mark.parametrize("number", NUMBERS)
def test_the_stub_has_the_solutions_signature(number):
    e = EXERCISES[number - 1]
    def parameters(f):
        return [(p.name, p.default) for p in inspect.signature(f).parameters.values()]

    assert parameters(stub_function(number)) == parameters(getattr(solutions, e.function))
    assert "NotImplementedError" in stub_text(number)


# --- plausible wrong answers: each fails, on a case that shows it, with the hint -----------------

def no_gamma(q, s, a, r, s2, done, alpha, gamma):
    target = r if done else r + q[s2].max()
    return q[s, a] + alpha * (target - q[s, a])


def bootstraps_when_done(q, s, a, r, s2, done, alpha, gamma):
    return q[s, a] + alpha * (r + gamma * q[s2].max() - q[s, a])


def forgets_stuck(q, counts, stuck, cost, goal, pairs, gamma, r_max):
    return solutions.dyna_planning(q, counts, 0 * stuck, cost, goal, pairs, gamma, r_max)


def goal_rows_not_zero(next_state, goal, gamma, r_max, step_cost=1.0):
    q = solutions.optinit(next_state, goal, gamma, r_max, step_cost)
    q[goal] = r_max
    return q


def no_change_waits_for_m(s, a, v, goal, prior_next, visits, learned, m, w, gamma, r_max,
                          prior_cost=1.0):
    stays = np.where(prior_next < 0, np.arange(len(v))[:, None], prior_next)
    return solutions.hybrid_backup(s, a, v, goal, stays, visits, learned, m, w, gamma, r_max,
                                   prior_cost)


def known_after_m(prior_value, trial_value, alternative, w, m):
    n = solutions.trials_to_turn_away(prior_value, trial_value, alternative, w, m)
    return n - 1 if n else n


@pytest.mark.parametrize(("number", "wrong", "hint"), [
    (1, no_gamma, "the discount gamma is missing"),
    (1, bootstraps_when_done, "when done, the target is r alone"),
    (2, forgets_stuck, "stuck trials are left out"),
    (3, goal_rows_not_zero, "only the goal states' rows differ"),
    (4, no_change_waits_for_m, "known after its first trial"),
    (5, known_after_m, "it takes more than m"),
])
def test_the_grader_fails_a_plausible_wrong_answer_and_says_why(number, wrong, hint):
    verdict = check(number, function=wrong)
    assert not verdict.passed
    assert "differs" in verdict.message and "The input: " in verdict.message
    assert hint in verdict.message, verdict.message


def test_a_failed_case_is_told_by_the_office_s_names():
    message = check(1, function=no_gamma).message
    assert "expected" in message and ", got " in message
    assert "gamma = " in message and "(p" in message  # a pair named as (p.., verb p..)


# --- the reference solutions compute what the learners compute ---------------------------------

def test_trials_to_turn_away_is_gdq_s_rule_at_a_jammed_door():
    """Stuck trials of ``opendoor p1`` (door d0, as if jammed) recorded in a GDQ learner's
    model one by one, the state values held fixed: the first trial count whose hybrid
    backup is below the best other action is the reference solution's, for several m
    and w."""
    world = builtin_world("office")
    context, spaces = office_task_context(world, "C"), LearnerSpaces(world)
    s, a = spaces.state("p1"), spaces.action("opendoor", "p1")
    counts = set()
    for m, w in ((0, 1.0), (2, 1.0), (0, 30.0), (1, 0.0), (3, 12.0)):
        learner = GDQ(context)
        t = learner.tables
        p = learner.params._replace(m=m, prior_weight=w)
        q, v = t.table.q, t.table.v
        alternative = max(q[s, b] for b in np.flatnonzero(t.table.allowed[s]) if b != a)

        def value(t=t, p=p):
            return hybrid_backup(t.table, t.model, t.prior.next_state, t.prior.reward,
                                 t.prior.dead, p, s, a)

        prior, observed = value(), None
        for n in range(1, 200):
            assert record(t.model, t.table.goal, p, s, a, -context.r_max, s, True, False)
            if value() < alternative:
                observed = n
                break
        trial = learned_value(t.model.slots, t.model.stuck, t.model.visits, t.model.cost_sum,
                              t.model.cost_n, t.model.cost_all, t.table.goal, v, p, s, a)
        assert trial == -context.r_max
        assert observed == solutions.trials_to_turn_away(prior, trial, alternative, w, m)
        counts.add(observed)
    assert len(counts) >= 3  # the cases tell the settings apart


def test_trials_to_turn_away_edges():
    assert solutions.trials_to_turn_away(1.0, -5.0, 2.0, 1.0, 0) == 0  # already below
    assert solutions.trials_to_turn_away(10.0, 3.0, 2.0, 1.0, 0) is None  # never
    assert solutions.trials_to_turn_away(10.0, -5.0, 2.0, 0.0, 3) == 4  # w = 0: once known
    # (n * -5 + 10) / (n + 1) < 2  <=>  n > 8/7: 2 trials; exactly on the boundary, more
    assert solutions.trials_to_turn_away(10.0, -5.0, 2.0, 1.0, 0) == 2
    assert solutions.trials_to_turn_away(10.0, -6.0, 2.0, 1.0, 0) == 2  # n = 1 gives 2: not below


# --- the command ---------------------------------------------------------------------------------

def test_the_command_lists_writes_and_grades(capsys, tmp_path):
    code, out = cli(capsys, "exercises")
    assert code == 0
    assert all(f"{e.number}. {e.title}" in out for e in EXERCISES)
    folder = tmp_path / "mine"
    code, out = cli(capsys, "exercises", "init", folder)
    assert code == 0
    assert sorted(p.name for p in folder.iterdir()) == sorted(e.file_name for e in EXERCISES)
    assert not any("solution" in p.read_text() for p in folder.iterdir())
    code, out = cli(capsys, "exercises", "init", folder)  # the student's work is kept
    assert code == 2 and "--force" in out and out.count("\n") == 1
    code, _ = cli(capsys, "exercises", "init", folder, "--force")
    assert code == 0
    stub = folder / EXERCISES[4].file_name
    code, out = cli(capsys, "exercises", "check", 5, stub)
    assert code == 1 and "not written yet" in out
    answer = inspect.getsource(solutions.trials_to_turn_away)
    stub.write_text(stub.read_text().split("def trials_to_turn_away")[0] + answer)
    code, out = cli(capsys, "exercises", "check", 5, stub)
    assert code == 0 and "all 25 cases pass" in out


@pytest.mark.parametrize("argv", [("check", 6), ("check", 0), ("check", "x"),
                                  ("check", 1, "no-such-file.py")])
def test_bad_usage_exits_2_in_one_line(capsys, tmp_path, monkeypatch, argv):
    monkeypatch.chdir(tmp_path)
    code, out = cli(capsys, "exercises", *argv)
    assert code == 2
    assert "Traceback" not in out


def test_a_file_that_fails_to_load_is_a_failed_check(capsys, tmp_path):
    broken = tmp_path / "ex1.py"
    broken.write_text("def q_update(:\n")
    code, out = cli(capsys, "exercises", "check", 1, broken)
    assert code == 1 and "failed to load (line 1): SyntaxError" in out
    other = tmp_path / "ex2.py"
    other.write_text("x = 1\n")
    code, out = cli(capsys, "exercises", "check", 1, other)
    assert code == 1 and "has no function q_update()" in out


def test_init_into_a_file_is_refused(tmp_path):
    target = tmp_path / "file"
    target.write_text("")
    from gdq_pddl.errors import ConfigError

    with pytest.raises(ConfigError, match="is a file"):
        write_stubs(target)


def test_a_function_that_returns_nothing_is_told_so():
    def in_place(q, counts, stuck, cost, goal, pairs, gamma, r_max):
        q[:] = solutions.dyna_planning(q, counts, stuck, cost, goal, pairs, gamma, r_max)

    message = check(2, function=in_place).message
    assert "returned None: return the Q table" in message
    message = check(1, function=lambda **kwargs: None).message
    assert "returned None (a return missing?)" in message
