"""Planner backends agree on the office: lengths, plan sets, validity, and NO_PLAN."""

from __future__ import annotations

from pathlib import Path

import pytest

from gdq_pddl.errors import PlanningError
from gdq_pddl.planning import Plan, PlanningProblem, Status, get_planner, planners
from gdq_pddl.planning.clingo_backend import ClingoPlanner
from gdq_pddl.planning.graph import GraphPlanner
from gdq_pddl.planning.pyperplan_backend import PyperplanPlanner
from gdq_pddl.planning.validate import validate_plan
from gdq_pddl.world import load_world
from gdq_pddl.world_types import office_problem

LENGTHS = {"A": 5, "B": 4, "C": 8, "D": 9}
COUNTS = {"C": 2, "D": 3}
TASKS = ["A", "B", "C", "D", "E", "X"]
PAIRS = [("p0", "p1"), ("p3", "p17"), ("p18", "p0"), ("p12", "p9")]
DOORS_CLOSED = frozenset(f"(closed d{i})" for i in range(6))
AT_P3_D0_OPEN = DOORS_CLOSED - {"(closed d0)"} | {"(at p3)", "(open d0)"}

needs_clingo = pytest.mark.skipif(ClingoPlanner.unusable_reason() is not None,
                                  reason=ClingoPlanner.unusable_reason() or "")

# A corridor a - b, and a door d between c and e that no walkway leads to.
CUT_OFF = """(define (problem cut-off) (:domain office)
  (:objects a b c e - position d - door)
  (:init (at a) (floor a) (floor b) (walkway a b) (walkway b a)
         (door-side c d) (door-side e d) (connects d c e) (connects d e c) (closed d))
  (:goal (at e)))"""


def _domain_text() -> str:
    """The shipped domain; from the source tree when the package is not installed."""
    from gdq_pddl.resources import domain_text

    try:
        return domain_text()
    except OSError:
        return (Path(__file__).resolve().parents[2] / "domains" / "office.pddl").read_text()


@pytest.fixture(scope="module")
def domain() -> str:
    return _domain_text()


@pytest.fixture(scope="module")
def problems(domain: str) -> dict[str, PlanningProblem]:
    """One problem per task and per extra start/goal pair, shared by the module's tests."""
    world = load_world()
    out = {t: PlanningProblem.from_texts(domain, office_problem(world, world.task(t)))
           for t in TASKS}
    for s, g in PAIRS:
        task = world.resolve(start=s, goal=g)
        out[task.name] = PlanningProblem.from_texts(domain, office_problem(world, task))
    return out


ALL = TASKS + [f"{s}-{g}" for s, g in PAIRS]


def actions(result) -> set[tuple[str, ...]]:
    return {p.actions for p in result.plans}


@pytest.mark.parametrize("task", sorted(LENGTHS))
def test_graph_lengths_and_counts(problems, task):
    result = GraphPlanner().solve(problems[task])
    assert result.status is Status.SOLVED
    assert result.length == LENGTHS[task]
    assert len(result.plans) == COUNTS.get(task, 1)
    assert all(len(p) == LENGTHS[task] for p in result.plans)


@pytest.mark.parametrize("task", sorted(LENGTHS))
def test_pyperplan_finds_a_shortest_plan(problems, task):
    result = PyperplanPlanner().solve(problems[task])
    assert result.status is Status.SOLVED
    assert len(result.plans) == 1
    assert result.length == LENGTHS[task]
    assert result.plans[0].actions in actions(GraphPlanner().solve(problems[task]))
    validate_plan(problems[task], result.plans[0])


@pytest.mark.slow
@pytest.mark.parametrize("task", ALL)
def test_pyperplan_agrees_with_graph_everywhere(problems, task):
    graph = GraphPlanner().solve(problems[task])
    for tolerance in (0.0, 0.3):
        result = PyperplanPlanner().solve(problems[task], tolerance=tolerance)
        assert result.length == graph.length
        assert result.plans[0].actions in actions(graph)


@needs_clingo
@pytest.mark.parametrize("tolerance", [0.0, 0.3])
@pytest.mark.parametrize("task", ALL)
def test_clingo_finds_the_same_plans_as_graph(problems, task, tolerance):
    graph = GraphPlanner().solve(problems[task], tolerance=tolerance)
    result = ClingoPlanner().solve(problems[task], tolerance=tolerance)
    assert result.status is Status.SOLVED
    assert actions(result) == actions(graph)
    assert [p.states for p in result.plans] == [p.states for p in graph.plans]


@pytest.mark.parametrize("task", ALL)
def test_every_graph_plan_validates(problems, task):
    for tolerance in (0.0, 0.3):
        for plan in GraphPlanner().solve(problems[task], tolerance=tolerance).plans:
            validate_plan(problems[task], plan)


