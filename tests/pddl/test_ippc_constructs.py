"""The IPPC PPDDL language construct by construct (issue 22, item 1): small domains of our
own whose grounded result is derived by hand in the comments (when, probabilistic
inside and around it, forall, exists, or, imply, equality, constants, goals with
alternatives), one run end to end; and random domains drawn from the whole language
against an independent interpreter (tests/pddl/ippc.py)."""

from __future__ import annotations

import numpy as np
import pytest

from gdq_pddl.cli import main
from gdq_pddl.pddl import parse_domain, parse_problem
from tests.pddl.ippc import (
    dist,
    grounded,
    interpreted_model_agrees,
    mask,
    op_named,
    planner_agrees,
    random_domain,
)

# --- constructs, each in a small domain with its grounded result derived by hand ----------

TOGGLE = """(define (domain lamp) (:requirements :strips)
  (:predicates (on))
  (:action toggle :parameters ()
    :effect (and (when (on) (not (on))) (when (not (on)) (on)))))
(define (problem lamp-on) (:domain lamp) (:init) (:goal (on)))
"""


def test_when_decides_in_the_state_the_action_is_taken_in():
    """toggle: from {} to {on}, from {on} to {} (both effects read the old state)."""
    learner, planner = grounded(TOGGLE, TOGGLE)
    toggle = op_named(learner, "(toggle)")
    on = mask(learner, "(on)")
    assert dist(toggle, 0) == {on: 1.0} and dist(toggle, on) == {0: 1.0}
    # the planner's STRIPS view: one op per way the conditions can go
    assert sorted((op.name, op.pre, op.neg, op.add, op.dele) for op in planner.ops) == [
        ("(toggle)", on, 0, 0, on), ("(toggle_v2)", 0, on, on, 0)]
    planner_agrees(learner, planner)


COIN = """(define (domain coin) (:requirements :probabilistic-effects :conditional-effects)
  (:predicates (heads) (armed) (won))
  (:action flip :parameters () :effect (probabilistic 1/2 (heads) 1/2 (not (heads))))
  (:action cash :parameters () :effect (when (heads) (probabilistic 3/4 (won))))
  (:action arm :parameters ()
    :effect (probabilistic 1/3 (when (heads) (armed))
                           1/3 (probabilistic 1/2 (and (armed) (not (heads)))))))
(define (problem coin-1) (:domain coin) (:init) (:goal (and (won) (armed))))
"""


def test_when_and_probabilistic_nest_both_ways():
    """cash (probabilistic inside when): from {heads}, won 3/4; from {}, nothing.
    arm (when inside probabilistic, and nested probabilistic): from {heads}: armed with
    1/3, armed and not heads with 1/3 x 1/2 = 1/6, nothing 1/2; from {}: armed and not
    heads 1/6 (the when does nothing), nothing 5/6."""
    learner, planner = grounded(COIN, COIN)
    h, a, w = (mask(learner, f) for f in ("(heads)", "(armed)", "(won)"))
    cash, arm = op_named(learner, "(cash)"), op_named(learner, "(arm)")
    assert dist(cash, h) == pytest.approx({h | w: 0.75, h: 0.25})
    assert dist(cash, 0) == pytest.approx({0: 1.0})
    assert dist(arm, h) == pytest.approx({h | a: 1 / 3, a: 1 / 6, h: 1 / 2})
    assert dist(arm, 0) == pytest.approx({a: 1 / 6, 0: 5 / 6})
    planner_agrees(learner, planner)


BOXES = """(define (domain boxes) (:requirements :adl)
  (:types box)
  (:predicates (in ?b - box) (out ?b - box) (tipped))
  (:action tip :parameters () :precondition (exists (?b - box) (in ?b))
    :effect (and (tipped) (forall (?b - box) (when (in ?b) (and (out ?b) (not (in ?b))))))))
(define (problem boxes-3) (:domain boxes) (:objects x y z - box)
  (:init (in x) (in z))
  (:goal (forall (?b - box) (not (in ?b)))))
"""


def test_forall_effects_and_an_exists_precondition():
    """tip: applicable when some box is in; every box that is in goes out. From {in x,
    in z}: {out x, out z, tipped}. (in y) and (out y) can never be true: not facts."""
    learner, planner = grounded(BOXES, BOXES)
    assert learner.facts == ("(in x)", "(in z)", "(out x)", "(out z)", "(tipped)")
    tip = op_named(learner, "(tip)")
    assert tip.alternatives == ((mask(learner, "(in x)"), 0), (mask(learner, "(in z)"), 0))
    start = learner.init
    assert start == mask(learner, "(in x)", "(in z)")
    assert dist(tip, start) == {mask(learner, "(out x)", "(out z)", "(tipped)"): 1.0}
    assert dist(tip, mask(learner, "(in z)")) == {mask(learner, "(out z)", "(tipped)"): 1.0}
    assert not learner.applicable(mask(learner, "(tipped)"))
    # the goal's forall over the three boxes: (in y) can never hold, so it drops out
    assert learner.goal_pos == 0 and learner.goal_neg == mask(learner, "(in x)", "(in z)")
    planner_agrees(learner, planner)


