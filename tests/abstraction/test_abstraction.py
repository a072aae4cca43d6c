"""O and its inverse for the office."""

from __future__ import annotations

import pytest

from gdq_pddl.abstraction import OfficeAbstraction, build_plan_table
from gdq_pddl.errors import AbstractionError
from gdq_pddl.planning import PlanningProblem, get_planner
from gdq_pddl.resources import domain_text
from gdq_pddl.world import load_world
from gdq_pddl.world_types import office_problem


@pytest.fixture(scope="module")
def office():
    world = load_world()
    return world, OfficeAbstraction(world)


def test_inverse_then_forward_is_the_identity_on_states(office):
    _, ab = office
    for s in range(ab.n_states):
        assert ab.learner_state(ab.planner_state(s)) == s


def test_actions_map_to_the_named_verb_and_position(office):
    _, ab = office
    sp = ab.spaces
    assert sp.action_name(ab.learner_action("(approach p0 p2 d1)")) == "approach p2"
    assert sp.action_name(ab.learner_action("(opendoor p2 d1)")) == "opendoor p2"
    assert sp.action_name(ab.learner_action("(gothrough p2 p4 d1)")) == "gothrough p4"
    assert sp.action_name(ab.learner_action("(goto p4 p8)")) == "goto p8"


@pytest.mark.parametrize("bad", ["(fly p0 p1)", "(goto p0 p99)", "()", "(goto p0)"])
def test_unmappable_action_is_a_loud_error(office, bad):
    with pytest.raises(AbstractionError, match="planner action"):
        office[1].learner_action(bad)


def test_unmappable_state_is_a_loud_error(office):
    with pytest.raises(AbstractionError, match="no single known"):
        office[1].learner_state(frozenset({"(closed d0)"}))


@pytest.mark.parametrize("task", ["A", "B", "C", "D", "E"])
def test_o_is_total_over_every_plan_pair(office, task):
    world, ab = office
    problem = PlanningProblem.from_texts(domain_text(), office_problem(world, world.task(task)))
    goal = ab.goal(world.task(task).goal)
    for tolerance in (0.0, 0.3):
        table = build_plan_table(ab, problem, get_planner("graph"), goal, tolerance)
        # every learner state but the goal's has a plan in the office
        goal_states = {ab.spaces.state(world.task(task).goal, o) for o in (False, True)}
        for s in range(ab.n_states):
            assert (table.length[s] == 0) == (s in goal_states)
            for plan in table.plans_from(s):
                assert plan[0][0] == s
        first = table.first_actions.sum(axis=1)
        assert (first[table.length > 0] >= 1).all()


def test_plan_cap_warns_and_marks_the_result_capped():
    from gdq_pddl.planning.graph import GraphPlanner

    world = load_world()
    problem = PlanningProblem.from_texts(domain_text(), office_problem(world, world.task("D")))
    with pytest.warns(UserWarning, match="more than 4 plans"):
        result = GraphPlanner(max_plans=4).solve(problem, tolerance=0.3)
    assert result.capped and len(result.plans) == 4
    full = GraphPlanner().solve(problem, tolerance=0.3)
    assert not full.capped and len(full.plans) > 4
