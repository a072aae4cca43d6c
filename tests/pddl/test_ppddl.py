"""PPDDL input: the reader's probabilistic effects and costs, its file:line errors, the
determinisations and O, the true model, the shipped keys domain in PPDDL (the same true
model as keys.pddl with keys.toml), the overlay, and the command line end to end on a
PPDDL domain written here."""

from __future__ import annotations

import json
import os
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st

from gdq_pddl.abstraction.pddl import PDDLAbstraction, graph_plan_table
from gdq_pddl.abstraction.table import build_plan_table
from gdq_pddl.cli import main
from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLEnv, PDDLInstance
from gdq_pddl.envs.solve import expected_costs, solve
from gdq_pddl.envs.step import pair_of
from gdq_pddl.errors import PDDLError, PlanningError, WorldError
from gdq_pddl.learners import make_learner, pddl_task_context, run_episodes
from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.planning import PlanningProblem, get_planner
from gdq_pddl.planning.validate import validate_plan
from tests.helpers import BACKGROUND
from tests.helpers import DYNAMICS as DYN
from tests.helpers import REPO_ROOT as ROOT

# A domain no shipped file knows: a hiker on two banks of a river. Fording is quick,
# but the current may carry the hiker downstream, or away (a failed trial); the bridge
# is at the far end of the trail.
HIKE_DOMAIN = """; the hike domain
(define (domain hike)
  (:requirements :strips :typing :probabilistic-effects :rewards)
  (:types camp)
  (:predicates (at ?c - camp) (trail ?a ?b - camp) (ford ?a ?b ?down - camp) (stuck))
  (:action walk
    :parameters (?a ?b - camp)
    :precondition (and (at ?a) (trail ?a ?b))
    :effect (and (decrease (reward) 1)
                 (probabilistic 0.9 (and (at ?b) (not (at ?a))))))
  (:action wade
    :parameters (?a ?b ?down - camp)
    :precondition (and (at ?a) (ford ?a ?b ?down))
    :effect (and (decrease (reward) 2)
                 (probabilistic 0.5 (and (at ?b) (not (at ?a)))
                                0.3 (and (at ?down) (not (at ?a)))
                                0.1 (stuck)))))
"""
HIKE_PROBLEM = """(define (problem hike-4) (:domain hike)
  (:objects w1 w2 w3 w4 e1 e2 e3 e4 - camp)
  (:init (at w1)
    (trail w1 w2) (trail w2 w1) (trail w2 w3) (trail w3 w2) (trail w3 w4) (trail w4 w3)
    (trail e1 e2) (trail e2 e1) (trail e2 e3) (trail e3 e2) (trail e3 e4) (trail e4 e3)
    (trail w4 e4) (trail e4 w4)
    (ford w2 e2 e3) (ford w3 e3 e4))
  (:goal (at e1))
  (:goal-reward 30)
  (:metric maximize (reward)))
"""


def hike(determinisation: str = "all-outcomes", overlay: str | None = None) -> PDDLInstance:
    return PDDLInstance.from_texts(HIKE_DOMAIN, HIKE_PROBLEM, overlay,
                                   determinisation=determinisation)


def atoms_of(inst: PDDLInstance, s: int) -> set[str]:
    return set(inst.atoms(s))


def state_with(inst: PDDLInstance, atom: str) -> int:
    return next(s for s in range(inst.n_states) if atom in inst.atoms(s))


def action(inst: PDDLInstance, name: str) -> int:
    return next(a for a in range(inst.n_actions) if inst.action_name(a) == name)


def outcomes(inst: PDDLInstance, s: int, a: int) -> dict[tuple[str, bool], float]:
    """``{(where the hiker is, stuck): probability}`` of action ``a`` in state ``s``."""
    m = inst.model
    i = pair_of(m, s, a)
    if i is None:  # not offered in s: stepping it changes nothing
        return {(next(x for x in inst.atoms(s) if x.startswith("(at")), False): 1.0}
    k = slice(m.ptr[i], m.ptr[i + 1])
    out: dict[tuple[str, bool], float] = {}
    for t, stuck, p in zip(m.next[k], m.stuck[k], m.prob[k], strict=True):
        key = (next(x for x in inst.atoms(int(t)) if x.startswith("(at")), bool(stuck))
        out[key] = out.get(key, 0.0) + float(p)
    return out


