"""h_add (``planning/heuristic.py: HAdd``): values derived by hand on small domains of our
own (STRIPS, a PPDDL action with conditional effects, a disjunctive precondition, a goal
with alternatives), and on random small PPDDL tasks against a plain Python fixpoint over
facts, beside h_max (compiled, and a plain Python one) on the same relaxed actions."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.pddl import ground, parse_domain, parse_problem
from gdq_pddl.pddl.grounding import GroundOp, GroundOutcome, GroundTask, set_bits
from gdq_pddl.pddl.ppddl import ProbabilisticTask, ground_ppddl
from gdq_pddl.pddl.wordrows import words
from gdq_pddl.planning.heuristic import INFINITE, HAdd, HMax, hadd_for, hmax_for
from tests.pddl.ippc import random_domain


def strips(text: str) -> GroundTask:
    """The grounded STRIPS task of a domain and its problem in one text."""
    domain = parse_domain(text, "d.pddl")
    return ground(domain, parse_problem(text, domain, "d.pddl"))


def ppddl(text: str, determinisation: str = "all-outcomes"):
    """Reality's task and the planner's of a PPDDL domain and its problem in one text."""
    domain = parse_domain(text, "d.pddl")
    return ground_ppddl(domain, parse_problem(text, domain, "d.pddl"), determinisation)


def rows(task: GroundTask, states: list[int]) -> np.ndarray:
    n_words = (len(task.facts) + 63) // 64
    return np.stack([words(s, n_words) for s in states])


# --- by hand ------------------------------------------------------------------------------

# One gripper, two rooms, two balls in room a; both must go to b.
GRIPPER = """(define (domain gripper) (:requirements :strips :typing)
  (:types room ball)
  (:predicates (at-robby ?r - room) (at ?b - ball ?r - room) (carry ?b - ball) (free))
  (:action move :parameters (?from ?to - room)
    :precondition (at-robby ?from)
    :effect (and (at-robby ?to) (not (at-robby ?from))))
  (:action pick :parameters (?b - ball ?r - room)
    :precondition (and (at ?b ?r) (at-robby ?r) (free))
    :effect (and (carry ?b) (not (at ?b ?r)) (not (free))))
  (:action drop :parameters (?b - ball ?r - room)
    :precondition (and (carry ?b) (at-robby ?r))
    :effect (and (at ?b ?r) (free) (not (carry ?b)))))
(define (problem two-balls) (:domain gripper)
  (:objects a b - room b1 b2 - ball)
  (:init (at-robby a) (at b1 a) (at b2 a) (free))
  (:goal (and (at b1 b) (at b2 b))))
"""


def test_gripper_by_hand():
    """From the start: c(at-robby b) = 1, c(carry bi) = 1 (pick in a), c(at bi b) = 1 +
    c(carry bi) + c(at-robby b) = 3: h_add = 6 (h_max = 2; the plan takes 7).
    Robot in b holding b1, b2 in a: c(at b1 b) = 1, c(free) = c(at-robby a) = 1,
    c(carry b2) = 1 + 0 + 1 + 1 = 3, c(at b2 b) = 1 + 3 + 0 = 4: h_add = 5 (h_max = 3;
    the plan takes 5)."""
    task = strips(GRIPPER)
    h, hm = HAdd(task), HMax(task)
    mid = task.mask({"(at-robby b)", "(carry b1)", "(at b2 a)"})
    done = task.mask({"(at b1 b)", "(at b2 b)", "(at-robby a)"})
    assert [h(task.init), h(mid), h(done)] == [6, 5, 0]
    assert [hm(s, task.goal_pos) for s in (task.init, mid, done)] == [2, 3, 0]
    nothing = task.mask({"(at b1 b)"})  # b2 is nowhere and no action puts it anywhere
    assert h(nothing) == hm(nothing, task.goal_pos) == INFINITE
    assert h.many(rows(task, [task.init, mid, done, nothing])).tolist() == [6, 5, 0, -1]


def line(n: int) -> str:
    """Positions p0 .. p<n-1> in a line, walked both ways; moving to a position visits it."""
    names = [f"p{i}" for i in range(n)]
    links = " ".join(f"(link {a} {b}) (link {b} {a})" for a, b in zip(names, names[1:],
                                                                     strict=False))
    return f"""(define (domain line) (:requirements :strips)
  (:predicates (at ?p) (visited ?p) (link ?a ?b))
  (:action walk :parameters (?a ?b)
    :precondition (and (at ?a) (link ?a ?b))
    :effect (and (at ?b) (visited ?b) (not (at ?a)))))
