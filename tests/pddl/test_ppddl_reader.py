"""PPDDL input, the reader: probabilistic effects flattened into outcomes that sum to
one, probabilities in either notation, costs from functions, and file:line errors of
bad domains and problems."""

from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.envs.solve import expected_costs
from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import parse_domain, parse_problem
from tests.pddl.hike import HIKE_DOMAIN, HIKE_PROBLEM, action

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
    notation (``125e-7``) that sum to 1 leave no "no effect" outcome; one more of 1e-13
    (what floats printed in full miss 1 by) is taken as a sum of 1, one of 1e-8 is too
    much, and one of 10**-MAX_EXPONENT, the smallest a number may be written, underflows
    a float."""
    from gdq_pddl.pddl.formulas import MAX_EXPONENT

    ks = [*weights, 10**digits - sum(weights)]
    probs = [f"{k}e-{digits}" if scientific else f"0.{k:0{digits}d}" for k in ks]
    effects = ["(at ?b)", "(not (at ?a))", "(trail ?b ?a)", "(not (trail ?a ?b))"]
    pairs = " ".join(f"{p} {e}" for p, e in zip(probs, effects, strict=False))
    walk = parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, f"(probabilistic {pairs})")).actions[0]
    assert all(o.effect for o in walk.outcomes)
    assert sum(o.probability for o in walk.outcomes) == pytest.approx(1.0)
    close = parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, f"(probabilistic {pairs} "
                                                          "1e-13 (at ?a))")).actions[0]
    assert sum(o.probability for o in close.outcomes) == pytest.approx(1.0, abs=1e-15)
    assert all(o.effect for o in close.outcomes)
    with pytest.raises(PDDLError, match=r"sum to 1\.00000001, 1e-08 more than 1; they must "
                                        r"sum to at most 1 \(within 1e-12"):
        parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, f"(probabilistic {pairs} 1e-8 (at ?a))"))
    tiny = f"(probabilistic {pairs} 1e-{MAX_EXPONENT} (at ?a))"
    with pytest.raises(PDDLError, match=f"the probability 1e-{MAX_EXPONENT} is below the "
                                        "smallest positive float"):
        parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, tiny))
    with pytest.raises(PDDLError, match=f"1e-{MAX_EXPONENT + 1}: an exponent past"):
        parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, tiny.replace(f"e-{MAX_EXPONENT}",
                                                                   f"e-{MAX_EXPONENT + 1}")))


@pytest.mark.parametrize(("old", "new", "line", "expected"), [
    ("0.5 (and (at ?b)", "0.7 (and (at ?b)", 15,
     "sum to 1.1, 0.1 more than 1; they must sum to at most 1"),
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


def test_a_sum_past_1_by_float_printing_is_1_and_the_likeliest_outcome_gives_it_up():
    """0.1 + 0.2 + 0.7000000000000001 (as a float sum prints it) is 1 + 1e-16: read as 1,
    the excess taken off the likeliest outcome, so the probabilities are as meant."""
    effect = "(probabilistic 0.1 (at ?b) 0.2 (trail ?b ?a) 0.7000000000000001 (at ?a))"
    walk = parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, effect)).actions[0]
    assert [o.probability for o in walk.outcomes] == [0.1, 0.2, 0.7]


@pytest.mark.parametrize(("effect", "expected"), [
    ("(probabilistic 1e-400 (at ?b) 0.5 (at ?a))",
     r"hike.pddl:10: action walk: the probability 1e-400 is below the smallest positive "
     r"float \(about 5e-324\): it would underflow to 0"),
    ("(probabilistic 1e-200 (probabilistic 1e-200 (at ?b)))",
     r"hike.pddl:6: action walk: an outcome's probability, the product of nested "
     r"\(probabilistic ...\) ones, is about 1e-400: below the smallest positive float"),
])
def test_a_probability_that_underflows_a_float_is_refused_saying_so(effect, expected):
    """Before: 1e-400 was read as an outcome of probability 0.0, and refused later for
    another reason (or run with an outcome that never happens)."""
    with pytest.raises(PDDLError, match=f"^{expected}"):
        parse_domain(HIKE_DOMAIN.replace(WALK_EFFECT, effect), "hike.pddl")
