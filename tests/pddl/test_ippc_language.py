"""The IPPC PPDDL language at the PDDL layer (issue 22, item 1): a domain and its problems
in one file, requirements that declare and never decide, every construct outside the
language listed at once; and, construct by construct, small domains of our own whose
grounded result is derived by hand in the comments."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from gdq_pddl.cli import main
from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import ground, parse_domain, parse_problem, read_domain, read_problem
from gdq_pddl.pddl.ppddl import ground_ppddl

# Two rooms and a door; opening is a coin flip. The domain and two problems in one file,
# as the IPPC-2008 distribution writes them.
ONE_FILE = """; a door between two rooms
(define (domain door)
  (:requirements :typing :probabilistic-effects)
  (:types room)
  (:predicates (in ?r - room) (open) (link ?a ?b - room))
  (:action push
    :parameters ()
    :precondition (not (open))
    :effect (probabilistic 1/2 (open)))
  (:action go
    :parameters (?a ?b - room)
    :precondition (and (in ?a) (link ?a ?b) (open))
    :effect (and (in ?b) (not (in ?a)))))

(define (problem door-1) (:domain door)
  (:objects hall kitchen - room)
  (:init (in hall) (link hall kitchen))
  (:goal (in kitchen)))

(define (problem door-2) (:domain door)
  (:objects hall kitchen - room)
  (:init (in kitchen) (link kitchen hall))
  (:goal (in hall)))