(define (problem walk) (:domain line) (:objects {' '.join(names)})
  (:init (at p0) {links})
  (:goal (and (visited p40) (at p{n - 1}))))
"""


def test_a_task_of_more_than_two_words_by_hand():
    """70 positions: 70 at-facts and 70 visited-facts, three words a row. c(at pk) =
    c(visited pk) = the distance to pk; the goal visits p40 and ends at p69."""
    task = strips(line(70))
    assert len(task.facts) == 140
    h = HAdd(task)

    def at(*places: str) -> int:
        return task.mask({f"(at {p})" for p in places})

    states = [task.init, at("p50"), at("p69") | task.mask({"(visited p40)"}), at("p65", "p35"),
              task.mask({"(visited p40)"})]
    want = [40 + 69, 10 + 19, 0, 5 + 4, INFINITE]
    assert [h(s) for s in states] == want
    assert h.many(rows(task, states)).tolist() == want
    hm = HMax(task)
    assert [hm(s, task.goal_pos) for s in states] == [69, 19, 0, 5, INFINITE]


# A lamp lights when flipped with the power on (a conditional effect of the likely
# outcome), or by luck (an unlikely outcome); it warms up if also not broken; it smokes
# if broken -- which flip's own precondition excludes, so it never does.
LAMP = """(define (domain lamp)
  (:requirements :adl :probabilistic-effects :conditional-effects)
  (:predicates (tool) (power) (switch-on) (lit) (warm) (broken) (smoke))
  (:action get-tool :parameters () :effect (tool))
  (:action fix :parameters () :precondition (tool) :effect (power))
  (:action break :parameters () :effect (broken))
  (:action flip :parameters () :precondition (not (broken))
    :effect (probabilistic
              0.7 (and (switch-on) (when (power) (lit))
                       (when (and (power) (not (broken))) (warm)) (when (broken) (smoke)))
              0.1 (lit))))
(define (problem dark) (:domain lamp) (:init) (:goal (lit)))
"""


@pytest.mark.parametrize("determinisation", ["all-outcomes", "most-likely"])
def test_conditional_effects_by_hand(determinisation):
    """c(tool) = 1, c(power) = 2. lit: by luck (all-outcomes only) 1, else flip with power
    1 + 2 = 3; warm: 3 either way; smoke: never (the condition contradicts flip's
    precondition). The planner's STRIPS variants relax to the same values."""
    learner, planner = ppddl(LAMP, determinisation)
    lit = 1 if determinisation == "all-outcomes" else 3
    for task in (learner, planner):
        h, hm = HAdd(task), HMax(task)
        assert h(task.init) == lit and hm(task.init, task.goal_pos) == min(lit, 3)
        both = replace(task, goal_pos=task.mask({"(lit)", "(warm)"}))
        assert HAdd(both)(task.init) == lit + 3
        assert HMax(both)(task.init, both.goal_pos) == 3
        powered = task.mask({"(power)"})
        assert HAdd(both)(powered) == 2
        smoke = replace(task, goal_pos=task.mask({"(smoke)"}))
        assert HAdd(smoke)(task.init) == INFINITE
        assert HMax(smoke)(task.init, smoke.goal_pos) == INFINITE