# --- the reader ----------------------------------------------------------------------

def test_effects_flatten_into_outcomes_that_sum_to_one():
    domain = parse_domain(HIKE_DOMAIN)
    walk, wade = domain.actions
    assert [o.probability for o in walk.outcomes] == pytest.approx([0.9, 0.1])
    assert walk.outcomes[1].effect == ()  # the leftover: nothing happens
    assert [o.probability for o in wade.outcomes] == pytest.approx([0.5, 0.3, 0.1, 0.1])
    assert [o.stuck for o in wade.outcomes] == [False, False, True, False]
    assert walk.cost == (1.0,) and wade.cost == (2.0,)
    assert domain.probabilistic and walk.effect == ()


def test_nested_and_independent_effects_multiply_out():
    text = HIKE_DOMAIN.replace(
        "(probabilistic 0.9 (and (at ?b) (not (at ?a))))",
        "(probabilistic 1/2 (and (at ?b) (not (at ?a)) (probabilistic 0.5 (stuck)))) "
        "(probabilistic 0.25 (not (trail ?a ?b)))")
    walk = parse_domain(text).actions[0]
    got = {(frozenset(str(lit.atom) + str(lit.positive) for lit in o.effect), o.stuck):
           o.probability for o in walk.outcomes}
    moved = frozenset({"(at ?b)True", "(at ?a)False"})
    cut = frozenset({"(trail ?a ?b)False"})
    assert got == pytest.approx({(frozenset(), True): 0.25,  # both stuck outcomes merged
                                 (moved, False): 0.25 * 0.75,
                                 (moved | cut, False): 0.25 * 0.25,
                                 (cut, False): 0.5 * 0.25,
                                 (frozenset(), False): 0.5 * 0.75})


@st.composite
def effects(draw, depth: int = 0):
    """A random effect text of ?a/?b atoms, with its probability of making (at ?b) true."""
    kind = draw(st.sampled_from(("atom", "and", "prob") if depth < 3 else ("atom",)))
    if kind == "atom":
        return "(at ?b)", Fraction(1)
    if kind == "and":
        parts = draw(st.lists(effects(depth + 1), min_size=1, max_size=3))
        miss = Fraction(1)
        for _, p in parts:
            miss *= 1 - p
        return "(and " + " ".join(t for t, _ in parts) + ")", 1 - miss
    n = draw(st.integers(1, 3))
    weights = draw(st.lists(st.integers(0, 4), min_size=n + 1, max_size=n + 1))
    probs = [Fraction(w, sum(weights) or 1) for w in weights[:n]]
    subs = [draw(effects(depth + 1)) for _ in range(n)]
    text = " ".join(f"{p.numerator}/{p.denominator} {t}" for p, (t, _) in
                    zip(probs, subs, strict=True))
    return f"(probabilistic {text})", sum((p * q for p, (_, q) in zip(probs, subs,
                                                                       strict=True)), Fraction(0))


@settings(max_examples=60, deadline=None)
@given(effects())
def test_any_probabilistic_effect_is_a_distribution(effect):
    text, p_at = effect
    domain = parse_domain(HIKE_DOMAIN.replace("(probabilistic 0.9 (and (at ?b) (not (at ?a))))",
                                              text))
    walk = domain.actions[0]
    dist = walk.outcomes or ()
    total = sum(o.probability for o in dist) if dist else 1.0
    assert total == pytest.approx(1.0)
    made = sum(o.probability for o in dist if any(str(lit.atom) == "(at ?b)" for lit in
                                                  o.effect)) if dist else 1.0
    assert made == pytest.approx(float(p_at))


