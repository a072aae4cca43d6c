"""``probabilistic`` inside ``forall`` effects (issue 22, item 1), read as PPDDL planners
and MDPSim read it: once grounded, one independent draw per binding of the forall's
variables, as if the bindings' probabilistic effects stood side by side. Small domains of
our own, their grounded distributions and V* derived by hand in the comments."""

from __future__ import annotations

from fractions import Fraction
from itertools import product

import numpy as np
import pytest

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.pddl.grounding import GroundOutcome
from gdq_pddl.pddl.parser import MAX_OUTCOMES
from gdq_pddl.pddl.ppddl import ground_ppddl
from tests.pddl.ippc import (
    dist,
    grounded,
    interpreted_model_agrees,
    mask,
    op_named,
    planner_agrees,
    random_domain,
)

# shake: every coin comes up with 1/4, each on its own. touch: every coin is touched, and
# comes up with 1/2 if it is ready (a when inside the forall, an and around the draw).
COINS = """(define (domain coins) (:requirements :adl :probabilistic-effects)
  (:types coin)
  (:predicates (up ?c - coin) (ready ?c - coin) (touched ?c - coin) (shaken))
  (:action shake :parameters ()
    :effect (and (shaken) (forall (?c - coin) (probabilistic 1/4 (up ?c)))))
  (:action touch :parameters ()
    :effect (forall (?c - coin) (and (touched ?c)
                                     (when (ready ?c) (probabilistic 1/2 (up ?c)))))))
(define (problem coins-3) (:domain coins) (:objects c1 c2 c3 - coin)
  (:init (ready c1) (ready c3))
  (:goal (and (up c1) (up c2) (up c3))))
"""


def test_a_forall_of_a_probabilistic_effect_is_the_product_of_its_draws():
    """shake from {}: each subset S of the three coins comes up with (1/4)^|S| (3/4)^(3-|S|),
    8 outcomes (all dyadic: the floats are exact), and (shaken) in every one."""
    learner, planner = grounded(COINS, COINS)
    shake = op_named(learner, "(shake)")
    coins = ("c1", "c2", "c3")
    s = mask(learner, "(shaken)")
    want: dict[int, float] = {}
    for ups in product((False, True), repeat=3):
        p = Fraction(1)
        for up in ups:
            p *= Fraction(1, 4) if up else Fraction(3, 4)
        t = s | mask(learner, *(f"(up {c})" for c, up in zip(coins, ups, strict=True) if up))
        want[t] = float(p)
    assert len(shake.outcomes) == 8
    assert dist(shake, 0) == want  # exactly
    assert sum(o.probability for o in shake.outcomes) == 1.0
    # a coin already up stays up whatever its draw
    c2 = mask(learner, "(up c2)")
    assert dist(shake, c2) == {s | c2: 9 / 16, s | c2 | mask(learner, "(up c1)"): 3 / 16,
                               s | c2 | mask(learner, "(up c3)"): 3 / 16,
                               s | c2 | mask(learner, "(up c1)", "(up c3)"): 1 / 16}
    planner_agrees(learner, planner)


def test_when_and_and_inside_the_forall_draw_per_object():
    """touch from {}: all three touched; c1 and c3 (ready) come up with 1/2 each, c2
    never (its when is false: no draw matters), so 4 outcomes of 1/4."""
    learner, planner = grounded(COINS, COINS)
    touch = op_named(learner, "(touch)")
    t = mask(learner, "(touched c1)", "(touched c2)", "(touched c3)")
    c1, c3 = mask(learner, "(up c1)"), mask(learner, "(up c3)")
    assert dist(touch, 0) == {t: 0.25, t | c1: 0.25, t | c3: 0.25, t | c1 | c3: 0.25}
    # (ready c2) is static and false: its draw merged away when grounded
    assert len(touch.outcomes) == 4
    planner_agrees(learner, planner)


def test_the_planner_keeps_each_outcome_or_the_most_likely():
    learner, planner = grounded(COINS, COINS)
    shake = op_named(learner, "(shake)")
    names = sorted(op.name for op in planner.ops if planner_origin(learner, op) == "(shake)")
    assert names == [f"(shake_c{j})" for j in range(1, 9)]  # every draw does something
    domain = parse_domain(COINS, "d.pddl")
    likely, planner2 = ground_ppddl(domain, parse_problem(COINS, domain, "p.pddl"),
                                    "most-likely")
    shake2 = op_named(likely, "(shake)")
    best = max(shake2.outcomes, key=lambda o: o.probability)
    assert best.probability == 27 / 64 and len(shake2.known) == 1
    assert shake2.outcomes[shake2.known[0]] == best
    assert [op.name for op in planner2.ops if likely.origin[op.name] == "(shake)"] == \
        ["(shake)"]
    assert len(shake.outcomes) == len(shake2.outcomes)
    planner_agrees(likely, planner2)


