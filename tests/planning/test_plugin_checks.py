"""Planner plugins are untrusted input (issue 38): every answer is replayed on the knowledge,
a plugin's failure is one line naming it, and a name cannot be registered twice.

The plugins are real distributions: a ``*.dist-info`` folder and a module written into a
temporary directory put on ``sys.path``, found by ``importlib.metadata`` as any installed
package is.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from gdq_pddl.errors import PlanningError
from gdq_pddl.planning import Plan, PlanResult, Status, get_planner, planners
from gdq_pddl.planning.checked import CheckedPlanner
from gdq_pddl.planning.graph import GraphPlanner
from tests.cli.hostile import refused
from tests.helpers import cli

PLUGIN = '''
from gdq_pddl.planning import Plan, PlanResult, Status
from gdq_pddl.planning.graph import GraphPlanner


class Base:
    name = "base"
    all_plans = False

    @classmethod
    def unusable_reason(cls):
        return None

    def edit(self, plan):
        return plan

    def solve(self, problem, start=None, goal=None, tolerance=0.0):
        good = GraphPlanner().solve(problem, start, goal, tolerance)
        if not good.plans:
            return good
        return PlanResult(Status.SOLVED, (self.edit(good.plans[0]),), self.name, {})


class Good(Base):
    pass


class Swapped(Base):  # steps 1 and 2 exchanged: step 1 is not applicable
    def edit(self, p):
        return Plan(p.actions[1:2] + p.actions[:1] + p.actions[2:], p.states)


class Short(Base):  # stops one step short of the goal
    def edit(self, p):
        return Plan(p.actions[:-1], p.states[:-1])


class Unknown(Base):  # an action the domain does not have
    def edit(self, p):
        return Plan(("(fly p0 p17)",) + p.actions[1:], p.states)


class Mismatch(Base):  # states that are not the ones the actions lead through
    def edit(self, p):
        return Plan(p.actions, p.states[:1] + p.states[:-1])


class Blind(Base):  # says there is no plan where there is one
    def solve(self, problem, start=None, goal=None, tolerance=0.0):
        return PlanResult(Status.NO_PLAN, (), self.name, {})


class Raises(Base):
    def solve(self, problem, start=None, goal=None, tolerance=0.0):
        raise RuntimeError("boom\\non two lines")


class ReturnsNone(Base):
    def solve(self, problem, start=None, goal=None, tolerance=0.0):
        return None


class BadReason(Base):
    @classmethod
    def unusable_reason(cls):
        raise ValueError("cannot tell")


class Shadow(Base):  # registered as "graph": must not replace the built-in
    pass
'''

NAMES = {"good": "Good", "swapped": "Swapped", "short": "Short", "unknown": "Unknown",
         "mismatch": "Mismatch", "blind": "Blind", "raises": "Raises", "none": "ReturnsNone",
         "badreason": "BadReason"}


def _dist(root: Path, dist: str, entries: dict[str, str]) -> None:
    info = root / f"{dist}-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        "[gdq_pddl.planners]\n" + "".join(f"{k} = {v}\n" for k, v in entries.items()))


@pytest.fixture
def plugins(tmp_path, monkeypatch):
    """Three distributions: ``hostile-planners`` (every plugin above, one name each), and
    two that both register ``twice``."""
    (tmp_path / "hostile_planners.py").write_text(PLUGIN)
    _dist(tmp_path, "hostile_planners", {k: f"hostile_planners:{v}" for k, v in NAMES.items()})
    _dist(tmp_path, "first_dist", {"twice": "hostile_planners:Good"})
    _dist(tmp_path, "second_dist", {"twice": "hostile_planners:Good"})
    monkeypatch.syspath_prepend(str(tmp_path))
    get_planner.cache_clear()
    yield tmp_path
    get_planner.cache_clear()
    sys.modules.pop("hostile_planners", None)


@pytest.fixture
def office_c():
    from gdq_pddl.planning import PlanningProblem
    from gdq_pddl.resources import domain_text
    from gdq_pddl.world import load_world, office_problem

    world = load_world()
    return PlanningProblem.from_texts(domain_text(), office_problem(world, world.task("C")))


def test_a_good_plugin_passes_the_checks(plugins, office_c):
    result = get_planner("good").solve(office_c)
    assert result.status is Status.SOLVED and result.length == 8


@pytest.mark.parametrize(("name", "words"), [
    ("swapped", ["'swapped'", "step 1", "not applicable", "does not hold"]),
    ("short", ["'short'", "stops short of the goal after 7 step(s)"]),
    ("unknown", ["'unknown'", "step 1 (fly p0 p17)", "not an action"]),
    ("mismatch", ["'mismatch'", "step 1", "not the one it leads to"]),
    ("blind", ["'blind'", "says there is no plan", "'graph' finds one of 8 actions"]),
    ("raises", ["'raises'", "RuntimeError: boom on two lines"]),
    ("none", ["'none'", "returned NoneType where a PlanResult was expected"]),
    ("badreason", ["'badreason'", "unusable_reason()", "ValueError: cannot tell"]),
])
def test_a_bad_answer_is_refused_naming_the_planner_and_the_step(plugins, office_c, capsys,
                                                                  name, words):
    with pytest.raises(PlanningError) as err:
        get_planner(name).solve(office_c)
    message = str(err.value)
    assert "\n" not in message
    for word in words:
        assert word in message, message
    code, text = cli(capsys, "plan", "--task", "C", "--planner", name)
    refused(code, text, *words)
    assert code == 2 and len(text.strip().splitlines()) == 1, text


def test_run_refuses_a_bad_plan_before_learning_from_it(plugins, capsys, tmp_path):
    code, text = cli(capsys, "run", "--task", "C", "--method", "GDQ-literal", "--episodes", "1",
                     "--runs", "1", "--jobs", "1", "--planner", "swapped", "--out",
                     tmp_path / "out")
    refused(code, text, "'swapped'", "step 1", "not applicable")
    assert code == 2


def test_a_built_in_name_cannot_be_shadowed(plugins, office_c, capsys, monkeypatch):
    shadow = plugins / "shadow"
    _dist(shadow, "shadow_planner", {"graph": "hostile_planners:Shadow"})
    monkeypatch.syspath_prepend(str(shadow))
    with pytest.raises(PlanningError, match="built-in planner name 'graph'.*shadow-planner"):
        get_planner("graph")
    code, text = cli(capsys, "plan", "--task", "C")
    refused(code, text, "graph", "shadow-planner")
    listed = {i.name: i for i in planners()}
    assert not listed["graph"].usable and "shadow-planner" in listed["graph"].reason
    assert listed["good"].usable and listed["pyperplan"].usable


def test_a_name_two_distributions_register_is_refused_naming_both(plugins):
    with pytest.raises(PlanningError, match="two distributions") as err:
        get_planner("twice")
    assert "first-dist" in str(err.value) and "second-dist" in str(err.value)
    assert not {i.name: i for i in planners()}["twice"].usable


def test_bad_result_shapes_are_refused(office_c):
    class Lying(GraphPlanner):
        answer: object = None

        def solve(self, problem, start=None, goal=None, tolerance=0.0):
            return self.answer

    good = GraphPlanner().solve(office_c)
    plan = good.plans[0]
    cases = {
        "'solved' is not Status": PlanResult("solved", good.plans, "x"),
        "says no plan but returned 1": PlanResult(Status.NO_PLAN, good.plans[:1], "x"),
        "says solved but returned no plan": PlanResult(Status.SOLVED, (), "x"),
        "plans must be a tuple of Plan": PlanResult(Status.SOLVED, [plan], "x"),
        "states must be a tuple of 9": PlanResult(Status.SOLVED,
                                                  (Plan(plan.actions, plan.states[:-1]),), "x"),
        "first state is not the query's start": PlanResult(
            Status.SOLVED, (Plan(plan.actions, (frozenset(),) + plan.states[1:]),), "x"),
        "unknown atom (at nowhere)": PlanResult(
            Status.SOLVED, (Plan(plan.actions, (plan.states[0] | {"(at nowhere)"},)
                                 + plan.states[1:]),), "x"),
    }
    for words, answer in cases.items():
        lying = Lying()
        lying.answer = answer
        with pytest.raises(PlanningError, match="planner 'liar'") as err:
            CheckedPlanner("liar", lying).solve(office_c)
        assert words in str(err.value), str(err.value)


def test_a_plan_past_the_goal_is_refused(office_c):
    """Plans end where the goal first holds: one that goes on after it is refused, and the
    empty plan from a goal state is right."""
    class Beyond(GraphPlanner):
        def solve(self, problem, start=None, goal=None, tolerance=0.0):
            plan = super().solve(problem, start, goal, tolerance).plans[0]
            task = problem.task
            end = task.mask(plan.states[-1])
            op, after = task.successors(end)[0]
            longer = Plan(plan.actions + (op.name,), plan.states + (task.atoms(after),))
            return PlanResult(Status.SOLVED, (longer,), self.name, {})

    with pytest.raises(PlanningError, match="step 9 .*the goal already holds before"):
        CheckedPlanner("beyond", Beyond()).solve(office_c, tolerance=0.5)
    at_goal = GraphPlanner().solve(office_c).plans[0].states[-1]
    assert CheckedPlanner("graph", GraphPlanner()).solve(office_c, start=at_goal).length == 0