# The door opens with the key (which needs the map and the lamp) or with a crowbar and
# strength.
DOOR = """(define (domain door) (:requirements :adl :probabilistic-effects)
  (:predicates (map) (lamp) (key) (crowbar) (strong) (open))
  (:action read :parameters () :effect (map))
  (:action light :parameters () :effect (lamp))
  (:action get-key :parameters () :precondition (and (map) (lamp)) :effect (key))
  (:action get-crowbar :parameters () :effect (probabilistic 0.5 (crowbar)))
  (:action train :parameters () :effect (strong))
  (:action open :parameters () :precondition (or (key) (and (crowbar) (strong)))
    :effect (open)))
(define (problem shut) (:domain door) (:init) (:goal (open)))
"""


def test_a_disjunctive_precondition_by_hand():
    """c(key) = 1 + c(map) + c(lamp) = 3, c(crowbar) = c(strong) = 1: open costs 1 + 3 by
    the key, 1 + 2 by the crowbar: h_add = 3 (h_max = 2). With the key: 1. With the
    crowbar: 1 + min(3, 0 + 1) = 2."""
    learner, planner = ppddl(DOOR)
    opener = next(op for op in learner.ops if op.name == "(open)")
    assert len(opener.alternatives) == 2
    for task in (learner, planner):
        h, hm = HAdd(task), HMax(task)
        key, crowbar = task.mask({"(key)"}), task.mask({"(crowbar)"})
        assert [h(task.init), h(key), h(crowbar)] == [3, 1, 2]
        assert [hm(s, task.goal_pos) for s in (task.init, key, crowbar)] == [2, 1, 2]


def test_a_goal_with_alternatives_by_hand():
    """(and (map) (or (open) (and (crowbar) (lamp)))): c(map) = 1 plus the cheaper of
    c(open) = 3 and c(crowbar) + c(lamp) = 2: h_add = 3; 0 once map, crowbar and lamp
    hold, though open does not; 1 with the lamp and the crowbar."""
    text = DOOR.replace("(:goal (open))", "(:goal (and (map) (or (open) (and (crowbar) "
                                          "(lamp)))))")
    learner, _ = ppddl(text)
    assert learner.goal_alternatives
    h = HAdd(learner)
    ready = learner.mask({"(map)", "(crowbar)", "(lamp)"})
    assert [h(learner.init), h(ready), h(learner.mask({"(crowbar)", "(lamp)"}))] == [3, 0, 1]
    assert h.many(rows(learner, [learner.init, ready])).tolist() == [3, 0]


def test_an_impossible_goal_is_infinite_everywhere():
    """A goal atom no action adds is no fact: the goal can never hold."""
    learner, _ = ppddl(DOOR.replace("(:goal (open))", "(:goal (and (open) (gold)))")
                       .replace("(open))\n  (:action read", "(open) (gold))\n  (:action read"))
    assert not learner.goal_possible
    h = HAdd(learner)
    assert h(learner.init) == INFINITE
    assert h.many(rows(learner, [learner.init, learner.mask({"(open)"})])).tolist() == [-1, -1]


def test_hadd_for_is_cached_per_task():
    learner, planner = ppddl(DOOR)
    assert hadd_for(learner) is hadd_for(learner)
    assert hadd_for(planner) is not hadd_for(learner)
    assert hmax_for(learner) is hmax_for(learner)


# --- property: random small tasks against plain Python fixpoints ---------------------------

def rules(task: GroundTask) -> list[tuple[int, int]]:
    """The relaxed actions ``(positive preconditions, adds)``, read from the ground
    actions as the semantics in HAdd's docstring states them."""
    out = []
    for op in task.ops:  # a STRIPS action: (pre, add)
        for p, n in op.alternatives or ((0, 0),):
            pos, neg = op.pre | p, op.neg | n
            for k in op.known:
                out.append((pos, op.outcomes[k].add))
                out += [(pos | cp, a) for cp, cn, a, _ in op.outcomes[k].conditional
                        if not (pos | cp) & (neg | cn)]
    return out


