"""One ground effect and one grounder (issue 38, item 2): a STRIPS action is the ground
action with one unconditional outcome of probability 1, a PPDDL domain and a STRIPS one
go through the same grounder, and the order of ground actions (the env's action numbers)
is each domain's as before."""

from __future__ import annotations

from dataclasses import replace

import pytest

from gdq_pddl.pddl import GroundOp, GroundOutcome, ground, parse_domain, parse_problem
from gdq_pddl.pddl.ppddl import ground_ppddl

# a ring of roads a -> b -> c -> a, starting at c: the sorted bindings are (go a b),
# (go b c), (go c a); relaxed reachability finds (go c a) first
RING = """(define (domain ring) (:requirements :typing)
  (:types place) (:predicates (at ?p - place) (road ?a ?b - place))
  (:action go :parameters (?a ?b - place) :precondition (and (at ?a) (road ?a ?b))
    :effect (and (at ?b) (not (at ?a)))))
"""
RING_PROBLEM = """(define (problem loop) (:domain ring) (:objects a b c - place)
  (:init (at c) (road a b) (road b c) (road c a)) (:goal (at b)))
"""
COIN = """(define (domain coin) (:requirements :probabilistic-effects)
  (:predicates (heads) (tails) (done))
  (:action flip :parameters () :precondition (not (done))
    :effect (probabilistic 0.5 (heads) 0.5 (tails)))
  (:action stop :parameters () :precondition (heads) :effect (done)))
"""
COIN_PROBLEM = "(define (problem p) (:domain coin) (:init) (:goal (done)))"


def grounded(domain_text: str, problem_text: str):
    domain = parse_domain(domain_text, "d.pddl")
    return domain, parse_problem(problem_text, domain, "p.pddl")


def test_a_strips_action_is_one_unconditional_outcome():
    task = ground(*grounded(RING, RING_PROBLEM))
    for op in task.ops:
        [outcome] = op.outcomes
        assert outcome == GroundOutcome(1.0, op.add, op.dele) and op.known == (0,)
        assert op == GroundOp.strips(op.name, op.pre, op.neg, op.add, op.dele, op.cost)
        assert op.apply(task.init) == outcome.apply(task.init)


def test_an_action_of_several_outcomes_has_no_single_effect():
    learner, planner = ground_ppddl(*grounded(COIN, COIN_PROBLEM))
    flip = next(op for op in learner.ops if op.name == "(flip)")
    assert len(flip.outcomes) == 2
    with pytest.raises(TypeError, match="no single unconditional effect"):
        _ = flip.add
    with pytest.raises(TypeError, match="no single unconditional effect"):
        flip.apply(learner.init)
    # the determinisation's actions are STRIPS ones: one outcome each
    assert sorted(op.name for op in planner.ops) == ["(flip_o1)", "(flip_o2)", "(stop)"]
    assert all(len(op.outcomes) == 1 for op in planner.ops)


def test_one_grounder_for_ppddl_and_strips():
    """``ground`` grounds a PPDDL domain (it refused one before): the same ground actions
    as reality's task of ``ground_ppddl``."""
    domain, problem = grounded(COIN, COIN_PROBLEM)
    task = ground(domain, problem)
    learner, _ = ground_ppddl(domain, problem)
    assert task.ops == learner.ops and task.facts == learner.facts


def test_an_action_name_with_a_hash_grounds_as_any_other():
    """Outcome numbers are no longer coded into names: a domain built in Python whose
    action name has a '#' grounds (it was refused while a fast path split names there)."""
    domain, problem = grounded(COIN, COIN_PROBLEM)
    hashed = replace(domain, actions=tuple(replace(a, name=a.name + "#1") if a.name == "flip"
                                           else a for a in domain.actions))
    learner, planner = ground_ppddl(hashed, problem)
    assert [op.name for op in learner.ops] == ["(flip#1)", "(stop)"]
    assert [len(op.outcomes) for op in learner.ops] == [2, 1]
    assert planner.ops[0].name == "(flip#1_o1)"


def test_a_plain_domain_keeps_the_order_relaxed_reachability_finds():
    task = ground(*grounded(RING, RING_PROBLEM))
    assert [op.name for op in task.ops] == ["(go c a)", "(go a b)", "(go b c)"]


def test_a_domain_with_conditional_effects_keeps_binding_order():
    text = RING.replace("(and (at ?b) (not (at ?a)))",
                        "(and (at ?b) (not (at ?a)) (when (at ?a) (at ?a)))")
    learner, _ = ground_ppddl(*grounded(text, RING_PROBLEM))
    assert [op.name for op in learner.ops] == ["(go a b)", "(go b c)", "(go c a)"]


def test_a_plain_domain_keeps_a_ground_action_whose_precondition_contradicts_itself():
    """(go ?a ?b) needs (at ?a) and not (at ?b): (go a a) never applies, and stays a ground
    action (an action number) as it always was; a domain that normalises its conditions
    (here, for a `when`) has none such."""
    text = RING.replace("(and (at ?a) (road ?a ?b))", "(and (at ?a) (not (at ?b)))")
    plain = ground(*grounded(text, RING_PROBLEM))
    assert len(plain.ops) == 9 and "(go a a)" in {op.name for op in plain.ops}
    never = next(op for op in plain.ops if op.name == "(go a a)")
    assert never.pre & never.neg and not any(never.holds(s) for s in range(8))
    when = text.replace("(and (at ?b) (not (at ?a)))",
                        "(and (at ?b) (not (at ?a)) (when (at ?a) (at ?a)))")
    learner, _ = ground_ppddl(*grounded(when, RING_PROBLEM))
    assert len(learner.ops) == 6 and "(go a a)" not in {op.name for op in learner.ops}