WALK_EFFECT = "(probabilistic 0.9 (and (at ?b) (not (at ?a))))"


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(1, 10**6), min_size=1, max_size=3), st.integers(7, 30),
       st.booleans())
def test_decimal_probabilities_sum_exactly_in_either_notation(weights, digits, scientific):
    """Property: probabilities written as decimals (``0.0000125``) or in scientific
    notation (``125e-7``) that sum to 1 leave no "no effect" outcome, and one more of
    10**-MAX_EXPONENT, the smallest a number may be written, makes the sum too large."""
    from gdq_pddl.pddl.formulas import MAX_EXPONENT

    ks = [*weights, 10**digits - sum(weights)]
    probs = [f"{k}e-{digits}" if scientific else f"0.{k:0{digits}d}" for k in ks]
    effects = ["(at ?b)", "(not (at ?a))", "(trail ?b ?a)", "(not (trail ?a ?b))"]
    pairs = " ".join(f"{p} {e}" for p, e in zip(probs, effects, strict=False))
    walk = parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, f"(probabilistic {pairs})")).actions[0]
    assert all(o.effect for o in walk.outcomes)
    assert sum(o.probability for o in walk.outcomes) == pytest.approx(1.0)
    tiny = f"(probabilistic {pairs} 1e-{MAX_EXPONENT} (at ?a))"
    with pytest.raises(PDDLError, match="they must sum to at most 1"):
        parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, tiny))
    with pytest.raises(PDDLError, match=f"1e-{MAX_EXPONENT + 1}: an exponent past"):
        parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, tiny.replace(f"e-{MAX_EXPONENT}",
                                                                   f"e-{MAX_EXPONENT + 1}")))




@pytest.mark.parametrize(("old", "new", "line", "expected"), [
    ("0.5 (and (at ?b)", "0.7 (and (at ?b)", 15, "sum to 1.1; they must sum to at most 1"),
    ("0.3 (and (at ?down)", "-0.3 (and (at ?down)", 16, "a probability must be in [0, 1]"),
    ("0.9 (and", "1.5 (and", 10, "a probability must be in [0, 1], got 1.5"),
    ("0.9 (and", "most (and", 10, "expected a probability"),
    (WALK_EFFECT, "(probabilistic 0.9)", 10, "pairs of a probability and an effect"),
    ("(at ?a) (trail ?a ?b))", "(at ?a) (probabilistic 0.5 (trail ?a ?b)))", 8,
     "(probabilistic ...) can only be an effect, not a precondition"),
    (WALK_EFFECT, "(when (at ?a) (stuck))", 10, "(stuck) inside (when ...)"),
    (WALK_EFFECT, "(oneof (at ?b) (at ?a))", 10, "(oneof ...) (FOND"),
    (WALK_EFFECT, "(not (stuck))", 10, "(not (stuck)) is not an effect"),
    ("(at ?a) (trail ?a ?b))", "(at ?a) (trail ?a ?b) (stuck))", 8,
     "(stuck) marks a failed trial"),
    ("(decrease (reward) 1)", "(increase (fuel) 1)", 9, "other numeric fluents"),
    ("(decrease (reward) 1)", "(increase (total-cost) (len ?a ?b))", 9,
     "a function declared in :functions"),
    ("(decrease (reward) 1)", "(increase (total-cost) -1)", 9, "expected an amount >= 0"),
])
def test_bad_ppddl_gets_file_line_errors(old, new, line, expected):
    text = HIKE_DOMAIN.replace(old, new)
    assert text != HIKE_DOMAIN
    with pytest.raises(PDDLError) as err:
        parse_domain(text, "hike.pddl")
    assert str(err.value).startswith(f"hike.pddl:{line}: "), str(err.value)
    assert expected in str(err.value)


