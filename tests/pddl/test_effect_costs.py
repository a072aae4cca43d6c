"""Costs and rewards inside ``forall``, ``when`` and ``probabilistic`` (issue 38): paid on
both reward scales, by the enumerated env, V* and the env of a problem explored online
alike. They were dropped on the goal scale (a step paid the default cost 1 instead)."""

from __future__ import annotations

import numpy as np
import pytest

from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.online_env import OnlineEnv
from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLEnv, PDDLInstance
from gdq_pddl.envs.solve import Budget, solve, value_within

DOMAIN = """(define (domain coins) (:requirements :adl :probabilistic-effects :action-costs)
  (:types coin)
  (:predicates (a) (b))
  (:functions (total-cost) - number (fee ?c - coin))
  (:action first :parameters () :precondition (not (a))
    :effect (and (a) EFFECT))
  (:action second :parameters () :precondition (a)
    :effect (and (b) (increase (total-cost) 1))))
"""
PROBLEM = """(define (problem coins-3) (:domain coins) (:objects x y z - coin)
  (:init (= (fee x) 2) (= (fee y) 2) (= (fee z) 2)) (:goal (b)) METRIC)
"""
GOAL_SCALE = "(:metric minimize (total-cost))"
OWN_SCALE = "(:goal-reward 20) (:metric maximize (reward))"

SIX = {  # ways to write "the first action costs 6" (3 coins of 2) inside a construct
    "forall": "(forall (?c - coin) (increase (total-cost) 2))",
    "forall of a function": "(forall (?c - coin) (increase (total-cost) (fee ?c)))",
    "when": "(when (not (b)) (increase (total-cost) 6))",
    "probabilistic 1": "(probabilistic 1 (increase (total-cost) 6))",
    "forall of when of probabilistic": "(forall (?c - coin) (when (not (b)) "
                                       "(probabilistic 1 (increase (total-cost) 2))))",
    "probabilistic of forall": "(probabilistic 1/2 (forall (?c - coin) (increase "
                               "(total-cost) 2)) 1/2 (increase (total-cost) 6))",
    "decrease reward in when": "(when (not (b)) (decrease (reward) 6))",
    "and of two": "(and (when (not (b)) (increase (total-cost) 4)) "
                  "(probabilistic 1 (increase (total-cost) 2)))",
}


def instance(effect: str, metric: str) -> PDDLInstance:
    return PDDLInstance.from_texts(DOMAIN.replace("EFFECT", effect),
                                   PROBLEM.replace("METRIC", metric))


def first_rewards(inst, online: bool) -> list[float]:
    """The rewards of the two steps first, second from the initial state."""
    env = OnlineEnv(OnlineInstance(inst)) if online else PDDLEnv(instance=inst)
    env.reset(seed=0)
    names = [inst.action_name(a) for a in range(inst.n_actions)]
    return [float(env.step(names.index(n))[1]) for n in ("(first)", "(second)")]


@pytest.mark.parametrize("effect", SIX.values(), ids=SIX.keys())
def test_a_cost_inside_a_construct_is_paid_on_the_goal_scale(effect):
    """V* = 20 - 6: the first step pays 6 (not the default 1: the action states a cost),
    the second reaches the goal (+20 instead of its cost). Before: V* 19, a step of -1."""
    inst = instance(effect, GOAL_SCALE)
    assert inst.reward_scale == "goal"
    assert solve(inst.model, GOAL_POS).V[0, 0] == pytest.approx(14.0)
    assert first_rewards(inst, online=False) == [-6.0, 20.0]
    assert first_rewards(inst, online=True) == [-6.0, 20.0]


@pytest.mark.parametrize("effect", SIX.values(), ids=SIX.keys())
def test_the_same_cost_is_paid_on_the_problems_own_scale(effect):
    """V* = -6 - 1 + 20: on the file's own scale the goal step pays its cost too."""
    inst = instance(effect, OWN_SCALE)
    assert inst.reward_scale == "problem"
    assert solve(inst.model, GOAL_POS).V[0, 0] == pytest.approx(13.0)
    assert first_rewards(inst, online=False) == [-6.0, 19.0]
    assert first_rewards(inst, online=True) == [-6.0, 19.0]


def test_a_reward_inside_a_construct_is_earned_on_the_goal_scale():
    """An action that states no cost costs the default 1 on the goal scale, and earns the
    reward its effect writes: 3 - 1 on the first step, then +20."""
    inst = instance("(when (not (b)) (increase (reward) 3))", GOAL_SCALE)
    assert inst.reward_scale == "goal"
    assert solve(inst.model, GOAL_POS).V[0, 0] == pytest.approx(22.0)
    assert first_rewards(inst, online=False) == [2.0, 20.0]
    assert first_rewards(inst, online=True) == [2.0, 20.0]
    # a step may pay: no cheap bound on V* when it is not computed
    assert value_within(inst.model, GOAL_POS, 0, Budget(bytes=0, work=0))[
        "v_star_upper_bound"] is None


