"""Grounding's progress bars (:func:`~gdq_pddl.limits.slow_progress`): relaxed
reachability counts the ground actions it finds reachable, and a bar is closed before an
error raised mid-way leaves grounding (so the error's message is not printed under a
bar still on screen)."""

from __future__ import annotations

import pytest

from gdq_pddl.pddl import grounding, parse_domain, parse_problem

# A road n0 -> n1 -> ... -> n5, and a road m0 -> m1 that cannot be reached from n0.
ROAD = """(define (domain road) (:requirements :typing)
  (:types place) (:predicates (at ?p - place) (road ?a ?b - place))
  (:action go :parameters (?a ?b - place) :precondition (and (at ?a) (road ?a ?b))
    :effect (and (at ?b) (not (at ?a)))))
"""
PROBLEM = """(define (problem trip) (:domain road)
  (:objects n0 n1 n2 n3 n4 n5 m0 m1 - place)
  (:init (at n0) (road n4 n5) (road n3 n4) (road n2 n3) (road n1 n2) (road n0 n1)
         (road m0 m1))
  (:goal (at n5)))
"""


def test_relaxed_reachability_counts_the_reachable_ground_actions(bars):
    domain = parse_domain(ROAD)
    task = grounding.ground(domain, parse_problem(PROBLEM, domain))
    assert sorted(op.name for op in task.ops) == [f"(go n{i} n{i + 1})" for i in range(5)]
    [bar] = [b for b in bars if b.desc == "relaxed reachability"]
    assert (bar.n, bar.total) == (5, 6)  # 5 of the 6 ground actions: not (go m0 m1)
    assert all(b.disable for b in bars)  # every bar closed


def test_a_bar_is_closed_before_an_error_leaves_grounding(bars, monkeypatch):
    real, calls = grounding.ground_outcomes, []

    def failing(*args):
        calls.append(args)
        if len(calls) == 3:
            raise RuntimeError("mid-way")
        return real(*args)

    monkeypatch.setattr(grounding, "ground_outcomes", failing)
    domain = parse_domain(ROAD)
    with pytest.raises(RuntimeError, match="mid-way") as error:
        grounding.ground(domain, parse_problem(PROBLEM, domain))
    # checked while the error, and so its traceback's frames, are alive: a bar left to
    # close when they are freed would still be open here
    [bar] = [b for b in bars if b.desc == "grounding"]
    assert bar.disable and len(calls) == 3
    assert error.value.__traceback__ is not None


def test_the_ppddl_grounders_relaxed_reachability_counts_too(bars):
    """The same road with a conditional effect goes through PPDDL's grounder."""
    from gdq_pddl.pddl.ppddl import ground_ppddl

    text = ROAD.replace("(and (at ?b) (not (at ?a)))",
                        "(and (at ?b) (not (at ?a)) (when (at ?a) (at ?a)))")
    domain = parse_domain(text)
    learner, _ = ground_ppddl(domain, parse_problem(PROBLEM, domain))
    assert len(learner.ops) == 5
    [bar] = [b for b in bars if b.desc == "relaxed reachability"]
    assert (bar.n, bar.total) == (5, 6) and bar.disable