def planner_origin(learner, op) -> str:
    return learner.origin.get(op.name, op.name)


# The IPPC-2008 idiom of a wrong turn: the forall's when picks the one detour city (a
# static fact), and the draw inside it is one of two; the rest of the bindings do nothing.
LANE = """(define (domain lane) (:requirements :adl :probabilistic-effects)
  (:types city)
  (:predicates (at ?c - city) (road ?a ?b - city) (detour ?a ?b - city))
  (:action drive :parameters (?a ?b - city)
    :precondition (and (at ?a) (road ?a ?b))
    :effect (and (not (at ?a))
                 (probabilistic 1/4 (forall (?w - city)
                                      (when (detour ?a ?w)
                                        (probabilistic 1/2 (at ?w) 1/2 (at ?a))))
                                3/4 (at ?b)))))
(define (problem lane-1) (:domain lane) (:objects x y z - city)
  (:init (at x) (road x y) (road y x) (detour x z))
  (:goal (at y)))
"""


def test_a_forall_inside_a_probabilistic_branch_under_a_static_when():
    """drive x y: 3/4 to y; 1/4 x 1/2 to z (the detour); 1/4 x 1/2 back to x (the add
    wins over the delete). drive y x: 3/4 to x, 1/4 nowhere (y has no detour)."""
    learner, planner = grounded(LANE, LANE)
    x, y, z = (mask(learner, f"(at {c})") for c in "xyz")
    xy, yx = op_named(learner, "(drive x y)"), op_named(learner, "(drive y x)")
    assert dist(xy, x) == {y: 0.75, z: 0.125, x: 0.125}
    assert len(xy.outcomes) == 3  # the two bindings without a detour merged away
    assert dist(yx, y) == {x: 0.75, 0: 0.25}
    planner_agrees(learner, planner)


# Two coins; flip throws both, each up with 1/2 on its own. The goal: both up.
TWO = """(define (domain two) (:requirements :adl :probabilistic-effects)
  (:types coin)
  (:predicates (up ?c - coin))
  (:action flip :parameters () :effect (forall (?c - coin) (probabilistic 1/2 (up ?c)))))
(define (problem two-1) (:domain two) (:objects a b - coin) (:init)
  (:goal (and (up a) (up b))))
"""


def test_the_value_of_independent_draws_derived_by_hand():
    """Expected flips to reach both up, E_k with k coins up (an up coin stays up):
    E_1 = 1 + E_1 / 2, so E_1 = 2; E_0 = 1 + E_0 / 4 + E_1 / 2, so E_0 = 8 / 3.
    Every flip costs 1 but the last, which earns r_max = 20: V* = 20 - (8/3 - 1) = 55/3
    (the step limit of 20 cuts a tail of about 2^-19). Read as one draw for both coins
    (both up with 1/2), V* would be 20 - 1 = 19."""
    from gdq_pddl.envs.pddl_env import PDDLInstance

    instance = PDDLInstance.from_texts(TWO, TWO)
    assert instance.n_states == 4 and instance.n_actions == 1
    assert instance.optimal()["v_star"] == pytest.approx(55 / 3, abs=1e-3)


def test_past_the_limit_independent_draws_stay_factored():
    """13 coins: 2^13 = 8192 outcomes, past FACTORED_ABOVE: flip is kept as its own
    outcome (nothing) and 13 parts of 2 outcomes (never listed); its determinisation one
    coin at a time: every coin at its most likely draw (a tie: the first written, up),
    then each coin alone down (1 + 13 outcomes). 12 coins (4096 outcomes) are listed as
    before."""
    objects = " ".join(f"k{i}" for i in range(13))
    text = TWO.replace("(:objects a b - coin)", f"(:objects {objects} - coin)") \
        .replace("(and (up a) (up b))", "(up k0)")
    domain = parse_domain(text, "many.pddl")
    learner, planner = ground_ppddl(domain, parse_problem(text, domain, "many.pddl"))
    flip = op_named(learner, "(flip)")
    assert flip.factored and flip.product_size() == 8192 and len(flip.parts) == 14
    assert flip.parts[0] == (GroundOutcome(1.0, 0, 0),)
    assert [sorted(o.probability for o in part) for part in flip.parts[1:]] == [[0.5, 0.5]] * 13
    every = (1 << 13) - 1
    assert [o.add for o in flip.outcomes] == [every] + [every & ~(1 << i) for i in range(13)]
    assert flip.outcomes[0].probability == 0.5 ** 13
    assert flip.known == tuple(range(14)) and len(planner.ops) == 14
    fewer = text.replace(" k12 ", " ")
    domain = parse_domain(fewer, "many.pddl")
    learner, _ = ground_ppddl(domain, parse_problem(fewer, domain, "many.pddl"))
    assert len(op_named(learner, "(flip)").outcomes) == 4096
    assert not op_named(learner, "(flip)").factored


