"""A PPDDL action whose conditional effects need too many STRIPS variants for the
per-query planners still runs on the state graph, which reads conditional effects
itself; only a query on the planner's STRIPS task is refused, naming the action."""

from __future__ import annotations

import pytest

from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.errors import PlanningError
from gdq_pddl.pddl import ppddl

DOMAIN = """(define (domain lamps) (:requirements :conditional-effects :probabilistic-effects)
  (:predicates (a) (b) (c) (done))
  (:action toggle :parameters ()
    :effect (and (when (a) (not (a))) (when (not (a)) (a))
                 (when (b) (not (b))) (when (not (b)) (b))))
  (:action light :parameters () :precondition (and (a) (b))
    :effect (probabilistic 1/2 (done))))
"""
PROBLEM = """(define (problem p) (:domain lamps) (:init) (:goal (done)))"""


def test_too_many_variants_leave_the_graph_whole_and_refuse_a_query(monkeypatch):
    monkeypatch.setattr(ppddl, "MAX_VARIANTS", 2)  # toggle needs 4 STRIPS variants
    inst = PDDLInstance.from_texts(DOMAIN, PROBLEM)
    planner_task = inst.problem.task
    assert "action toggle" in planner_task.incomplete
    assert all("toggle" not in op.name for op in planner_task.ops)
    # toggle flips a and b together: {} -> {a, b}; light then works half the time
    assert inst.n_states == 3  # {}, {a b}, {a b done}
    assert inst.plan_table().length[0] == 2
    # V* by hand (goal scale: r_max 20, cost 1, the 20th step's failure -20): in {a b}
    # at step t, light: 1/2 x 20 + 1/2 x (-1 + V(t + 1)), the last step 1/2 x 20 - 1/2 x 20;
    # from {} toggle first: V* = -1 + V(1)
    limit = inst.model.step_limit
    value = 0.5 * 20 + 0.5 * -20  # at step limit - 1
    for _ in range(limit - 2):  # steps limit - 2 down to 1
        value = 0.5 * 20 + 0.5 * (-1 + value)
    assert inst.optimal()["v_star"] == pytest.approx(-1 + value)
    with pytest.raises(PlanningError, match="action toggle.*use the state graph"):
        inst.problem.query("graph", None, None, 0.0)


def test_within_the_variants_nothing_is_missing():
    inst = PDDLInstance.from_texts(DOMAIN, PROBLEM)
    assert inst.problem.task.incomplete == ""
    assert sum("toggle" in op.name for op in inst.problem.task.ops) == 4
