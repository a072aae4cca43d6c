"""The shipped lift (conditional effects) and courier (IPPC rewards) domains: V* derived
by hand, episodes scored on the problem's own scale (issue 22, items 1, 2 and 6)."""

from __future__ import annotations

import pytest

from gdq_pddl.envs.pddl_env import PDDLEnv, PDDLInstance, load_instance
from gdq_pddl.errors import PlanningError, WorldError

COURIER = "(define (domain c) (:requirements :rewards)\n" \
    "  (:predicates (a) (b) (stuck))\n" \
    "  (:action go :effect (and (a) (decrease (reward) 2)))\n" \
    "  (:action jump :precondition (a) :effect (probabilistic 1/2 (b) 1/2 (stuck))))\n"


def problem(goal: str = "(b)", extra: str = "") -> str:
    return f"(define (problem p) (:domain c) (:init) (:goal {goal}) {extra})"


def test_lift_v_star_by_hand():
    """lift-1: stop at the ground floor (Ann boards), move up until it works (9/10 each
    time: 10/9 moves expected), stop (Ann is served). The goal scale: -1 per action,
    +20 instead of the last one's cost: V* = -1 - 10/9 + 20 = 161/9 (the step limit of
    20 leaves 18 tries, missing all of them has probability 1e-18)."""
    instance = load_instance("lift", "lift-1")
    assert instance.reward_scale == "goal"
    assert instance.optimal()["v_star"] == pytest.approx(161 / 9, abs=1e-9)


def test_courier_v_star_by_hand():
    """courier-1 (goal: one parcel delivered; metric: maximise the reward). Round by the
    mill: drive (-1), deliver p2 late (+5), the goal (+20): 24. Over the hill: -3, then
    with 3/4 the market, deliver p1 on time (+5 +20) and the goal (+20), with 1/4 a
    breakdown (the trial ends, no penalty on the IPPC's scale): -3 + 3/4 x 45 = 30.75."""
    instance = load_instance("courier", "courier-1")
    assert (instance.reward_scale, instance.r_max) == ("problem", 20.0)
    assert instance.optimal()["v_star"] == pytest.approx(30.75, abs=1e-12)
    assert instance.optimal()["reward_scale"] == "problem"


def test_an_episode_returns_what_the_ippc_would_score():
    env = PDDLEnv(domain="courier", problem="courier-1")
    env.reset(seed=0)
    names = [env.unwrapped.action_name(a) for a in range(env.action_space.n)]
    first = env.step(names.index("(drive depot mill)"))
    assert first[1:4] == (-1.0, False, False)
    last = env.step(names.index("(deliver p2 mill)"))
    assert last[1:4] == (25.0, True, False) and last[4]["cause"] == "goal"


def test_no_penalty_for_a_failed_or_late_end_on_the_problem_scale():
    text = problem(extra="(:goal-reward 10) (:metric maximize (reward))")
    instance = PDDLInstance.from_texts(COURIER, text)
    env = PDDLEnv(instance=instance)
    # V*: go (-2), jump: 1/2 the goal (+10), 1/2 a failed trial (0)
    assert instance.optimal()["v_star"] == pytest.approx(-2 + 5)
    rewards = set()
    for seed in range(20):
        env.reset(seed=seed)
        env.step(0)
        _, r, terminated, _, info = env.step(1)
        rewards.add((r, info["cause"]))
    assert rewards == {(0.0, "stuck"), (10.0, "goal")}
    env.reset(seed=0)
    steps = [env.step(0) for _ in range(instance.dynamics.step_limit)]
    assert [s[1] for s in steps] == [-2.0] * len(steps) and steps[-1][3]  # truncated


def test_the_goal_scale_stays_without_a_reward_metric():
    # (decrease (reward) 2) with (:metric minimize (total-cost)): the metric decides
    instance = PDDLInstance.from_texts(COURIER, problem(extra="(:metric minimize "
                                                        "(total-cost))"))
    assert instance.reward_scale == "goal" and instance.r_max == 20.0
    assert PDDLInstance.from_texts(COURIER, problem()).reward_scale == "problem"
    assert PDDLInstance.from_texts(COURIER, problem()).r_max == 0.0  # no :goal-reward


def test_a_goal_with_alternatives_is_a_set_of_states():
    instance = load_instance("courier", "courier-1")
    goals = {instance.state_name(s) for s in range(instance.n_states)
             if instance.learner_goal[s]}
    assert {("(delivered p1)" in g, "(delivered p2)" in g) for g in goals} == \
        {(True, False), (False, True)}
    with pytest.raises(PlanningError, match=r"courier-1.pddl: the goal has alternatives.*"
                                            r"use --planner graph"):
        instance.plan_table("pyperplan")


def test_one_problem_of_a_file_by_name(tmp_path):
    both = tmp_path / "both.pddl"
    both.write_text(COURIER + problem("(a)").replace("(problem p)", "(problem one)")
                    + problem().replace("(problem p)", "(problem two)"))
    instance = PDDLInstance.from_files(both, f"{both}:two")
    assert (instance.name, instance.problem.problem.source) == ("two", str(both))
    with pytest.raises(Exception, match=r"both.pddl:\d+: this file has 2 problems \(one, "
                                        r"two\): pick one by name \(.*both.pddl:one\)"):
        PDDLInstance.from_files(both, both)


def test_a_step_limit_no_file_states_names_the_problem_and_its_rule(tmp_path):
    chain = "(define (domain ch) (:predicates (s0) (s1) (s2) (s3))\n" + "".join(
        f"(:action a{i} :precondition (s{i}) :effect (probabilistic 1 (s{i + 1})))\n"
        for i in range(3)) + ")"
    (tmp_path / "d.pddl").write_text(chain)
    (tmp_path / "p.pddl").write_text("(define (problem p) (:domain ch) (:init (s0)) "
                                     "(:goal (s3)))")
    (tmp_path / "o.toml").write_text("[dynamics]\nr_max = 5\n")
    instance = PDDLInstance.from_files(tmp_path / "d.pddl", tmp_path / "p.pddl",
                                       tmp_path / "o.toml")
    source, key = instance.step_limit_key
    assert source == str(tmp_path / "p.pddl") and key.startswith("the default step limit")
    (tmp_path / "o.toml").write_text("[dynamics]\nstep_limit = 2\n")
    with pytest.raises(WorldError, match=r"o.toml: dynamics.step_limit: 2 is less"):
        _ = PDDLInstance.from_files(tmp_path / "d.pddl", tmp_path / "p.pddl",
                                    tmp_path / "o.toml").dynamics


def test_backends_that_read_text_say_they_cannot_carry_conditional_effects():
    instance = load_instance("lift", "lift-1")
    with pytest.raises(PlanningError, match=r"lift.pddl has conditional or quantified "
                       r"effects \(stop\); a disjunctive or quantified precondition \(move\), "
                       r"which the STRIPS text .* use one of them"):
        instance.plan_table("pyperplan")
    assert instance.plan_table("graph").length[0] == 3


def test_a_planner_query_refuses_a_goal_with_alternatives():
    instance = load_instance("courier", "courier-1")
    with pytest.raises(PlanningError, match=r"courier-1.pddl: the goal has alternatives"):
        instance.problem.query("graph", None, None, 0.0)