def test_too_many_outcomes_that_cannot_be_factored_name_the_forall():
    """A forall of draws inside one branch of a probabilistic effect is a mixture of
    products, not independent parts: past MAX_OUTCOMES it is refused, naming the forall's
    line and why it is not factored."""
    objects = " ".join(f"k{i}" for i in range(13))
    text = TWO.replace("(:objects a b - coin)", f"(:objects {objects} - coin)") \
        .replace("(and (up a) (up b))", "(up k0)") \
        .replace(":effect (forall (?c - coin) (probabilistic 1/2 (up ?c)))",
                 ":effect (probabilistic 1/2\n (forall (?c - coin) (probabilistic 1/2 (up ?c))))")
    domain = parse_domain(text, "many.pddl")
    problem = parse_problem(text, domain, "many.pddl")
    with pytest.raises(PDDLError) as err:
        ground_ppddl(domain, problem)
    message = str(err.value)
    assert message.startswith("many.pddl:5:"), message  # the line of the forall
    assert f"more than {MAX_OUTCOMES} outcomes" in message and "(flip)" in message
    assert "\n" not in message


def test_a_cost_inside_the_forall_is_paid_per_binding():
    """Three coins, each costing 1 to throw: -3 in every outcome."""
    text = COINS.replace("(forall (?c - coin) (probabilistic 1/4 (up ?c)))",
                         "(forall (?c - coin) (and (decrease (reward) 1) "
                         "(probabilistic 1/4 (up ?c))))")
    learner, _ = grounded(text, text)
    assert {o.reward for o in op_named(learner, "(shake)").outcomes} == {-3.0}


@pytest.mark.parametrize("seed", range(60))
def test_random_foralls_of_probabilistic_effects_agree_with_the_interpreter(seed):
    """As ``test_the_grounded_model_agrees_with_an_independent_interpreter``, with forall
    effects whose bodies are any effect (probabilistic, when, and, nested foralls)."""
    rng = np.random.default_rng(1000 + seed)
    interpreted_model_agrees(*random_domain(rng, choices=True))


def test_a_failed_trial_in_any_draw_fails_the_trial():
    """Two coins, each breaks the machine with 1/10: a failed trial with 1 - 0.9^2 = 0.19,
    one outcome; otherwise both up (0.81)."""
    text = TWO.replace("(:predicates (up ?c - coin))", "(:predicates (up ?c - coin) (stuck))") \
        .replace("(probabilistic 1/2 (up ?c))", "(probabilistic 1/10 (stuck) 9/10 (up ?c))")
    learner, _ = grounded(text, text)
    flip = op_named(learner, "(flip)")
    outcomes = sorted((o.stuck, o.probability) for o in flip.outcomes)
    assert [stuck for stuck, _ in outcomes] == [False, True]
    assert [p for _, p in outcomes] == pytest.approx([0.81, 0.19])


def test_a_quantified_goal_too_wide_before_its_static_atoms_are_decided_is_read():
    """forall box exists city (destination and at): 5^10 alternatives as written, one
    conjunction once the static destinations are decided (IPPC-2008 boxworld's goal)."""
    boxes = " ".join(f"b{i}" for i in range(10))
    cities = ("c0", "c1", "c2", "c3", "c4")
    dests = " ".join(f"(dest b{i} {cities[i % 5]})" for i in range(10))
    text = f"""(define (domain ship) (:requirements :adl :probabilistic-effects)
  (:types box city)
  (:predicates (at ?b - box ?c - city) (dest ?b - box ?c - city))
  (:action move :parameters (?b - box ?c - city)
    :effect (probabilistic 1/2 (at ?b ?c))))
(define (problem ship-1) (:domain ship) (:objects {boxes} - box {' '.join(cities)} - city)
  (:init {dests})
  (:goal (forall (?b - box) (exists (?c - city) (and (dest ?b ?c) (at ?b ?c))))))
"""
    domain = parse_domain(text, "ship.pddl")
    problem = parse_problem(text, domain, "ship.pddl")
    assert sorted(str(lit.atom) for lit in problem.goal) == \
        sorted(f"(at b{i} {cities[i % 5]})" for i in range(10))
    assert problem.goal_alternatives == ()
