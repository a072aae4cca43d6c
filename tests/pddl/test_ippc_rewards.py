"""PPDDL rewards (issue 22, item 1): ``(increase (reward) X)`` / ``(decrease (reward) X)``
at the top of an effect, inside ``probabilistic``, ``when`` and ``forall``; the metric."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.pddl.ppddl import ground_ppddl
from tests.pddl.ippc import (
    OBJECTS,
    costed_domain,
    holds,
    interpreted_rewards_agree,
    random_condition,
    random_domain,
    random_effect,
    sexp,
)

DOMAIN = """(define (domain r) (:requirements :typing :rewards)
  (:types coin)
  (:predicates (shiny ?c - coin) (held ?c - coin) (done))
  (:functions (worth ?c - coin))
  (:action take :parameters (?c - coin)
    :effect (and (held ?c) (increase (reward) (worth ?c)) (decrease (reward) 1)))
  (:action gamble
    :effect (probabilistic 1/4 (and (done) (increase (reward) 8)) 3/4 (decrease (reward) 2)))
  (:action polish
    :effect (and (done) (forall (?c - coin) (when (and (held ?c) (not (shiny ?c)))
                                                (and (shiny ?c) (increase (reward) 3)))))))
"""
PROBLEM = """(define (problem p) (:domain r) (:objects a b - coin)
  (:init (= (worth a) 4) (= (worth b) 6)) (:goal (done)) (:goal-reward 10)
  (:metric maximize (reward)))"""


def grounded():
    domain = parse_domain(DOMAIN)
    learner, _ = ground_ppddl(domain, parse_problem(PROBLEM, domain))
    return domain, learner, {op.name: op for op in learner.ops}


def test_rewards_are_read_where_they_stand():
    domain, learner, ops = grounded()
    assert domain.reward_effects
    take = next(a for a in domain.actions if a.name == "take")
    assert take.cost == (1.0,)  # a cost whatever happens stays the action's cost
    assert [r.sign for r in take.outcomes[0].rewards] == [1.0]
    assert [o.reward for o in ops["(take a)"].outcomes] == [4.0]
    assert [o.reward for o in ops["(take b)"].outcomes] == [6.0]
    assert sorted((o.probability, o.reward) for o in ops["(gamble)"].outcomes) == \
        [(0.25, 8.0), (0.75, -2.0)]


def test_a_reward_under_when_and_forall_counts_each_binding_that_holds():
    _, learner, ops = grounded()
    polish = ops["(polish)"].outcomes[0]
    m = {f: 1 << i for i, f in enumerate(learner.facts)}
    held_a, held_b, shiny_a = m["(held a)"], m["(held b)"], m["(shiny a)"]
    assert polish.gain(0) == 0.0
    assert polish.gain(held_a) == 3.0
    assert polish.gain(held_a | held_b) == 6.0
    assert polish.gain(held_a | held_b | shiny_a) == 3.0


def test_the_metric_is_kept_and_others_refused():
    domain = parse_domain(DOMAIN)
    assert parse_problem(PROBLEM, domain).metric == "maximize (reward)"
    bad = PROBLEM.replace("maximize (reward)", "minimize (total-time)")
    with pytest.raises(PDDLError, match=r"^p.pddl:3: \(:metric minimize \(total-time\)\) is "
                                        r"not supported: the metrics read are"):
        parse_problem(bad, domain, "p.pddl")


def test_a_negative_function_value_in_a_reward_is_refused_naming_it():
    domain = parse_domain(DOMAIN)
    problem = parse_problem(PROBLEM.replace("(= (worth b) 6)", "(= (worth b) -6)"), domain,
                            "p.pddl")
    with pytest.raises(PDDLError, match=r"^p.pddl: \(worth b\) = -6 in :init: a reward of "
                                        r"take must be >= 0"):
        ground_ppddl(domain, problem)


def reward_effect(rng, depth: int, variables: list[str], chance: bool = True) -> str:
    """A random effect of rewards and costs, nested in when, forall and (``chance``)
    probabilistic (never inside a forall: a choice per object is not read)."""
    k = int(rng.integers(1, 9))
    kind = rng.integers(0, 4 + chance) if depth > 0 else rng.integers(0, 2)
    if kind <= 1:
        return f"({('increase', 'decrease')[kind]} (reward) {k})"
    if kind == 2:
        return f"(when {random_condition(rng, 2, variables)} " \
               f"{reward_effect(rng, depth - 1, variables, chance)})"
    if kind == 3:
        v = f"?w{depth}"
        return f"(forall ({v} - t) (when {random_condition(rng, 1, [*variables, v])} " \
               f"{reward_effect(rng, depth - 1, [*variables, v], False)}))"
    return f"(probabilistic 1/3 {reward_effect(rng, depth - 1, variables)} " \
           f"1/2 (and {random_effect(rng, 1, variables)} " \
           f"{reward_effect(rng, depth - 1, variables)}))"


def expected_reward(e, b: dict[str, str], state: frozenset[str]) -> float:
    """The expected reward of effect ``e`` in ``state``: what an interpreter of PPDDL's
    text pays, by linearity (the action's cost included)."""
    head = e[0] if e else "and"
    if head == "and":
        return sum(expected_reward(x, b, state) for x in e[1:])
    if head == "forall":
        return sum(expected_reward(e[2], {**b, e[1][0]: o}, state) for o in OBJECTS)
    if head == "when":
        return expected_reward(e[2], b, state) if holds(e[1], b, state) else 0.0
    if head == "probabilistic":
        return sum(float(Fraction(p)) * expected_reward(sub, b, state)
                   for p, sub in zip(e[1::2], e[2::2], strict=True))
    if head in ("increase", "decrease") and e[1] == ["reward"]:
        return float(e[2]) * (1 if head == "increase" else -1)
    return 0.0


@pytest.mark.parametrize("seed", range(30))
def test_rewards_agree_with_an_independent_interpreter(seed):
    rng = np.random.default_rng(seed)
    domain_text, problem_text = random_domain(rng)
    lines = domain_text.split("\n")
    for i, line in enumerate(lines):  # each action's effect, with rewards beside it
        if line.strip().startswith(":effect"):
            closers = ")" * (line.count(")") - line.count("("))
            lines[i] = f"    :effect (and {random_effect(rng, 2, ['?x'])} " \
                f"{reward_effect(rng, 3, ['?x'])}){closers}"
    domain_text = "\n".join(lines)
    domain = parse_domain(domain_text)
    learner, _ = ground_ppddl(domain, parse_problem(problem_text, domain))
    costs = {op.name: op.cost for op in learner.ops}
    schemas = {a[1]: a[7] for a in sexp(domain_text)[0]
               if isinstance(a, list) and a[0] == ":action"}
    statics = frozenset(learner.statics)
    for state in {0, learner.init, *(int(x) for x in rng.integers(0, 1 << len(learner.facts),
                                                                 size=20))}:
        atoms = learner.atoms(state) | statics
        for op in learner.ops:
            if not op.holds(state):
                continue
            schema, arg = op.name.strip("()").split()
            ours = sum(o.probability * o.gain(state) for o in op.outcomes) - \
                (costs[op.name] or 0.0)
            assert ours == pytest.approx(expected_reward(schemas[schema], {"?x": arg}, atoms),
                                         abs=1e-9), (op.name, learner.atoms(state))


@settings(max_examples=25, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**32 - 1), own=st.booleans(), online=st.booleans())
def test_costs_and_rewards_in_every_construct_agree_with_the_interpreter(seed, own, online):
    """Property (issue 38): costs and rewards at the top of an effect and inside ``and``,
    ``when``, ``forall`` (of a ``probabilistic`` too) and ``probabilistic``, nested, on
    the goal scale and the problem's own, enumerated and online: every outcome pays what
    an interpreter of the text pays, and each action costs what it states whatever
    happens (1 on the goal scale where it states no cost anywhere). On the goal scale the
    costs inside constructs were dropped before."""
    interpreted_rewards_agree(*costed_domain(np.random.default_rng(seed)), own, online)