@needs_clingo
@pytest.mark.parametrize("task", TASKS)
def test_every_clingo_plan_validates(problems, task):
    for plan in ClingoPlanner().solve(problems[task], tolerance=0.3).plans:
        validate_plan(problems[task], plan)


def _backends():
    return [GraphPlanner(), PyperplanPlanner(),
            pytest.param(ClingoPlanner(), marks=needs_clingo)]


@pytest.mark.parametrize("planner", _backends(), ids=lambda p: p.name)
def test_from_a_state_other_than_init(problems, planner):
    problem = problems["C"]
    p0, p17 = frozenset({"(at p0)"}), frozenset({"(at p17)"})
    to_p0 = planner.solve(problem, start=AT_P3_D0_OPEN, goal=p0)
    assert [p.actions for p in to_p0.plans] == [("(gothrough p3 p1 d0)", "(goto p1 p0)")]
    assert to_p0.plans[0].states[0] == AT_P3_D0_OPEN
    to_p17 = planner.solve(problem, start=AT_P3_D0_OPEN, goal=p17)
    assert to_p17.length == 5
    for goal, result in ((p0, to_p0), (p17, to_p17)):
        for plan in result.plans:
            assert "(open d0)" in plan.states[-1]  # the open door stays open
            validate_plan(problem, plan, start=AT_P3_D0_OPEN, goal=goal)


@pytest.mark.parametrize("planner", _backends(), ids=lambda p: p.name)
def test_start_is_already_a_goal(problems, planner):
    result = planner.solve(problems["C"], goal=frozenset({"(at p0)"}))
    assert result.status is Status.SOLVED
    assert [p.actions for p in result.plans] == [()]
    assert len(result.plans[0].states) == 1


@pytest.mark.parametrize("planner", _backends(), ids=lambda p: p.name)
def test_unreachable_goals_give_no_plan(problems, domain, planner):
    contradictory = frozenset({"(open d0)", "(closed d0)"})  # no action closes a door
    result = planner.solve(problems["C"], goal=contradictory)
    assert result.status is Status.NO_PLAN
    assert result.plans == () and result.length is None
    cut_off = PlanningProblem.from_texts(domain, CUT_OFF)
    assert planner.solve(cut_off).status is Status.NO_PLAN
    assert planner.solve(cut_off, goal=frozenset({"(at b)"})).length == 1


@pytest.mark.parametrize("planner", _backends(), ids=lambda p: p.name)
def test_cache_returns_the_same_object(problems, planner):
    first = planner.solve(problems["B"], tolerance=0.3)
    assert planner.solve(problems["B"], tolerance=0.3) is first


@pytest.mark.parametrize("planner", _backends(), ids=lambda p: p.name)
def test_negative_tolerance_and_unknown_atoms_are_errors(problems, planner):
    with pytest.raises(PlanningError, match="tolerance"):
        planner.solve(problems["A"], tolerance=-0.1)
    with pytest.raises(PlanningError, match="p99"):
        planner.solve(problems["A"], start=frozenset({"(at p99)"}))


def test_validator_rejects_bad_plans(problems):
    problem = problems["C"]
    plan = GraphPlanner().solve(problem).plans[0]
    swapped = Plan(plan.actions[1:2] + plan.actions[:1] + plan.actions[2:], plan.states)
    with pytest.raises(PlanningError, match="inapplicable action"):
        validate_plan(problem, swapped)
    short = Plan(plan.actions[:-1], plan.states[:-1])
    with pytest.raises(PlanningError, match="unsatisfied goals"):
        validate_plan(problem, short)
    wrong_states = Plan(plan.actions, plan.states[:1] + plan.states[:-1])
    with pytest.raises(PlanningError, match="state 1"):
        validate_plan(problem, wrong_states)
    with pytest.raises(PlanningError, match="not an action"):
        validate_plan(problem, Plan(("(fly p0 p17)",), plan.states[:1] + plan.states[-1:]))


def test_unknown_planner_lists_the_known_ones():
    with pytest.raises(PlanningError, match="unknown planner 'nope'") as err:
        get_planner("nope")
    for name in ("graph", "pyperplan", "clingo"):
        assert name in str(err.value)


def test_registry_lists_the_builtin_backends():
    found = {info.name: info for info in planners()}
    assert found["graph"].usable and found["pyperplan"].usable
    assert found["clingo"].usable == (ClingoPlanner.unusable_reason() is None)
    assert isinstance(get_planner("pyperplan").backend, PyperplanPlanner)


def test_clingo_says_how_to_install_it(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "clingo", None)  # makes `import clingo` fail
    assert ClingoPlanner.unusable_reason() == (
        "the optional package clingo is not installed (pip install gdq_pddl[clingo])")
