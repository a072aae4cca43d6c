"""PPDDL input, what it means: the determinisations and O, the true model, the overlay,
and the shipped keys domain in PPDDL (the same true model as keys.pddl with
keys.toml). The reader is tested in test_ppddl_reader.py, the env and the command
line in test_ppddl_env_cli.py."""

from __future__ import annotations

import numpy as np
import pytest

from gdq_pddl.abstraction.pddl import PDDLAbstraction, graph_plan_table
from gdq_pddl.abstraction.table import build_plan_table
from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLInstance
from gdq_pddl.envs.solve import expected_costs, solve
from gdq_pddl.errors import PlanningError, WorldError
from gdq_pddl.planning import PlanningProblem, get_planner
from gdq_pddl.planning.validate import validate_plan
from tests.helpers import DYNAMICS as DYN
from tests.helpers import REPO_ROOT as ROOT
from tests.pddl.hike import HIKE_DOMAIN, HIKE_PROBLEM, action, hike, outcomes, state_with

# --- determinisations and O --------------------------------------------------------

def test_all_outcomes_plans_with_every_outcome_and_o_maps_back():
    inst = hike()
    planner_ops = [op.name for op in inst.problem.task.ops]
    # walk has one outcome that does something: it keeps its name; wade has two
    assert "(walk w1 w2)" in planner_ops
    assert {"(wade_o1 w2 e2 e3)", "(wade_o2 w2 e2 e3)"} <= set(planner_ops)
    assert not any(name.startswith("(wade_o3") for name in planner_ops)  # stuck: never
    o = PDDLAbstraction(inst.graph)
    for name in ("(wade_o1 w2 e2 e3)", "(wade_o2 w2 e2 e3)", "(wade w2 e2 e3)"):
        assert inst.action_name(o.learner_action(name)) == "(wade w2 e2 e3)"
    assert inst.action_name(o.learner_action("(walk w1 w2)")) == "(walk w1 w2)"
    with pytest.raises(Exception, match="not a ground action"):
        o.learner_action("(wade_o9 w2 e2 e3)")
    # the state graph has both of wade's outcomes as edges of the one ground action
    w2 = state_with(inst, "(at w2)")
    wade = action(inst, "(wade w2 e2 e3)")
    nexts = {next(iter(inst.atoms(t))) for a, t in inst.graph.edges(w2) if a == wade}
    assert nexts == {"(at e2)", "(at e3)"}


def test_most_likely_keeps_one_outcome_per_action():
    inst = hike("most-likely")
    assert {op.name for op in inst.problem.task.ops} == {op.name for op in inst.graph.task.ops}
    w2 = state_with(inst, "(at w2)")
    wade = action(inst, "(wade w2 e2 e3)")
    assert [inst.atoms(t) for a, t in inst.graph.edges(w2) if a == wade] == [{"(at e2)"}]
    # reality is the same whatever the planner knows
    np.testing.assert_array_equal(inst.model.prob, hike().model.prob)


def test_most_likely_can_leave_a_goal_without_plan():
    """Where only an unlikely outcome leads on, most-likely knows no way there."""
    # wading now does nothing 4 times in 10, its likeliest outcome; no bridge
    text = HIKE_DOMAIN.replace("0.5 (and (at ?b)", "0.2 (and (at ?b)")
    problem = HIKE_PROBLEM.replace("(trail w4 e4) (trail e4 w4)", "")
    every = PDDLInstance.from_texts(text, problem)
    likely = PDDLInstance.from_texts(text, problem, determinisation="most-likely")
    assert every.n_states == likely.n_states  # reality reaches e1 either way
    assert graph_plan_table(every.graph).length[0] == 3  # walk, wade_o1, walk
    assert graph_plan_table(likely.graph).length[0] == -1


def test_a_planner_on_the_determinised_pddl_plans_in_ground_actions():
    inst = hike()
    o = PDDLAbstraction(inst.graph)
    states = list(range(inst.n_states))
    table = build_plan_table(o, inst.problem, get_planner("pyperplan"), o.goal(), 0.0, states)
    fast = graph_plan_table(inst.graph)
    for s in states:
        plans = table.plans_from(s)
        assert table.length[s] == fast.length[s]
        if plans:
            assert plans[0] in fast.plans_from(s), s
    result = get_planner("pyperplan").solve(inst.problem)
    validate_plan(inst.problem, result.plans[0])  # unified-planning reads the written PDDL
    assert any("wade_o" in a for a in result.plans[0].actions)