def test_a_cost_that_depends_on_the_outcome_and_the_state():
    """first: with 1/4 the coins cost 2 each where (b) does not hold (always here): 6;
    else 2. Expected step reward -(1/4 6 + 3/4 2) = -3; V* = 20 - 3."""
    inst = instance("(probabilistic 1/4 (forall (?c - coin) (when (not (b)) "
                    "(increase (total-cost) 2))) 3/4 (increase (total-cost) 2))", GOAL_SCALE)
    assert solve(inst.model, GOAL_POS).V[0, 0] == pytest.approx(17.0)
    m = inst.model
    first = [a for a in range(inst.n_actions) if inst.action_name(a) == "(first)"][0]
    pair = int(np.flatnonzero(m.acts[0] == first)[0])
    ks = range(m.ptr[pair], m.ptr[pair + 1])
    assert sorted((m.prob[k], m.gain[k]) for k in ks) == [(0.25, -6.0), (0.75, -2.0)]


def test_the_bound_on_v_star_counts_what_an_outcome_earns():
    """Not computed (budget 0): V* <= r_max - (L - 1) c, c the least a step costs: here
    1 less the 1/2 the first action earns, so the bound is V* itself, 19.5 (19 without
    the reward: below V*)."""
    inst = instance("(increase (total-cost) 1) (when (not (b)) (increase (reward) 0.5))",
                    GOAL_SCALE)
    assert solve(inst.model, GOAL_POS).V[0, 0] == pytest.approx(19.5)
    got = value_within(inst.model, GOAL_POS, 0, Budget(bytes=0, work=0))
    assert got["v_star"] is None and got["v_star_upper_bound"] == pytest.approx(19.5)


BIG = """(define (domain big) (:requirements :adl :rewards)
  (:predicates (a) (b))
  (:action first :parameters () :precondition (not (a))
    :effect (and (a) (increase (reward) ONE) (when (not (b)) (increase (reward) TWO))))
  (:action second :parameters () :precondition (a) :effect (b)))
"""
BIG_PROBLEM = """(define (problem big-1) (:domain big) (:init) (:goal (b)) (:goal-reward GOAL)
  (:metric maximize (reward)))"""


def big(one: str, two: str, goal: str) -> PDDLInstance:
    return PDDLInstance.from_texts(BIG.replace("ONE", one).replace("TWO", two),
                                   BIG_PROBLEM.replace("GOAL", goal))


def test_a_step_that_can_pay_past_the_bound_is_refused_up_front_both_ways():
    """Each reward within 1e15, one step 2e15: refused before any episode, naming the
    domain and the action, enumerated and online alike. Before: the enumerated run went
    on, the online one stopped midway with a learner's error naming no file."""
    from gdq_pddl.errors import PDDLError

    message = (r"^<domain>:3: action first: one step of \(first\) can pay 2e\+15 in size "
               r".*the rewards and costs of one step, added up, must be at most 1e\+15")
    with pytest.raises(PDDLError, match=message):
        big("1e15", "1e15", "10").model  # noqa: B018
    with pytest.raises(PDDLError, match=message):
        OnlineInstance(big("1e15", "1e15", "10"))


def test_a_step_within_the_bound_runs_both_ways():
    """5e14 + 4e14 and the goal reward 1e14 add up to 1e15: accepted, and paid."""
    inst = big("5e14", "4e14", "1e14")
    assert first_rewards(inst, online=False) == [9e14, 1e14]
    assert first_rewards(inst, online=True) == [9e14, 1e14]


ROUTES = """(define (domain routes) (:requirements :adl :probabilistic-effects :action-costs)
  (:types coin)
  (:predicates (got ?c - coin) (done))
  (:functions (total-cost) - number (fee ?c - coin))
  (:action take :parameters (?c - coin)
    :effect (and (got ?c) (increase (total-cost) (fee ?c)) (increase (total-cost) 1)))
  (:action free :parameters () :effect (done))
  LAST)
"""


@pytest.mark.parametrize(("last", "route"), [
    ("", "STRIPS (grounding.ground)"),
    ("(:action toss :parameters () :effect (probabilistic 1/2 (done)))",
     "PPDDL, one schema per outcome"),
    ("(:action toss :parameters () :effect (forall (?c - coin) (when (got ?c) "
     "(increase (total-cost) 5))))", "PPDDL, normalised"),
])
def test_every_grounding_route_gives_each_ground_action_its_cost(last, route):
    """The ground action carries its cost beside its effect (GroundOp.cost), whichever
    grounder made it: take a costs its fee (3) plus 1; free states none (None); toss
    states its costs only inside its effect (0 outside)."""
    from gdq_pddl.planning.base import PlanningProblem

    problem = PlanningProblem.from_texts(
        ROUTES.replace("LAST", last), "(define (problem r) (:domain routes) (:objects a - coin)"
        " (:init (= (fee a) 3)) (:goal (and (got a) (done))))")
    costs = {op.name: op.cost for op in problem.learner_task.ops}
    want = {"(take a)": 4.0, "(free)": None} | ({"(toss)": 0.0} if "forall" in last else
                                                 {"(toss)": None} if last else {})
    assert costs == want, route


def test_an_overlay_cost_replaces_the_actions_cost_not_its_outcomes():
    """An overlay's cost for first (2) is the action's cost; the 6 its effect writes inside
    a forall stays the outcome's: the step pays 8 on either scale."""
    overlay = '[dynamics]\nname = "coins"\n\n[actions.first]\ncost = 2.0\n'
    for metric, first in ((GOAL_SCALE, -8.0), (OWN_SCALE, -8.0)):
        inst = PDDLInstance.from_texts(DOMAIN.replace("EFFECT", SIX["forall"]),
                                       PROBLEM.replace("METRIC", metric), overlay)
        assert first_rewards(inst, online=False)[0] == first
        assert first_rewards(inst, online=True)[0] == first
