"""A problem whose goal already holds in its initial state runs: as mdpsim ends such a
round at turn 0, every episode ends before its first action, with return 0 and success,
in the env, both episode loops, online exploration, V* and the command line."""

from __future__ import annotations

import csv

import numpy as np
import pytest
from gymnasium.error import ResetNeeded

from gdq_pddl.cli import main
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.online_env import OnlineEnv
from gdq_pddl.envs.pddl_env import PDDLEnv, load_instance
from gdq_pddl.learners import make_learner, pddl_task_context, run_episodes
from gdq_pddl.learners.online import online_context
from gdq_pddl.resources import resolve_pddl

# lift-1 with the passenger already served: the goal holds before any action.
SERVED = """(define (problem lift-served)
  (:domain lift)
  (:objects ground first - floor ann - passenger)
  (:init (lift-at ground) (above first ground) (served ann))
  (:goal (forall (?p - passenger) (served ?p))))
"""


@pytest.fixture
def served(tmp_path):
    domain, _, _ = resolve_pddl("lift", "lift-1", None)
    problem = tmp_path / "served.pddl"
    problem.write_text(SERVED, "utf-8")
    return domain, problem


def test_the_env_is_over_at_reset(served) -> None:
    env = PDDLEnv(instance=load_instance(*served))
    _, info = env.reset(seed=0)
    assert info["cause"] == "goal" and info["step"] == 0
    with pytest.raises(ResetNeeded):
        env.step(0)


@pytest.mark.parametrize("method", ["GDQ", "DARLING", "Dyna-Q", "Q-learning"])
def test_both_loops_record_episodes_of_no_action(served, method: str) -> None:
    instance = load_instance(*served)
    records = []
    for fast in (True, False):
        env = PDDLEnv(instance=instance)
        env.reset(seed=1)
        learner = make_learner(method, pddl_task_context(instance))
        records.append(run_episodes(learner, env, 12, np.random.default_rng(2), fast=fast))
    for r in records:
        assert (r.returns == 0).all() and (r.steps == 0).all() and r.success.all()


def test_v_star_is_zero_and_the_shortest_plan_empty(served) -> None:
    optimal = load_instance(*served).optimal()
    assert optimal["v_star"] == 0 and optimal["shortest_plan"] == 0


def test_online_exploration_agrees(served) -> None:
    online = OnlineInstance(load_instance(*served))
    env = OnlineEnv(online)
    env.reset(seed=0)
    r = run_episodes(make_learner("GDQ", online_context(online)), env, 5,
                     np.random.default_rng(0))
    assert (r.steps == 0).all() and r.success.all() and (r.returns == 0).all()


@pytest.mark.parametrize("explore", ["enumerate", "online"])
def test_the_command_line_runs_it_and_says_so(capsys, tmp_path, served, explore: str) -> None:
    domain, problem = served
    out = tmp_path / "out"
    code = main(["run", "--domain", str(domain), "--problem", str(problem), "--episodes", "5",
                 "--runs", "1", "--method", "GDQ", "Q-learning", "--explore", explore,
                 "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 0 and "already holds in the initial state" in err and str(problem) in err
    with open(out / "episodes.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 10 and {(r["return"], r["steps"], r["success"]) for r in rows} == \
        {("0", "0", "1")}
    assert "before its first action" in (out / "REPORT.md").read_text("utf-8")


def test_a_strips_problem_with_slips_too(tmp_path) -> None:
    domain, problem, dynamics = resolve_pddl("keys", "keys-1", None)
    text = problem.read_text("utf-8").replace("(:goal (at c35))", "(:goal (at c11))")
    assert "(:goal (at c11))" in text
    (tmp_path / "p.pddl").write_text(text, "utf-8")
    instance = load_instance(domain, tmp_path / "p.pddl", dynamics)
    env = PDDLEnv(instance=instance)
    env.reset(seed=0)
    r = run_episodes(make_learner("GDQ", pddl_task_context(instance)), env, 4,
                     np.random.default_rng(0))
    assert (r.steps == 0).all() and r.success.all() and instance.optimal()["v_star"] == 0