@pytest.mark.parametrize(("old", "new", "line", "expected"), [
    ("(:goal (at e1))", "(:goal (and (at e1) (stuck)))", 8, "(stuck) marks a failed trial"),
    ("(:goal (at e1))", "(:goal (probabilistic 0.5 (at e1)))", 8, "can only be an effect"),
    ("(at w1)\n", "(at w1) (probabilistic 0.5 (at w2))\n", 3, "probabilistic initial state"),
    ("(:goal-reward 30)", "(:goal-reward -3)", 9, "N > 0"),
    ("(:metric maximize (reward))", "(:metric minimize (steps))", 10, "is not supported"),
    ("(at w1)\n", "(at w1) (= (len w1 w2) 3)\n", 3, "unknown function 'len'"),
])
def test_bad_ppddl_problems_get_file_line_errors(old, new, line, expected):
    text = HIKE_PROBLEM.replace(old, new)
    assert text != HIKE_PROBLEM
    with pytest.raises(PDDLError) as err:
        parse_problem(text, parse_domain(HIKE_DOMAIN), "hike-4.pddl")
    assert str(err.value).startswith(f"hike-4.pddl:{line}: "), str(err.value)
    assert expected in str(err.value)


def test_costs_from_functions_valued_in_the_problem():
    domain = HIKE_DOMAIN.replace("(stuck))\n", "(stuck))\n  (:functions (len ?a ?b - camp))\n") \
        .replace("(decrease (reward) 1)", "(increase (total-cost) (len ?a ?b))")
    problem = HIKE_PROBLEM.replace("(ford w2 e2 e3)", "(ford w2 e2 e3) (= (len w1 w2) 4) "
                                   "(= (total-cost) 0)")
    with pytest.raises(PDDLError, match=r"no value for \(len w2 w1\) in :init"):
        PDDLInstance.from_texts(domain, problem).costs  # noqa: B018
    values = " ".join(f"(= (len {a} {b}) {4 if (a, b) == ('w1', 'w2') else 1})"
                      for a, b in [("w1", "w2"), ("w2", "w1"), ("w2", "w3"), ("w3", "w2"),
                                   ("w3", "w4"), ("w4", "w3"), ("e1", "e2"), ("e2", "e1"),
                                   ("e2", "e3"), ("e3", "e2"), ("e3", "e4"), ("e4", "e3"),
                                   ("w4", "e4"), ("e4", "w4")])
    inst = PDDLInstance.from_texts(domain, HIKE_PROBLEM.replace("(ford w2 e2 e3)",
                                                                f"(ford w2 e2 e3) {values}"))
    costs = expected_costs(inst.model)
    assert costs[action(inst, "(walk w1 w2)")] == 4.0
    assert costs[action(inst, "(walk w2 w1)")] == 1.0
    assert costs[action(inst, "(wade w2 e2 e3)")] == 2.0


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


# --- the env, the learners, the command line ----------------------------------------

def test_the_env_passes_the_checker_and_learners_run_on_it():
    inst = hike()
    env = PDDLEnv(instance=inst)
    check_env(env, skip_render_check=True)
    ctx = pddl_task_context(inst)
    assert ctx.plans.length[0] == 3
    out = []
    for fast in (True, False):
        env.reset(seed=1)
        learner = make_learner("gdq", ctx, variant="code")
        out.append(run_episodes(learner, env, 30, np.random.default_rng(2), fast=fast))
    np.testing.assert_array_equal(out[0].returns, out[1].returns)


def test_the_env_takes_a_ppddl_domain_file_alone():
    env = PDDLEnv(ROOT / "domains" / "keys-ppddl.pddl", ROOT / "problems" / "keys-ppddl-2.pddl")
    check_env(env, skip_render_check=True)
    assert env.instance.dynamics.step_limit == 20  # no overlay: max(20, ceil(2.5 x 7))


def hike_files(tmp_path: Path, domain: str = HIKE_DOMAIN,
               problem: str = HIKE_PROBLEM) -> tuple[Path, Path]:
    files = (tmp_path / "hike.pddl", tmp_path / "hike-4.pddl")
    for path, text in zip(files, (domain, problem), strict=True):
        path.write_text(text, encoding="utf-8")
    return files