def test_unknown_determinisation_is_an_error():
    with pytest.raises(PlanningError, match="unknown determinisation 'best'"):
        hike("best")


# --- the true model ------------------------------------------------------------------

def test_reality_is_the_probabilistic_model():
    inst = hike()
    m = inst.model
    counts = np.diff(m.ptr)
    np.testing.assert_allclose(np.add.reduceat(m.prob, m.ptr[:-1][counts > 0]), 1.0)
    w2 = state_with(inst, "(at w2)")
    assert outcomes(inst, w2, action(inst, "(wade w2 e2 e3)")) == pytest.approx(
        {("(at e2)", False): 0.5, ("(at e3)", False): 0.3, ("(at w2)", True): 0.1,
         ("(at w2)", False): 0.1})
    assert outcomes(inst, w2, action(inst, "(walk w2 w3)")) == pytest.approx(
        {("(at w3)", False): 0.9, ("(at w2)", False): 0.1})
    assert outcomes(inst, w2, action(inst, "(walk e1 e2)")) == {("(at w2)", False): 1.0}
    assert inst.dynamics.r_max == 30.0  # (:goal-reward 30)
    # the fewest actions in reality: walk, wade_o1, walk (e2 -> e1): max(20, ceil(7.5))
    assert inst.dynamics.step_limit == 20


def test_default_step_limit_grows_with_the_plan():
    """A goal L = 12 actions away gets ceil(2.5 L) = 30 steps."""
    far = HIKE_PROBLEM.replace("(ford w2 e2 e3) (ford w3 e3 e4)", "") \
        .replace("(:objects w1 w2 w3 w4 e1 e2 e3 e4 - camp)",
                 "(:objects w1 w2 w3 w4 w5 w6 w7 e1 e2 e3 e4 e5 e6 - camp)") \
        .replace("(trail w4 e4) (trail e4 w4)",
                 "(trail w4 w5) (trail w5 w6) (trail w6 w7) (trail w7 e6) (trail e6 e5) "
                 "(trail e5 e4)")
    inst = PDDLInstance.from_texts(HIKE_DOMAIN, far)
    assert graph_plan_table(inst.graph).length[0] == 12
    assert inst.dynamics.step_limit == 30


OVERLAY = """
[dynamics]
r_max = 12.0
step_limit = 9

[actions.wade.objects.w3]
cost = { dist = "uniform", low = 1.0, high = 7.0 }
"""


def test_an_overlay_gives_r_max_step_limit_and_costs():
    inst = hike(overlay=OVERLAY)
    assert (inst.dynamics.r_max, inst.dynamics.step_limit) == (12.0, 9)
    assert (inst.model.r_max, inst.model.step_limit) == (12.0, 9)
    costs = expected_costs(inst.model)
    assert costs[action(inst, "(wade w3 e3 e4)")] == 4.0  # the overlay's, replacing 2
    assert costs[action(inst, "(wade w2 e2 e3)")] == 2.0  # the domain's


@pytest.mark.parametrize(("old", "new", "key"), [
    ("[actions.wade.objects.w3]", "[actions.wade]\nsuccess = 0.9", "actions.wade.success"),
    ("[actions.wade.objects.w3]", "[actions.wade.objects.w3]\nstuck = 0.1",
     "actions.wade.objects.w3.stuck"),
    ("[actions.wade.objects.w3]", "[actions.wade]\nfailure = [\"walk\"]",
     "actions.wade.failure"),
    ("[actions.wade.objects.w3]", "[actions.swim]", "actions.swim"),
    ("step_limit = 9", "step_limit = 0", "dynamics.step_limit"),
])
def test_overlay_errors_name_the_file_and_key(old, new, key):
    text = OVERLAY.replace(old, new)
    assert text != OVERLAY
    planning = PlanningProblem.from_texts(HIKE_DOMAIN, HIKE_PROBLEM, "hike.pddl")
    from gdq_pddl.dynamics import parse_dynamics

    with pytest.raises(WorldError) as err:
        parse_dynamics(text, planning.source_domain, planning.problem, "o.toml", overlay=True)
    assert str(err.value).startswith(f"o.toml: {key}: "), str(err.value)


