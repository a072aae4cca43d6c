"""Door-route plan tables (gdq_pddl.abstraction.routes) against the full tolerant tables."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gdq_pddl.abstraction import OfficeAbstraction
from gdq_pddl.abstraction.routes import knowledge_edges, route_plan_table
from gdq_pddl.buildings import building_world
from gdq_pddl.envs.office import office_plan_table
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.planning import PlanningProblem
from gdq_pddl.resources import domain_text
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import load_world
from gdq_pddl.world_types import Task, office_problem

TOL = 0.3


def _problem(world, goal):
    start = next(p for p in world.positions if p != goal)
    return PlanningProblem.from_texts(domain_text(),
                                      office_problem(world, Task("t", start, goal)))


def _door_routes(world, table, state):
    """The door sequences (gothrough actions in order) of the plans from ``state``."""
    spaces = LearnerSpaces(world)
    names = {spaces.action("gothrough", p): p for p in world.door_at}
    return {tuple(names[a] for _, a in plan if a in names) for plan in table.plans_from(state)}


def _check_against_full(world, goal):
    full = office_plan_table(world, goal, "graph", TOL)
    routes = office_plan_table(world, goal, "graph", TOL, kind="routes")
    shortest = office_plan_table(world, goal, "graph", 0.0)
    assert np.array_equal(routes.length, full.length)
    for s in range(full.n_states):
        mine = {tuple(p) for p in routes.plans_from(s)}
        every = {tuple(p) for p in full.plans_from(s)}
        assert mine <= every, f"state {s}: a route plan is not a plan within {TOL}"
        assert {tuple(p) for p in shortest.plans_from(s)} <= mine
        assert _door_routes(world, routes, s) == _door_routes(world, full, s), f"state {s}"
        assert len(routes.plans_from(s)) <= len(shortest.plans_from(s)) + len(
            _door_routes(world, full, s))
        assert not (routes.first_actions[s] & ~full.first_actions[s]).any()
    return routes, full


@pytest.mark.parametrize("task", list("ABCDE"))
def test_route_plans_are_plans_within_the_tolerance_with_every_door_route(task):
    world = load_world()
    _check_against_full(world, world.task(task).goal)


def test_route_plans_on_a_building_keep_every_door_route_with_far_fewer_plans():
    world = building_world(100, 0)
    routes, full = _check_against_full(world, world.task("A").goal)
    assert len(routes.pair_state) * 3 < len(full.pair_state)


def test_task_c_keeps_the_detour_through_the_easy_doors():
    world = load_world()
    ctx = office_task_context(world, "C", darling_kind="routes")
    doors = [[a for _, a in p] for p in ctx.darling_plans.plans_from(ctx.s0)]
    spaces = LearnerSpaces(world)
    through = {spaces.action("gothrough", p): world.door_at[p].name for p in world.door_at}
    routes = {tuple(through[a] for a in plan if a in through) for plan in doors}
    # the shortest routes cross d0 or d2 (difficult), the best one the easy d1 and d3
    assert routes == {("d0", "d2"), ("d0", "d3"), ("d1", "d2"), ("d1", "d3"), ("d1", "d4")}


def test_knowledge_graph_distances_are_the_planner_lengths():
    world = building_world(100, 1)
    goal = world.task("A").goal
    shortest = office_plan_table(world, goal, "graph", 0.0)
    edges = knowledge_edges(OfficeAbstraction(world), _problem(world, goal))
    n = shortest.n_states
    dist = np.where(shortest.length == 0, 0, np.inf)
    for _ in range(n):  # Bellman-Ford on unit edges, backwards from the goal
        before = dist.copy()
        for s, _a, s2, _op in edges:
            dist[s] = min(dist[s], 1 + dist[s2])
        if np.array_equal(before, dist):
            break
    assert np.array_equal(np.where(np.isinf(dist), -1, dist).astype(int), shortest.length)


def test_negative_tolerance_and_unknown_kind_are_refused():
    world = load_world()
    goal = world.task("C").goal
    with pytest.raises(ValueError, match="unknown plan table kind"):
        office_plan_table(world, goal, "graph", TOL, kind="some")
    shortest = office_plan_table(world, goal, "graph", 0.0)
    with pytest.raises(ValueError, match="tolerance"):
        route_plan_table(OfficeAbstraction(world), _problem(world, goal), shortest, -0.1,
                         lambda a: True)


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_mask_reader_agrees_with_learner_state(data):
    world = load_world()
    abstraction = OfficeAbstraction(world)
    task = _problem(world, "p17").task
    read = abstraction.mask_reader(task)
    p = data.draw(st.sampled_from(world.positions))
    opened = data.draw(st.sets(st.sampled_from([d.name for d in world.doors])))
    atoms = {f"(at {p})"} | {f"({'open' if d.name in opened else 'closed'} {d.name})"
                             for d in world.doors}
    state = frozenset(atoms)
    assert read(task.mask(state)) == abstraction.learner_state(state)