"""


def only(text: str, drop: str) -> str:
    """``ONE_FILE`` without the problem named ``drop``."""
    start = text.index(f"(define (problem {drop})")
    end = text.find("(define", start + 1)
    return text[:start] + (text[end:] if end >= 0 else "")


def test_a_domain_and_its_problems_in_one_file_are_read_by_name():
    domain = parse_domain(ONE_FILE, "door.pddl")
    assert domain.name == "door" and [a.name for a in domain.actions] == ["push", "go"]
    one = parse_problem(ONE_FILE, domain, "door.pddl", name="door-1")
    two = parse_problem(ONE_FILE, domain, "door.pddl", name="DOOR-2")  # names: any case
    assert [str(a) for a in sorted(one.init, key=str)] == ["(in hall)", "(link hall kitchen)"]
    assert [str(lit.atom) for lit in two.goal] == ["(in hall)"]


def test_several_problems_and_no_name_is_refused_listing_them():
    domain = parse_domain(ONE_FILE)
    with pytest.raises(PDDLError, match=r"^door.pddl:20: this file has 2 problems "
                                        r"\(door-1, door-2\): pick one by name "
                                        r"\(door.pddl:door-1\)$"):
        parse_problem(ONE_FILE, domain, "door.pddl")
    with pytest.raises(PDDLError, match=r"no problem named 'door-3' in this file \(it has "
                                        r"door-1, door-2\)"):
        parse_problem(ONE_FILE, domain, "door.pddl", name="door-3")


def test_a_file_of_only_problems_is_no_domain():
    domain = parse_domain(ONE_FILE)
    problems = ONE_FILE[ONE_FILE.index("(define (problem door-1)"):]
    with pytest.raises(PDDLError, match="^p.pddl: expected a .define .domain NAME"):
        parse_domain(problems, "p.pddl")
    with pytest.raises(PDDLError, match="^d.pddl: expected a .define .problem NAME.*only "
                                        "domains"):
        parse_problem(ONE_FILE[:ONE_FILE.index("(define (problem")], domain, "d.pddl")


def test_one_file_given_as_both_domain_and_problem_runs(capsys, tmp_path):
    """The command line reads the same file as the domain and as the problem."""
    path = tmp_path / "door.pddl"
    path.write_text(only(ONE_FILE, "door-2"), encoding="utf-8")
    domain = read_domain(path)
    learner, _ = ground_ppddl(domain, read_problem(path, domain))
    # push (open: 1/2) then go: the ground actions, hand-derived
    assert [op.name for op in learner.ops] == ["(push)", "(go hall kitchen)"]
    code = main(["run", "--domain", str(path), "--problem", str(path), "--episodes", "3",
                 "--runs", "1", "--method", "Q-learning", "--jobs", "1", "--no-report",
                 "--out", str(tmp_path / "out")])
    out = capsys.readouterr()
    assert code == 0, out.out + out.err
    assert (tmp_path / "out" / "episodes.csv").exists()


def test_a_type_glued_to_its_dash_is_read_as_lexers_read_it():
    """``(?loc -zone)``, as a published IPPC domain writes it: '-zone' is '- zone'."""
    domain = parse_domain(ONE_FILE.replace("(?a ?b - room)", "(?a ?b -room)"))
    assert domain.actions[1].parameters == (("?a", "room"), ("?b", "room"))


# --- requirements declare, never decide -------------------------------------------------

def test_an_undeclared_requirement_does_not_block_its_construct():
    """A negative precondition without :negative-preconditions is read, in a STRIPS
    domain as in a PPDDL one; before, only a PPDDL domain got this leniency."""
    text = """(define (domain d) (:requirements :strips)
      (:predicates (a) (b))
      (:action go :parameters () :precondition (not (b)) :effect (b)))"""
    domain = parse_domain(text)
    task = ground(domain, parse_problem("(define (problem p) (:domain d) (:init (a)) "
                                        "(:goal (b)))", domain))
    assert [op.name for op in task.ops] == ["(go)"]
    assert task.ops[0].neg == 1 << task.fact_index["(b)"]


def test_a_declared_requirement_never_blocks_a_file():
    """IPPC files declare :adl, :conditional-effects, :fluents... whatever they use."""
    reqs = ":adl :conditional-effects :fluents :rewards :mdp :equality :universal-preconditions"
    domain = parse_domain(ONE_FILE.replace(":typing :probabilistic-effects", f":typing {reqs}"))
    assert ":conditional-effects" in domain.requirements


# --- every construct outside the language, at once -----------------------------------------

def test_every_construct_outside_the_language_is_listed():
    text = ONE_FILE.replace(":effect (probabilistic 1/2 (open))",
                            ":effect (oneof (open) (and))") \
        .replace("(:types room)", "(:types room)\n  (:derived (open) (open))") \
        .replace(":effect (and (in ?b) (not (in ?a)))", ":effect (and (in ?b) (assign "
                 "(fuel) 1)\n (oneof (in ?a) (in ?b)))")
    with pytest.raises(PDDLError) as err:
        parse_domain(text, "door.pddl")
    message = str(err.value)
    assert message.startswith("door.pddl:5: not supported"), message
    for listed in ("(:derived ...) at line 5", "(oneof ...) (FOND: give probabilities with "
                   "(probabilistic ...)) at lines 10, 15", "(assign ...) (numeric fluents) at "
                   "line 14"):
        assert listed in message, message
    assert "\n" not in message


# --- constructs, each in a small domain with its grounded result derived by hand ----------

def grounded(domain_text: str, problem_text: str):
    domain = parse_domain(domain_text, "d.pddl")
    return ground_ppddl(domain, parse_problem(problem_text, domain, "p.pddl"))


def mask(task, *atoms: str) -> int:
    return task.mask(set(atoms))


def dist(op, state: int) -> dict[int, float]:
    """Where ``op`` leads from ``state``: next state -> probability."""
    out: dict[int, float] = {}
    for o in op.outcomes:
        t = o.apply(state)
        out[t] = out.get(t, 0.0) + o.probability
    return out


def op_named(task, name: str):
    return next(op for op in task.ops if op.name == name)


def planner_agrees(learner, planner) -> None:
    """In every state over the facts, the planner's STRIPS ops of each ground action are
    applicable exactly where it is, and lead where its kept outcomes lead."""
    by_origin: dict[str, list] = {}
    for op in planner.ops:
        by_origin.setdefault(learner.origin.get(op.name, op.name), []).append(op)
    for state in range(1 << len(learner.facts)):
        applicable = {op.name for op in learner.applicable(state)}
        for op in learner.ops:
            nexts = {o.apply(state) for k, o in enumerate(op.outcomes) if k in op.known}
            variants = [v for v in by_origin.get(op.name, []) if v.applicable(state)]
            assert bool(variants) == (op.name in applicable and bool(op.known)), (op.name, state)
            assert {v.apply(state) for v in variants} == (nexts if variants else set())


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
#
# Random small domains over one type, two objects, fluents p/1, q/1, r/0 and a static s/1,
# with conditions and effects drawn from the whole language. The interpreter below reads
# the PDDL text itself (its own s-expression reader) and applies PDDL's semantics
# directly: no normal form, no grounding. From the initial state it explores every state
# reality reaches; in each, every ground action must be applicable exactly when the
# library says, and lead to the same distribution of next states.

OBJECTS = ("o1", "o2")


def sexp(text: str):
    tokens = text.replace("(", " ( ").replace(")", " ) ").split()
    stack: list[list] = [[]]
    for tok in tokens:
        if tok == "(":
            stack.append([])
        elif tok == ")":
            done = stack.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(tok.lower())
    return stack[0]


def holds(c, b: dict[str, str], state: frozenset[str]) -> bool:
    head = c[0] if c else "and"
    if head == "and":
        return all(holds(x, b, state) for x in c[1:])
    if head == "or":
        return any(holds(x, b, state) for x in c[1:])
    if head == "not":
        return not holds(c[1], b, state)
    if head == "imply":
        return not holds(c[1], b, state) or holds(c[2], b, state)
    if head in ("forall", "exists"):
        var = c[1][0]
        test = all if head == "forall" else any
        return test(holds(c[2], {**b, var: o}, state) for o in OBJECTS)
    args = [b.get(a, a) for a in c[1:]]
    if head == "=":
        return args[0] == args[1]
    return "(" + " ".join([head, *args]) + ")" in state


def effect(e, b: dict[str, str], state: frozenset[str]) -> list[tuple]:
    """``[(probability, adds, deletes)]`` of effect ``e`` in ``state``."""
    head = e[0] if e else "and"
    if head == "and":
        out = [(1.0, frozenset(), frozenset())]
        for x in e[1:]:
            out = [(p * q, a | a2, d | d2) for p, a, d in out for q, a2, d2 in effect(x, b, state)]
        return out
    if head == "forall":
        var, out = e[1][0], [(1.0, frozenset(), frozenset())]
        for o in OBJECTS:
            out = [(p * q, a | a2, d | d2) for p, a, d in out
                   for q, a2, d2 in effect(e[2], {**b, var: o}, state)]
        return out
    if head == "when":
        return effect(e[2], b, state) if holds(e[1], b, state) else \
            [(1.0, frozenset(), frozenset())]
    if head == "probabilistic":
        out, total = [], 0.0
        for p_text, sub in zip(e[1::2], e[2::2], strict=True):
            p = float(Fraction(p_text))
            total += p
            out += [(p * q, a, d) for q, a, d in effect(sub, b, state)]
        return out + [(1.0 - total, frozenset(), frozenset())]
    if head == "not":
        atom = "(" + " ".join([e[1][0], *(b.get(a, a) for a in e[1][1:])]) + ")"
        return [(1.0, frozenset(), frozenset((atom,)))]
    atom = "(" + " ".join([head, *(b.get(a, a) for a in e[1:])]) + ")"
    return [(1.0, frozenset((atom,)), frozenset())]


def random_condition(rng, depth: int, variables: list[str]) -> str:
    atoms = [f"(p {v})" for v in variables] + [f"(q {v})" for v in variables] + \
        [f"(s {v})" for v in variables] + ["(r)"]
    kind = rng.integers(0, 8) if depth > 0 else 0
    if kind <= 1:
        return atoms[rng.integers(len(atoms))]
    if kind == 2:
        return f"(not {random_condition(rng, depth - 1, variables)})"
    if kind in (3, 4):
        word = ("and", "or")[kind - 3]
        return f"({word} {random_condition(rng, depth - 1, variables)} " \
               f"{random_condition(rng, depth - 1, variables)})"
    if kind == 5:
        return f"(imply {random_condition(rng, depth - 1, variables)} " \
               f"{random_condition(rng, depth - 1, variables)})"
    if kind == 6:
        v = f"?v{depth}"
        word = ("forall", "exists")[int(rng.integers(2))]
        return f"({word} ({v} - t) {random_condition(rng, depth - 1, [*variables, v])})"
    a, b = rng.choice(variables, size=2)
    return f"(= {a} {b})"


def random_effect(rng, depth: int, variables: list[str], choices: bool = False) -> str:
    """A random effect; ``choices``: a forall's body may be any effect (probabilistic ones
    too), else a when of a literal."""
    lits = [f"(p {v})" for v in variables] + [f"(q {v})" for v in variables] + ["(r)"]
    lit = lits[rng.integers(len(lits))]
    kind = rng.integers(0, 8 if choices else 6) if depth > 0 else 0
    if kind >= 6:  # a forall of a draw, under a when or beside a literal
        v = f"?w{depth}"
        inner = [*variables, v]
        body = f"(probabilistic 1/4 {random_effect(rng, depth - 1, inner, choices)} " \
               f"1/2 {random_effect(rng, depth - 1, inner, choices)})"
        if kind == 6:
            body = f"(when {random_condition(rng, 1, inner)} {body})"
        else:
            body = f"(and {random_effect(rng, 0, inner)} {body})"
        return f"(forall ({v} - t) {body})"
    if kind == 0:
        return lit
    if kind == 1:
        return f"(not {lit})"
    if kind == 2:
        return f"(and {random_effect(rng, depth - 1, variables, choices)} " \
               f"{random_effect(rng, depth - 1, variables, choices)})"
    if kind == 3:
        return f"(when {random_condition(rng, 2, variables)} " \
               f"{random_effect(rng, depth - 1, variables, choices)})"
    if kind == 4:
        v = f"?w{depth}"
        if choices and rng.random() < 0.7:
            body = random_effect(rng, depth - 1, [*variables, v], choices)
        else:
            body = f"(when {random_condition(rng, 1, [*variables, v])} " \
                   f"{random_effect(rng, 0, [*variables, v])})"
        return f"(forall ({v} - t) {body})"
    return f"(probabilistic 1/3 {random_effect(rng, depth - 1, variables, choices)} " \
           f"1/2 {random_effect(rng, depth - 1, variables, choices)})"


def random_domain(rng, choices: bool = False) -> tuple[str, str]:
    actions = []
    for i in range(3):
        actions.append(f"""  (:action a{i} :parameters (?x - t)
    :precondition {random_condition(rng, 3, ['?x'])}
    :effect {random_effect(rng, 2 if choices else 3, ['?x'], choices)})""")
    init = [f"({p} {o})" for p in "pqs" for o in OBJECTS if rng.random() < 0.5]
    init += ["(r)"] * int(rng.random() < 0.5)
    domain = ("(define (domain rnd) (:requirements :adl :probabilistic-effects)\n"
              "  (:types t)\n  (:predicates (p ?x - t) (q ?x - t) (r) (s ?x - t) (g))\n"
              + "\n".join(actions) + ")\n")
    problem = (f"(define (problem rnd-1) (:domain rnd) (:objects {' '.join(OBJECTS)} - t)\n"
               f"  (:init {' '.join(init)})\n  (:goal (g)))\n")
    return domain, problem


@pytest.mark.parametrize("seed", range(40))
def test_the_grounded_model_agrees_with_an_independent_interpreter(seed):
    interpreted_model_agrees(*random_domain(np.random.default_rng(seed)))


def interpreted_model_agrees(domain_text: str, problem_text: str) -> None:
    """The interpreter and the library reach the same states, and in each agree on what
    applies and where it leads."""
    from gdq_pddl.pddl.reachable import reachable_graph

    learner, planner = grounded(domain_text, problem_text)
    planner_agrees(learner, planner)
    graph = reachable_graph(learner)  # (g) never holds: every state is expanded
    tree = sexp(domain_text)[0]
    schemas = {a[1]: (a[5], a[7]) for a in tree if isinstance(a, list) and a[0] == ":action"}
    init_atoms = sexp(problem_text)[0][4][1:]
    init = frozenset("(" + " ".join(a) + ")" for a in init_atoms)
    statics = learner.statics  # init atoms no effect changes (full states are compared)
    ops = {op.name: op for op in learner.ops}

    def interpret(state: frozenset[str]) -> dict[str, dict[frozenset[str], float]]:
        out = {}
        for name, (pre, eff) in schemas.items():
            for o in OBJECTS:
                b = {"?x": o}
                if holds(pre, b, state):
                    dist: dict[frozenset[str], float] = {}
                    for p, adds, dels in effect(eff, b, state):
                        t = (state - dels) | adds
                        dist[t] = dist.get(t, 0.0) + p
                    out[f"({name} {o})"] = {t: p for t, p in dist.items() if p > 1e-12}
        return out

    seen = {init}
    frontier = [init]
    while frontier:  # the interpreter's own exploration of what reality reaches
        nxt = []
        for state in frontier:
            for dist in interpret(state).values():
                for t in dist:
                    if t not in seen:
                        seen.add(t)
                        nxt.append(t)
        frontier = nxt
    library = {learner.atoms(s) | statics for s in graph.states}
    assert library == seen, domain_text
    for s in graph.states:
        state = learner.atoms(s) | statics
        expected = interpret(state)
        applicable = {op.name for op in learner.applicable(s)}
        assert applicable == set(expected), (domain_text, sorted(state))
        for name, want in expected.items():
            got: dict[frozenset[str], float] = {}
            for o in ops[name].outcomes:
                t = learner.atoms(o.apply(s)) | statics
                got[t] = got.get(t, 0.0) + o.probability
            got = {t: p for t, p in got.items() if p > 1e-12}
            assert got.keys() == want.keys(), (domain_text, name, sorted(state))
            for t, p in want.items():
                assert got[t] == pytest.approx(p), (domain_text, name)
