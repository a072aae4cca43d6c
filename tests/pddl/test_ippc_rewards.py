"""PPDDL rewards (issue 22, item 1): ``(increase (reward) X)`` / ``(decrease (reward) X)``
at the top of an effect, inside ``probabilistic``, ``when`` and ``forall``; the metric."""

from __future__ import annotations

import pytest

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.pddl.ppddl import ground_ppddl

DOMAIN = """(define (domain r) (:requirements :typing :rewards)
  (:types coin)
  (:predicates (shiny ?c - coin) (held ?c - coin) (done))
  (:functions (worth ?c - coin))
  (:action take :parameters (?c - coin)
    :effect (and (held ?c) (increase (reward) (worth ?c)) (decrease (reward) 1)))
  (:action gamble
    :effect (probabilistic 1/4 (and (done) (increase (reward) 8)) 3/4 (decrease (reward) 2)))
  (:action polish
    :effect (and (done) (forall (?c - coin) (when (and (held ?c) (not (shiny ?c)))
                                                (and (shiny ?c) (increase (reward) 3)))))))
"""
PROBLEM = """(define (problem p) (:domain r) (:objects a b - coin)
  (:init (= (worth a) 4) (= (worth b) 6)) (:goal (done)) (:goal-reward 10)
  (:metric maximize (reward)))"""


def grounded():
    domain = parse_domain(DOMAIN)
    learner, _ = ground_ppddl(domain, parse_problem(PROBLEM, domain))
    return domain, learner, {op.name: op for op in learner.ops}


def test_rewards_are_read_where_they_stand():
    domain, learner, ops = grounded()
    assert domain.reward_effects
    take = next(a for a in domain.actions if a.name == "take")
    assert take.cost == (1.0,)  # a cost whatever happens stays the action's cost
    assert [r.sign for r in take.outcomes[0].rewards] == [1.0]
    assert [o.reward for o in ops["(take a)"].outcomes] == [4.0]
    assert [o.reward for o in ops["(take b)"].outcomes] == [6.0]
    assert sorted((o.probability, o.reward) for o in ops["(gamble)"].outcomes) == \
        [(0.25, 8.0), (0.75, -2.0)]


def test_a_reward_under_when_and_forall_counts_each_binding_that_holds():
    _, learner, ops = grounded()
    polish = ops["(polish)"].outcomes[0]
    m = {f: 1 << i for i, f in enumerate(learner.facts)}
    held_a, held_b, shiny_a = m["(held a)"], m["(held b)"], m["(shiny a)"]
    assert polish.gain(0) == 0.0
    assert polish.gain(held_a) == 3.0
    assert polish.gain(held_a | held_b) == 6.0
    assert polish.gain(held_a | held_b | shiny_a) == 3.0


def test_the_metric_is_kept_and_others_refused():
    domain = parse_domain(DOMAIN)
    assert parse_problem(PROBLEM, domain).metric == "maximize (reward)"
    bad = PROBLEM.replace("maximize (reward)", "minimize (total-time)")
    with pytest.raises(PDDLError, match=r"^p.pddl:3: \(:metric minimize \(total-time\)\) is "
                                        r"not supported: the metrics read are"):
        parse_problem(bad, domain, "p.pddl")


def test_a_negative_function_value_in_a_reward_is_refused_naming_it():
    domain = parse_domain(DOMAIN)
    problem = parse_problem(PROBLEM.replace("(= (worth b) 6)", "(= (worth b) -6)"), domain,
                            "p.pddl")
    with pytest.raises(PDDLError, match=r"^p.pddl: \(worth b\) = -6 in :init: a reward of "
                                        r"take must be >= 0"):
        ground_ppddl(domain, problem)