GATE = """(define (domain gate) (:requirements :adl)
  (:types key)
  (:constants master - key)
  (:predicates (has ?k - key) (bent ?k - key) (open))
  (:action open-with :parameters (?k - key)
    :precondition (and (has ?k) (or (= ?k master) (not (bent ?k))))
    :effect (open))
  (:action force :parameters ()
    :precondition (imply (exists (?k - key) (has ?k)) (forall (?k - key) (bent ?k)))
    :effect (open))
  (:action drop :parameters (?k - key)
    :precondition (and (has ?k) (not (and (bent ?k) (= ?k master))))
    :effect (not (has ?k))))
(define (problem gate-1) (:domain gate) (:objects k1 k2 - key)
  (:init (has k1) (bent k1) (has master))
  (:goal (and (open) (forall (?k - key) (imply (bent ?k) (not (has ?k)))))))
"""


def test_or_imply_not_forall_exists_equality_and_constants_in_conditions():
    """open-with k1 can never apply (k1 is not master and is bent), nor anything with k2
    (never held); force applies once no key is held (not every key is bent); drop master
    applies (master is not bent). The goal: open, and k1 (the only bent key) not held."""
    learner, planner = grounded(GATE, GATE)
    assert [op.name for op in learner.ops] == ["(open-with master)", "(force)", "(drop k1)",
                                               "(drop master)"]
    k1, m, o = (mask(learner, f) for f in ("(has k1)", "(has master)", "(open)"))
    assert (learner.goal_pos, learner.goal_neg) == (o, k1)
    force = op_named(learner, "(force)")
    assert not force.holds(k1) and not force.holds(m) and force.holds(0)
    from gdq_pddl.pddl.reachable import reachable_graph

    graph = reachable_graph(learner)
    # from {k1, master}: open-with master gives {k1, master, open}, not a goal state (k1
    # is held), where dropping master gives {k1, open}: all 8 subsets are reached
    assert sorted(graph.states) == sorted([k1 | m, k1 | m | o, m, k1, m | o, 0, o, k1 | o])
    assert sorted(s for s, g in zip(graph.states, graph.is_goal, strict=True) if g) == \
        sorted([m | o, o])
    planner_agrees(learner, planner)


def test_a_goal_with_real_alternatives_is_read_as_them():
    text = GATE.replace("(:goal (and (open) (forall (?k - key) (imply (bent ?k) (not "
                        "(has ?k))))))", "(:goal (or (open) (not (has k1))))")
    problem = parse_problem(text, parse_domain(text), "p.pddl")
    assert problem.goal == () and [[(lit.positive, str(lit.atom)) for lit in alt]
                                   for alt in problem.goal_alternatives] == \
        [[(True, "(open)")], [(False, "(has k1)")]]


BULB = """; one file: a lamp to switch on and boxes to tip out (1/2: the tipping jams)
(define (domain bulb) (:requirements :adl :probabilistic-effects)
  (:types box)
  (:predicates (on) (in ?b - box) (out ?b - box))
  (:action toggle :parameters ()
    :effect (and (when (on) (not (on))) (when (not (on)) (on))))
  (:action dump :parameters () :precondition (exists (?b - box) (in ?b))
    :effect (probabilistic 1/2 (forall (?b - box) (when (in ?b) (and (out ?b)
                                                                     (not (in ?b))))))))
(define (problem bulb-2) (:domain bulb) (:objects x y - box) (:init (in x) (in y))
  (:goal (and (on) (forall (?b - box) (out ?b)))))
"""


def test_the_new_constructs_run_end_to_end_with_the_hand_derived_value(capsys, tmp_path):
    """V* = 18: toggle once (-1), dump until it works (it fails once on average: -1), and
    +20 (r_max) on reaching the goal; the step limit of 20 cuts a 2^-19 tail."""
    from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLInstance
    from gdq_pddl.envs.solve import solve

    path = tmp_path / "bulb.pddl"
    path.write_text(BULB, encoding="utf-8")
    instance = PDDLInstance.from_files(path, path)
    assert instance.n_states == 4 and instance.n_actions == 2
    value = solve(instance.model, GOAL_POS).V[0, 0]
    assert value == pytest.approx(18.0, abs=1e-3)
    code = main(["run", "--domain", str(path), "--problem", str(path), "--episodes", "20",
                 "--runs", "1", "--jobs", "1", "--no-report", "--out", str(tmp_path / "o")])
    out = capsys.readouterr()
    assert code == 0, out.out + out.err
    assert (tmp_path / "o" / "episodes.csv").read_text().count("\n") == 1 + 5 * 20


# --- property: the grounded model against an independent interpreter ----------------------

@pytest.mark.parametrize("seed", range(40))
def test_the_grounded_model_agrees_with_an_independent_interpreter(seed):
    interpreted_model_agrees(*random_domain(np.random.default_rng(seed)))
