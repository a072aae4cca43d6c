"""Hostile inputs through the API rather than the command line: learners, envs,
experiments and planners refuse what they cannot use, with the package's own errors."""

from __future__ import annotations

import numpy as np
import pytest

from gdq_pddl.errors import GdqError
from gdq_pddl.resources import data_file
from tests.cli.hostile import (
    FAST,
    KEYS_DOMAIN,
    KEYS_PROBLEM,
    refused,
)
from tests.helpers import cli

# --- the API --------------------------------------------------------------------------------

def test_run_episodes_refuses_what_memory_cannot_hold():
    import gymnasium

    from gdq_pddl.errors import SizeError
    from gdq_pddl.learners import QLearning, office_task_context, run_episodes

    env = gymnasium.make("gdq_pddl/Office-v0", task="C")
    learner = QLearning(office_task_context(env.unwrapped.world, "C"))
    with pytest.raises(SizeError, match="n_episodes = 1,000,000,000,000"):
        run_episodes(learner, env, 10**12, np.random.default_rng(0))
    with pytest.raises(ValueError, match="n_episodes"):
        run_episodes(learner, env, 2.5, np.random.default_rng(0))


@pytest.mark.parametrize("action", [2.5, np.float64(2.0), "2", True, -1, 95, None])
def test_env_step_refuses_what_is_not_an_action(action):
    import gymnasium

    env = gymnasium.make("gdq_pddl/Office-v0", task="C")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must be an integer"):
        env.step(action)
    env.step(np.int64(3))  # numpy integers are actions


@pytest.mark.parametrize(("argv", "said"), [
    (["--start", "p0"], "a start but no goal"), (["--goal", "p3"], "a goal but no start"),
])
def test_half_an_ad_hoc_task_says_which_half(capsys, tmp_path, argv, said):
    code, text = cli(capsys, "run", *argv, "--episodes", "5", "--runs", "1", "--out",
                     tmp_path / "o")
    refused(code, text, said)


@pytest.mark.parametrize(("config", "kwargs", "name"), [
    ("DynaQConfig", {"n_backups": 2.5}, "n_backups"),
    ("DynaQConfig", {"n_backups": 1e12}, "n_backups"),
    ("DynaQConfig", {"n_backups": 10**12}, "n_backups"),
    ("DynaQConfig", {"m": -1}, "m"),
    ("DynaQConfig", {"m": 0.5}, "m"),
    ("QLearningConfig", {"alpha": float("nan")}, "alpha"),
    ("QLearningConfig", {"gamma": float("inf")}, "gamma"),
    ("QLearningConfig", {"epsilon": "0.1"}, "epsilon"),
    ("DarlingConfig", {"tolerance": float("nan")}, "tolerance"),
    ("DarlingConfig", {"tolerance": float("inf")}, "tolerance"),
    ("DarlingConfig", {"tolerance": 1e308}, "tolerance"),
    ("GDQConfig", {"plan_tolerance": 101.0}, "plan_tolerance"),
    ("GDQConfig", {"explore_all_last_step": "no"}, "explore_all_last_step"),
])
def test_learner_configs_refuse_non_numbers(config, kwargs, name):
    from gdq_pddl.learners import config as configs

    with pytest.raises(ValueError, match=name):
        getattr(configs, config)(**kwargs)


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"runs": 0}, "runs"), ({"runs": 2.5}, "runs"), ({"seed": -1}, "seed"),
    ({"schedule": (("C", 0),)}, "episodes"), ({"schedule": (("C", 2.5),)}, "episodes"),
    ({"methods": ("GDQ", "SARSA")}, "SARSA"),
])
def test_experiments_refuse_bad_fields(kwargs, name):
    from gdq_pddl.experiments import Experiment

    fields = {"name": "x", "schedule": (("C", 3),)} | kwargs
    with pytest.raises(ValueError, match=name):
        Experiment(**fields)