def fixpoint(task: GroundTask, state: int, combine) -> dict[int, int]:
    """Each fact's relaxed cost from ``state`` (absent: unreachable): 0 in ``state``, else
    the least ``1 + combine(costs of the preconditions)`` of a relaxed action adding it,
    iterated until nothing changes."""
    cost = dict.fromkeys(set_bits(state), 0)
    actions = rules(task)
    changed = True
    while changed:
        changed = False
        for pre, add in actions:
            need = list(set_bits(pre))
            if all(f in cost for f in need):
                c = 1 + combine([cost[f] for f in need])
                for f in set_bits(add):
                    if c < cost.get(f, c + 1):
                        cost[f] = c
                        changed = True
    return cost


def hmax_of(costs: list[int]) -> int:
    return max(costs, default=0)


def reference(task: GroundTask, state: int, combine) -> int:
    """h_add (``combine=sum``) or h_max (:func:`hmax_of`) of the task's goal, alternatives
    read as HAdd's docstring says (h_max: of the cheapest alternative)."""
    if not task.goal_possible:
        return INFINITE
    cost = fixpoint(task, state, combine)

    def of(mask: int) -> int | None:
        need = list(set_bits(mask))
        return combine([cost[f] for f in need]) if all(f in cost for f in need) else None

    if not task.goal_alternatives:
        value = of(task.goal_pos)
        return INFINITE if value is None else value
    if combine is hmax_of:
        values = [of(task.goal_pos | p) for p, _ in task.goal_alternatives]
    else:
        base = of(task.goal_pos)
        values = [None if base is None or of(p & ~task.goal_pos) is None
                  else base + of(p & ~task.goal_pos) for p, _ in task.goal_alternatives]
    values = [v for v in values if v is not None]
    return min(values) if values else INFINITE


ATOMS = ["(p o1)", "(p o2)", "(q o1)", "(q o2)", "(r)"]  # s is static


def random_goal(rng: np.random.Generator) -> str:
    """A conjunction of one to three atoms, and one time in three a disjunction besides."""
    def conj(k: int) -> str:
        return "(and " + " ".join(rng.choice(ATOMS, size=k, replace=False)) + ")"
    goal = conj(int(rng.integers(1, 4)))
    if rng.random() < 1 / 3:
        goal = f"(and {goal} (or {conj(int(rng.integers(1, 3)))} {conj(2)}))"
    return goal


def relaxed_goal(task: GroundTask, state: int) -> bool:
    return task.goal_possible and state & task.goal_pos == task.goal_pos and (
        not task.goal_alternatives or any(state & p == p for p, _ in task.goal_alternatives))


@pytest.mark.parametrize("seed", range(30))
def test_random_tasks_agree_with_the_fixpoints(seed):
    """Reality's task (ground actions: outcomes, conditional effects, disjunctive
    preconditions) and the planner's (plain GroundOps), on random states: HAdd equals
    the fixpoint's h_add, one state or many; HMax equals the fixpoint's h_max (with
    alternatives: of the cheapest); h_add >= h_max, both 0 exactly where the relaxed goal
    holds and -1 together; the planner's STRIPS variants relax to no less than reality's
    actions (the same where no action has a conditional effect)."""
    rng = np.random.default_rng(seed)
    domain, problem = random_domain(rng)
    problem = problem.replace("(:goal (g))", f"(:goal {random_goal(rng)})")
    determinisation = ("all-outcomes", "most-likely")[seed % 2]
    dom = parse_domain(domain, "d.pddl")
    learner, planner = ground_ppddl(dom, parse_problem(problem, dom, "p.pddl"), determinisation)
    n = len(learner.facts)
    states = [learner.init, 0, (1 << n) - 1] + [int(rng.integers(0, 1 << n)) for _ in range(12)]
    conditional = any(o.conditional for op in learner.ops for o in op.outcomes)
    values = {}
    for task in (learner, planner):
        h, hm = HAdd(task), HMax(task)
        got = [h(s) for s in states]
        assert got == [reference(task, s, sum) for s in states], (domain, problem)
        assert h.many(rows(task, states)).tolist() == got
        for s, value in zip(states, got, strict=True):
            hmax = reference(task, s, hmax_of)
            if not task.goal_alternatives and task.goal_possible:
                assert hm(s, task.goal_pos) == hmax
            assert (value == INFINITE) == (hmax == INFINITE)
            assert value == INFINITE or value >= hmax
            assert (value == 0) == (hmax == 0) == relaxed_goal(task, s)
        values[task is planner] = got
    if not planner.incomplete:
        pairs = zip(values[False], values[True], strict=True)
        assert all(b == INFINITE or a != INFINITE and b >= a for a, b in pairs), \
            (domain, problem)
        if not conditional:
            assert values[False] == values[True], (domain, problem)


