"""What V* means in probabilities (issue 40 item 3): the goal probability of V*'s policy
within the step limit, the most any policy has within it, and the most with no limit
(MaxProb), on small domains whose answers are derived by hand."""

from __future__ import annotations

import json

import pytest

from gdq_pddl.cli import main
from gdq_pddl.envs import goal_chance
from gdq_pddl.envs.goal_chance import best_within_limit, best_without_limit
from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLInstance


def instance(domain: str, problem: str, step_limit: int) -> PDDLInstance:
    return PDDLInstance.from_texts(domain, problem, f"[dynamics]\nstep_limit = {step_limit}\n")


# one action, tried until it works: it reaches the goal 1 time in 10 and else changes nothing
RETRY = """(define (domain retry) (:requirements :probabilistic-effects)
  (:predicates (done))
  (:action try :effect (probabilistic 0.1 (done))))"""
RETRY_P = "(define (problem retry-1) (:domain retry) (:init) (:goal (done)))"


@pytest.mark.parametrize("limit", [3, 10, 40])
def test_a_retry_reaches_the_goal_surely_with_no_limit_and_rarely_within_one(limit):
    inst = instance(RETRY, RETRY_P, limit)
    facts = inst.optimal()
    assert facts["goal_within_limit"] == pytest.approx(1 - 0.9**limit, abs=1e-12)
    assert facts["goal_v_star_policy"] == pytest.approx(1 - 0.9**limit, abs=1e-12)
    # value iteration from 0 is 1 - 0.9^k after k sweeps: the exact evaluation of the
    # policy (a self-loop is an end component) gives 1 itself
    assert facts["goal_no_limit"] == pytest.approx(1.0, abs=1e-12)
    assert facts["goal_no_limit_exact"] is True


def test_without_the_exact_evaluation_the_answer_is_a_lower_bound(monkeypatch):
    inst = instance(RETRY, RETRY_P, 5)
    monkeypatch.setattr(goal_chance, "FIXED_POINT_TOLERANCE", -1.0)  # never a fixed point
    out = best_without_limit(inst.model, GOAL_POS, work=1000)
    assert not out.exact and 0.99 < out.value[inst.start_state] <= 1.0
    monkeypatch.setattr(goal_chance, "EXACT_STATES", 0)  # too many states to solve exactly
    alone = best_without_limit(inst.model, GOAL_POS, work=64)
    sweeps = goal_chance.SWEEPS  # value iteration alone: 1 - 0.9^k after k sweeps
    assert not alone.exact
    assert alone.value[inst.start_state] == pytest.approx(1 - 0.9**sweeps, abs=1e-12)


# a gamble (goal 6 in 10, else broken), or a climb to a ledge (8 in 10, else broken), from
# which a jump reaches the goal 9 times in 10 (else broken) or a path leads back down:
# with no limit max(0.6, 0.8 x max(0.9, x)) = 0.72; within one action 0.6
LEDGE = """(define (domain ledge) (:requirements :probabilistic-effects :negative-preconditions)
  (:predicates (top) (ledge) (broken))
  (:action gamble :precondition (and (not (broken)) (not (ledge)))
    :effect (probabilistic 0.6 (top) 0.4 (broken)))
  (:action climb :precondition (and (not (broken)) (not (ledge)))
    :effect (probabilistic 0.8 (ledge) 0.2 (broken)))
  (:action jump :precondition (and (not (broken)) (ledge))
    :effect (probabilistic 0.9 (top) 0.1 (broken)))
  (:action descend :precondition (and (not (broken)) (ledge)) :effect (not (ledge))))"""
LEDGE_P = "(define (problem ledge-1) (:domain ledge) (:init) (:goal (top)))"


def test_the_best_route_by_hand():
    inst = instance(LEDGE, LEDGE_P, 2)
    facts = inst.optimal()
    assert facts["goal_no_limit"] == pytest.approx(0.72, abs=1e-12)
    assert facts["goal_within_limit"] == pytest.approx(0.72, abs=1e-12)
    assert best_within_limit(instance(LEDGE, LEDGE_P, 2).model, GOAL_POS)[
        inst.start_state] == pytest.approx(0.72)
    one = instance(LEDGE, LEDGE_P, 1)
    assert best_within_limit(one.model, GOAL_POS)[one.start_state] == pytest.approx(0.6)


# a tireworld: a move goes flat 1 time in 2 (arriving all the same); a flat is changed
# only where a spare lies. The short road l0-l1-l2 has no spare on l1: 1/2. The long
# road l0-l3-l4-l2 has spares on l3 and l4: 1, in at least 3 moves
TYRES = """(define (domain tyres) (:requirements :typing :probabilistic-effects
    :negative-preconditions)
  (:types place)
  (:predicates (at ?l - place) (road ?a ?b - place) (spare ?l - place) (flat))
  (:action move :parameters (?a ?b - place)
    :precondition (and (at ?a) (road ?a ?b) (not (flat)))
    :effect (and (not (at ?a)) (at ?b) (probabilistic 0.5 (flat))))
  (:action change :parameters (?a - place) :precondition (and (at ?a) (spare ?a) (flat))
    :effect (and (not (flat)) (not (spare ?a)))))"""