@pytest.mark.parametrize("determinisation", ["all-outcomes", "most-likely"])
def test_gymnasium_make_takes_the_determinisation(tmp_path, determinisation):
    import gymnasium

    d, p = hike_files(tmp_path)
    env = gymnasium.make("gdq_pddl/PDDL-v0", domain=str(d), problem=str(p),
                         determinisation=determinisation).unwrapped
    check_env(env, skip_render_check=True)
    assert env.instance.determinisation == determinisation
    want = hike(determinisation).graph  # the planner's knowledge: the graph's edges
    np.testing.assert_array_equal(env.instance.graph.edge_next, want.edge_next)
    assert gymnasium.make("gdq_pddl/PDDL-v0", domain=str(d),
                          problem=str(p)).unwrapped.instance.determinisation == "all-outcomes"
    with pytest.raises(PlanningError, match="unknown determinisation 'best'"):
        gymnasium.make("gdq_pddl/PDDL-v0", domain=str(d), problem=str(p),
                       determinisation="best")


def test_a_step_limit_below_the_way_reality_reaches_the_goal_is_refused(tmp_path):
    """Most-likely knows no way to e1 (wading mostly does nothing), so no plan is longer
    than the step limit; reality's fewest actions (walk, wade, walk) are."""
    domain = HIKE_DOMAIN.replace("0.5 (and (at ?b)", "0.2 (and (at ?b)")
    problem = HIKE_PROBLEM.replace("(trail w4 e4) (trail e4 w4)", "")
    short = PDDLInstance.from_texts(domain, problem, "[dynamics]\nstep_limit = 2\n",
                                    determinisation="most-likely")
    with pytest.raises(WorldError, match=r"<string>: dynamics.step_limit: 2 is less than the "
                       r"fewest actions .* in reality \(3 actions; the knowledge has no plan"):
        short.model  # noqa: B018
    assert PDDLInstance.from_texts(domain, problem, "[dynamics]\nstep_limit = 3\n",
                                   determinisation="most-likely").model.step_limit == 3