def random_task(rng: np.random.Generator, n_facts: int = 14,
                n_ops: int = 24) -> ProbabilisticTask:
    """A random task built directly from masks, larger and deeper than the PDDL ones:
    plain and probabilistic ground actions side by side, outcomes the planner does and
    does not know, conditional effects (some contradicting the precondition), disjunctive
    preconditions, and a goal with or without alternatives."""
    def some(p: float) -> int:
        return int(sum(1 << f for f in np.flatnonzero(rng.random(n_facts) < p)))

    ops: list[GroundOp] = []
    for i in range(n_ops):
        pre, neg = some(0.15), some(0.05)
        if rng.random() < 0.3:
            ops.append(GroundOp.strips(f"(plain{i})", pre, neg & ~pre, some(0.15), some(0.1)))
            continue
        outcomes = tuple(GroundOutcome(0.5, some(0.12), some(0.1), conditional=tuple(
            (some(0.15), some(0.1), some(0.15), some(0.05)) for _ in range(rng.integers(0, 3))))
            for _ in range(rng.integers(1, 4)))
        known = tuple(k for k in range(len(outcomes)) if rng.random() < 0.6)
        alternatives = tuple((some(0.15), some(0.05)) for _ in range(rng.integers(0, 3)))
        ops.append(GroundOp(f"(prob{i})", pre, neg & ~pre, outcomes, known,
                            tuple((p, n & ~p) for p, n in alternatives)))
    facts = tuple(f"(f{i})" for i in range(n_facts))
    return ProbabilisticTask(facts, tuple(ops), some(0.2), some(0.25), 0, True, frozenset(),
                             {f: i for i, f in enumerate(facts)},
                             goal_alternatives=tuple((some(0.2), 0)
                                                     for _ in range(rng.integers(0, 3))))


@pytest.mark.parametrize("seed", range(40))
def test_random_mask_tasks_agree_with_the_fixpoints(seed):
    """As above, on tasks built from random masks, with states of every density."""
    rng = np.random.default_rng(1000 + seed)
    task = random_task(rng)
    h, hm = HAdd(task), HMax(task)
    n = len(task.facts)
    states = [task.init, 0] + [int(sum(1 << f for f in np.flatnonzero(rng.random(n) < p)))
                               for p in (0.05, 0.1, 0.2, 0.3, 0.5) for _ in range(4)]
    got = [h(s) for s in states]
    assert got == [reference(task, s, sum) for s in states]
    assert h.many(rows(task, states)).tolist() == got
    for s, value in zip(states, got, strict=True):
        hmax = reference(task, s, hmax_of)
        if not task.goal_alternatives:
            assert hm(s, task.goal_pos) == hmax
        assert (value == INFINITE) == (hmax == INFINITE)
        assert value == INFINITE or value >= hmax
        assert (value == 0) == (hmax == 0) == relaxed_goal(task, s)