TYRES_P = """(define (problem tyres-1) (:domain tyres) (:objects l0 l1 l2 l3 l4 - place)
  (:init (at l0) (road l0 l1) (road l1 l2) (road l0 l3) (road l3 l4) (road l4 l2)
         (spare l3) (spare l4))
  (:goal (at l2)))"""


def test_a_step_limit_that_cuts_the_safe_road_off():
    short = instance(TYRES, TYRES_P, 2).optimal()
    assert short["goal_within_limit"] == pytest.approx(0.5, abs=1e-12)
    assert short["goal_no_limit"] == pytest.approx(1.0, abs=1e-12)
    # 5 actions: the long road with both changes (3 moves, 2 changes) is always in time
    long = instance(TYRES, TYRES_P, 5).optimal()
    assert long["goal_within_limit"] == pytest.approx(1.0, abs=1e-12)
    assert long["goal_v_star_policy"] <= long["goal_within_limit"] + 1e-12


def test_the_report_says_what_v_star_means_and_that_the_limit_cuts_the_goal_off(tmp_path):
    domain, problem = tmp_path / "tyres.pddl", tmp_path / "tyres-1.pddl"
    domain.write_text(TYRES)
    problem.write_text(TYRES_P)
    (tmp_path / "limit.toml").write_text("[dynamics]\nstep_limit = 2\n")
    out = tmp_path / "run"
    assert main(["run", "--domain", str(domain), "--problem", str(problem), "--dynamics",
                 str(tmp_path / "limit.toml"), "--method", "Q-learning", "--episodes", "5",
                 "--runs", "2", "--jobs", "1", "--out", str(out)]) == 0
    facts = next(iter(json.loads((out / "optimal.json").read_text()).values()))
    assert facts["goal_within_limit"] == pytest.approx(0.5)
    text = (out / "REPORT.md").read_text()
    assert "V*'s policy reaches it with probability 0.500 within the step limit of 2 " \
        "actions, the best policy for the goal with 0.500; with no step limit the goal can " \
        "be reached with probability 1.000" in text
    assert "The step limit makes V* far below what the goal is worth: with no limit the " \
        "goal is reached with probability 1.000, within 2 actions at most 0.500" in text


def test_a_limit_that_cuts_nothing_off_is_not_blamed(tmp_path):
    # ledge-1 with 2 actions: 0.72 within the limit and without it
    from gdq_pddl.analysis.generic import goal_lines
    facts = instance(LEDGE, LEDGE_P, 2).optimal()
    lines = goal_lines(facts)
    assert len(lines) == 1 and "0.720 within the step limit of 2" in lines[0]
    assert goal_lines({"v_star": None}) == []


def test_an_online_report_says_why_and_bounds_v_star(tmp_path):
    domain, problem = tmp_path / "tyres.pddl", tmp_path / "tyres-1.pddl"
    domain.write_text(TYRES)
    problem.write_text(TYRES_P)
    out = tmp_path / "run"
    assert main(["run", "--domain", str(domain), "--problem", str(problem), "--explore",
                 "online", "--method", "Q-learning", "--episodes", "5", "--runs", "2",
                 "--jobs", "1", "--out", str(out)]) == 0
    facts = next(iter(json.loads((out / "optimal.json").read_text()).values()))
    # h_max of the start is 2 (l0-l1-l2); every action costs 1: V* <= r_max - 1
    r_max = facts["r_max"]
    assert facts["v_star"] is None and facts["v_star_upper_bound"] == r_max - 1
    enumerated = instance(TYRES, TYRES_P, facts["step_limit"]).optimal()
    assert enumerated["v_star"] <= facts["v_star_upper_bound"]
    text = (out / "REPORT.md").read_text()
    assert "- why online: `--explore online` was given" in text
    assert "V*: not computed: the problem was explored online" in text
    assert f"V* <= {r_max - 1:g}: r_max {r_max:g} minus the least mean action cost 1 for " \
        "each action before the goal's, of at least 2 actions (h_max" in text


def test_the_office_tasks_get_them_too_and_keep_their_v_star():
    from gdq_pddl.envs.office import OfficeInstance
    from gdq_pddl.envs.solve import optimal_value
    from gdq_pddl.world import load_world
    world = load_world()
    facts = OfficeInstance(world, world.task("C")).optimal()
    assert facts["v_star"] == optimal_value(world, "C")
    assert facts["goal_no_limit"] == pytest.approx(1.0, abs=1e-12)
    assert facts["goal_no_limit_exact"] and facts["step_limit"] == world.step_limit
    assert 0.999 < facts["goal_v_star_policy"] <= facts["goal_within_limit"] + 1e-12


def test_the_online_bound_counts_outcomes_that_change_nothing_and_not_most_likely():
    from gdq_pddl.envs.online import OnlineInstance
    retry = OnlineInstance(instance(RETRY, RETRY_P, 5))
    bound, why = retry.v_star_bound()  # one action to the goal: nothing to pay before it
    assert bound == retry.dynamics.r_max and "at least 1 actions" in why
    assert instance(RETRY, RETRY_P, 5).optimal()["v_star"] <= bound
    likely = OnlineInstance(PDDLInstance.from_texts(
        TYRES, TYRES_P, "[dynamics]\nstep_limit = 5\n", determinisation="most-likely"))
    assert likely.v_star_bound()[0] is None
    assert "most-likely determinisation" in likely.optimal()["v_star_note"]
