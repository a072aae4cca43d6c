"""What the IPPC language tests share (``test_ippc_language``, ``test_ippc_constructs``,
``test_forall_probabilistic``, ``test_ippc_rewards``): a small domain grounded and its
ground actions' distributions read back, the check that the planner's STRIPS ops
agree with the learner's ground actions in every state, and an independent
interpreter of PDDL text with the random domains it is checked on."""

from __future__ import annotations

from fractions import Fraction

import pytest

from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.pddl.ppddl import ground_ppddl


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


# --- an independent interpreter, and the random domains it is checked on ------------------
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