@pytest.mark.parametrize("jobs", [0, -2, 2.5])
def test_run_experiments_refuses_bad_jobs(tmp_path, jobs):
    from gdq_pddl.experiments import Experiment, run_experiments

    with pytest.raises(ValueError, match="jobs"):
        run_experiments([Experiment("x", (("C", 3),), methods=("Q-learning",), runs=1)],
                        tmp_path / "o", jobs=jobs)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("tolerance", [float("nan"), float("inf"), -1.0, 1e308, 101.0])
@pytest.mark.parametrize("planner", ["graph", "pyperplan"])
def test_planner_tolerance_must_be_finite(tolerance, planner):
    from gdq_pddl.errors import PlanningError
    from gdq_pddl.planning import PlanningProblem, get_planner

    problem = PlanningProblem.from_texts(KEYS_DOMAIN, KEYS_PROBLEM)
    with pytest.raises(PlanningError, match="tolerance"):
        get_planner(planner).solve(problem, tolerance=tolerance)


@pytest.mark.parametrize("kind", ["all", "routes"])
def test_plan_tables_refuse_absurd_tolerances(kind):
    # 1e308 x the shortest length overflowed into an OverflowError in length_bound
    from gdq_pddl.abstraction.pddl import graph_plan_table
    from gdq_pddl.envs.pddl_env import PDDLInstance
    from gdq_pddl.learners import office_task_context
    from gdq_pddl.world import load_world

    with pytest.raises(GdqError, match=r"tolerance .*got 1e\+308"):
        office_task_context(load_world(), "C", darling_tolerance=1e308, darling_kind=kind)
    keys = PDDLInstance.from_files(data_file("domains", "keys-ppddl.pddl"),
                                   data_file("problems", "keys-ppddl-1.pddl"))
    with pytest.raises(GdqError, match=r"tolerance .*got 1e\+308"):
        graph_plan_table(keys.graph, 1e308)


def test_a_bad_darling_kind_is_refused_before_any_plan_is_read():
    # DARLING's plans are built when first read; a learner that reads none must still not
    # run with a kind no table has
    from gdq_pddl.learners import office_task_context
    from gdq_pddl.world import load_world

    with pytest.raises(GdqError, match="unknown plan table kind 'paths'"):
        office_task_context(load_world(), "C", darling_kind="paths")


def test_value_iteration_refuses_up_front_what_memory_cannot_hold(monkeypatch):
    from dataclasses import replace

    from gdq_pddl.envs.solve import optimal_value
    from gdq_pddl.errors import SizeError
    from gdq_pddl.world import load_world

    world = replace(load_world(None), step_limit=10**9)
    with pytest.raises(SizeError, match="step_limit = 1000000000"):
        optimal_value(world, "C")
    monkeypatch.setenv("GDQ_PDDL_MEMORY", str(10**6))  # a machine of 1 MB
    with pytest.raises(SizeError, match="1 MB"):
        optimal_value(load_world(None), "C")


def test_the_shipped_and_generated_worlds_still_load():
    """The strict validator still reads every shipped and generated world."""
    from gdq_pddl.buildings import building_world
    from gdq_pddl.world import builtin_world

    for name in ("office", "office_robot"):
        assert builtin_world(name).tasks
    assert building_world(300, 1).tasks


def test_a_problem_file_without_its_domain_says_which_domain_to_give(capsys, tmp_path):
    """An IPPC-2008 problem file may hold a problem alone, its domain in another file."""
    problem = tmp_path / "p02.pddl"
    problem.write_text(KEYS_PROBLEM.replace("(:domain keys)", "(:domain locks-elsewhere)"),
                       encoding="utf-8")
    assert "locks-elsewhere" in problem.read_text(encoding="utf-8")
    code, out = cli(capsys, "run", "--problem", problem, *FAST, "--out", tmp_path / "o")
    refused(code, out, str(problem), "domain locks-elsewhere", "--domain")