@pytest.mark.parametrize(("which", "old", "new", "names"), [
    (0, "(probabilistic 0.9 (and", "(probabilistic 0 (and", [
        "hike.pddl", "(at e1) can never hold (no outcome of positive probability of"]),
    (1, "(:goal (at e1))", "(:goal (and (at e1) (not (at e1))))", [
        "hike-4.pddl", "(at e1) and (not (at e1)), which can never both hold"]),
])
def test_a_ppddl_goal_that_can_never_hold_says_why(tmp_path, capsys, which, old, new, names):
    texts = [HIKE_DOMAIN, HIKE_PROBLEM]
    assert old in texts[which]
    texts[which] = texts[which].replace(old, new)
    if which == 0:  # nor may the wader reach e1
        texts[0] = texts[0].replace("0.5 (and (at ?b)", "0 (and (at ?b)")
    d, p = hike_files(tmp_path, *texts)
    assert main(["run", "--domain", str(d), "--problem", str(p), "--episodes", "2", "--runs",
                 "1", "--jobs", "1", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"gdq-pddl: error: {p}: no plan: the goal cannot be reached"), err
    assert all(n in err for n in names), err


def test_cli_runs_a_ppddl_domain_nobody_has_seen_without_a_dynamics_file(tmp_path):
    (tmp_path / "d.pddl").write_text(HIKE_DOMAIN)
    (tmp_path / "p.pddl").write_text(HIKE_PROBLEM)
    out = tmp_path / "out"
    code = main(["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--episodes", "20", "--runs", "1",
                 "--jobs", "1", "--out", str(out)])
    assert code == 0
    report = (out / "REPORT.md").read_text()
    for method in ("GDQ", "GDQ-code", "DARLING", "Dyna-Q", "Q-learning"):  # the defaults
        assert f"| {method} |" in report or f"| **{method}** |" in report, method
    assert "hike-4" in report and "all-outcomes determinisation" in report
    assert "shortest plan: 3 actions" in report
    optimal = json.loads((out / "optimal.json").read_text())
    entry = next(iter(optimal.values()))
    assert entry["determinisation"] == "all-outcomes" and entry["r_max"] == 30.0
    assert entry["v_star"] == pytest.approx(solve(hike().model, GOAL_POS).V[0, 0])


def test_cli_most_likely_and_plan(tmp_path, capsys):
    (tmp_path / "d.pddl").write_text(HIKE_DOMAIN)
    (tmp_path / "p.pddl").write_text(HIKE_PROBLEM)
    assert main(["plan", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl")]) == 0
    assert "(wade_o1 w2 e2 e3)" in capsys.readouterr().out
    assert main(["plan", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--determinisation", "most-likely"]) == 0
    assert "(wade w2 e2 e3)" in capsys.readouterr().out
    out = tmp_path / "out"
    assert main(["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--determinisation", "most-likely",
                 "--method", "GDQ-code", "--episodes", "5", "--runs", "1", "--jobs", "1",
                 "--out", str(out)]) == 0
    assert "most-likely determinisation" in (out / "REPORT.md").read_text()
    (tmp_path / "o.toml").write_text("[actions.wade]\nsuccess = 0.5\n")
    assert main(["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--dynamics", str(tmp_path / "o.toml")]) == 2
    assert "o.toml: actions.wade.success: " in capsys.readouterr().err


def test_a_strips_domain_s_stated_cost_is_the_default_of_its_dynamics_file():
    domain = """(define (domain line) (:requirements :strips :action-costs)
      (:predicates (at1) (at2) (at3))
      (:functions (total-cost))
      (:action a :parameters () :precondition (at1)
        :effect (and (at2) (not (at1)) (increase (total-cost) 3)))
      (:action b :parameters () :precondition (at2)
        :effect (and (at3) (not (at2)) (increase (total-cost) 3))))"""
    problem = "(define (problem l) (:domain line) (:init (at1)) (:goal (at3)))"
    dynamics = "[actions.a]\nsuccess = 0.5\n[actions.b]\ncost = 0.5\n"
    inst = PDDLInstance.from_texts(domain, problem, dynamics)
    assert not inst.ppddl and inst.dynamics.outcomes("a", ()).success == 0.5
    assert expected_costs(inst.model).tolist() == [3.0, 0.5]


PPDDL_HASH_SEED_SCRIPT = """
import shutil, sys, tempfile
from pathlib import Path
import numpy as np
from gdq_pddl.envs.pddl_env import PDDLEnv
from gdq_pddl.learners import make_learner, pddl_task_context, run_episodes
folder = Path(tempfile.mkdtemp(prefix="gdq-hike-"))
(folder / "d.pddl").write_text(sys.argv[1])
(folder / "p.pddl").write_text(sys.argv[2])
env = PDDLEnv(str(folder / "d.pddl"), str(folder / "p.pddl"))
shutil.rmtree(folder)
inst = env.instance
print([op.name for op in inst.problem.task.ops], inst.model.prob.tolist())
env.reset(seed=0)
learner = make_learner("gdq", pddl_task_context(inst), variant="code")
print(run_episodes(learner, env, 20, np.random.default_rng(0)).returns.tolist())
"""


def start_ppddl_hash_seeds(item=None) -> list:
    """The hike run under two hash seeds, queued when collection ends to run beside the
    other tests (``tests.helpers.Background``)."""
    return [BACKGROUND.run(f"ppddl hash seed {seed}", [sys.executable, "-c",
                                                       PPDDL_HASH_SEED_SCRIPT, HIKE_DOMAIN,
                                                       HIKE_PROBLEM],
                           env=dict(os.environ, PYTHONHASHSEED=seed), timeout=300)
            for seed in ("1", "2")]


@pytest.mark.background.with_args(start_ppddl_hash_seeds)
def test_ppddl_runs_do_not_depend_on_the_hash_seed():
    """Ground actions, planner actions and outcomes come out in one order in every process."""
    outs = [future.result() for future in start_ppddl_hash_seeds()]
    for out in outs:
        assert out.returncode == 0, out.stderr[-2000:]
    assert outs[0].stdout == outs[1].stdout