def test_a_pddlgym_style_domain_runs():
    """pddlgym's PPDDL files name the action in a precondition atom the problem lists, and
    use negative preconditions without declaring them."""
    domain = """(define (domain tyres)
      (:requirements :typing :strips :probabilistic-effects)
      (:types loc)
      (:predicates (car-at ?l - loc) (road ?a ?b - loc) (spare ?l - loc) (flat)
                   (drive ?to - loc) (change ?l - loc))
      (:action drive-to :parameters (?from ?to - loc)
        :precondition (and (car-at ?from) (road ?from ?to) (not (flat)) (drive ?to))
        :effect (and (car-at ?to) (not (car-at ?from)) (probabilistic 0.4 (flat))))
      (:action change-tyre :parameters (?l - loc)
        :precondition (and (spare ?l) (car-at ?l) (change ?l) (flat))
        :effect (and (not (spare ?l)) (not (flat)))))"""
    problem = """(define (problem tyres-1) (:domain tyres)
      (:objects a b c - loc)
      (:init (car-at a) (road a b) (road b c) (spare b) (drive a) (drive b) (drive c)
             (change a) (change b) (change c))
      (:goal (and (car-at c))))"""
    inst = PDDLInstance.from_texts(domain, problem)
    assert graph_plan_table(inst.graph).length[0] == 2
    assert solve(inst.model, GOAL_POS).V[0, 0] > 0


# --- the shipped keys domain, in PPDDL ----------------------------------------------

@pytest.mark.parametrize("n", ["1", "2"])
def test_keys_in_ppddl_is_the_same_true_model_as_keys_with_its_dynamics(n):
    toml = PDDLInstance.from_files(ROOT / "domains" / "keys.pddl",
                                   ROOT / "problems" / f"keys-{n}.pddl", DYN / "keys.toml")
    ppddl = PDDLInstance.from_files(ROOT / "domains" / "keys-ppddl.pddl",
                                    ROOT / "problems" / f"keys-ppddl-{n}.pddl",
                                    DYN / "keys-ppddl.toml")
    a, b = solve(toml.model, GOAL_POS), solve(ppddl.model, GOAL_POS)
    assert b.V[0, 0] == pytest.approx(a.V[0, 0], abs=1e-9)
    # and everywhere: the same states (by their atoms), the same actions (by name; the
    # red lock's unlock is unlock-stiff), the same values at every step
    assert (toml.n_states, toml.n_actions) == (ppddl.n_states, ppddl.n_actions)
    where = {toml.atoms(s): s for s in range(toml.n_states)}
    states = np.array([where[ppddl.atoms(s)] for s in range(ppddl.n_states)])
    names = {toml.action_name(x): x for x in range(toml.n_actions)}
    acts = np.array([names[ppddl.action_name(x).replace("unlock-stiff", "unlock")]
                     for x in range(ppddl.n_actions)])
    np.testing.assert_allclose(b.V, a.V[:, states], atol=1e-9)
    for s in range(ppddl.n_states):  # Q over each state's offered actions, the same ones
        row = ppddl.columns[s][ppddl.columns[s] >= 0]
        there = toml.columns[states[s]]
        assert sorted(acts[row].tolist()) == sorted(there[there >= 0].tolist())
        columns = [int(np.flatnonzero(there == acts[x])[0]) for x in row]
        np.testing.assert_allclose(b.Q[:, s, :len(row)], a.Q[:, states[s]][:, columns],
                                   atol=1e-9)
    np.testing.assert_array_equal(ppddl.model.cost_kind, toml.model.cost_kind[acts])
    np.testing.assert_array_equal(ppddl.model.cost_a, toml.model.cost_a[acts])


def test_keys_in_ppddl_plans_like_keys():
    """Every keys action has one outcome that does something, so both determinisations
    are the STRIPS domain: the same plans from every state."""
    toml = PDDLInstance.from_files(ROOT / "domains" / "keys.pddl",
                                   ROOT / "problems" / "keys-2.pddl", DYN / "keys.toml")
    where = {toml.atoms(s): s for s in range(toml.n_states)}
    for determinisation in ("all-outcomes", "most-likely"):
        ppddl = PDDLInstance.from_files(ROOT / "domains" / "keys-ppddl.pddl",
                                        ROOT / "problems" / "keys-ppddl-2.pddl",
                                        determinisation=determinisation)
        mine, theirs = graph_plan_table(ppddl.graph, 0.3), graph_plan_table(toml.graph, 0.3)
        for s in range(ppddl.n_states):
            named = sorted([(ppddl.action_name(a).replace("-stiff", ""), tuple(ppddl.atoms(x)))
                            for x, a in p] for p in mine.plans_from(s))
            other = sorted([(toml.action_name(a), tuple(toml.atoms(x))) for x, a in p]
                           for p in theirs.plans_from(where[ppddl.atoms(s)]))
            assert named == other
