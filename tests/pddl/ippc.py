"""What the IPPC language tests share (``test_ippc_language``, ``test_ippc_constructs``,
``test_forall_probabilistic``, ``test_ippc_rewards``): a small domain grounded and its
ground actions' distributions read back, the check that the planner's STRIPS ops
agree with the learner's ground actions in every state, and an independent
interpreter of PDDL text with the random domains it is checked on."""

from __future__ import annotations

from fractions import Fraction
from itertools import product

import numpy as np
import pytest

from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.pddl.factored import combine, sample_parts
from gdq_pddl.pddl.ppddl import ground_ppddl


def grounded(domain_text: str, problem_text: str, determinisation: str = "all-outcomes"):
    domain = parse_domain(domain_text, "d.pddl")
    return ground_ppddl(domain, parse_problem(problem_text, domain, "p.pddl"), determinisation)


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


def reached(interpret, init: frozenset[str]) -> list[frozenset[str]]:
    """Every state the interpreter (:func:`interpreter`) reaches from ``init``, in
    breadth-first order: the interpreter's own exploration of what reality reaches."""
    seen, frontier, order = {init}, [init], [init]
    while frontier:
        nxt = []
        for state in frontier:
            for dist in interpret(state).values():
                for t in dist:
                    if t not in seen:
                        seen.add(t)
                        nxt.append(t)
        order += nxt
        frontier = nxt
    return order


def interpreter(schemas: dict):
    """The independent interpreter's next-state distributions in a state: ``(ground
    action name -> {next state: probability})`` for every schema and object whose
    precondition holds (``schemas``: name -> (precondition, effect) s-expressions)."""
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

    return interpret


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

    interpret = interpreter(schemas)
    seen = set(reached(interpret, init))  # the interpreter's own exploration
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


# --- the interpreter's rewards and costs: what each outcome pays, on either scale ---------

def cost_effect(rng, depth: int, variables: list[str]) -> str:
    """A random effect of rewards and costs (``(increase (reward) k)``, ``(decrease
    (reward) k)``, ``(increase (total-cost) k)``) beside literals, nested in ``and``,
    ``when``, ``forall`` and ``probabilistic``, a forall's body any of them (a forall of a
    ``probabilistic``: one draw per binding)."""
    k = int(rng.integers(1, 9))
    kind = int(rng.integers(0, 7)) if depth > 0 else int(rng.integers(0, 3))
    if kind <= 2:
        return ("(increase (reward) {k})", "(decrease (reward) {k})",
                "(increase (total-cost) {k})")[kind].format(k=k)
    if kind == 3:
        return f"(when {random_condition(rng, 2, variables)} " \
               f"{cost_effect(rng, depth - 1, variables)})"
    if kind == 4:
        v = f"?c{depth}"
        return f"(forall ({v} - t) {cost_effect(rng, depth - 1, [*variables, v])})"
    if kind == 5:
        return f"(probabilistic 1/3 {cost_effect(rng, depth - 1, variables)} " \
               f"1/2 (and {random_effect(rng, 1, variables)} " \
               f"{cost_effect(rng, depth - 1, variables)}))"
    return f"(and {cost_effect(rng, depth - 1, variables)} " \
           f"{cost_effect(rng, depth - 1, variables)})"


def costed_domain(rng) -> tuple[str, str]:
    """:func:`random_domain` with costs and rewards (:func:`cost_effect`) beside each
    action's effect, some at its top (the action's cost), some inside constructs, and an
    action ``finish`` that reaches the goal (a goal no action reaches is refused)."""
    domain_text, problem_text = random_domain(rng)
    lines = domain_text.split("\n")
    for i, line in enumerate(lines):
        if line.strip().startswith(":effect"):
            closers = ")" * (line.count(")") - line.count("("))
            top = "(increase (total-cost) 2)" if rng.random() < 0.5 else ""
            lines[i] = f"    :effect (and {random_effect(rng, 2, ['?x'])} {top} " \
                f"{cost_effect(rng, 3, ['?x'])}){closers}"
    finish = "  (:action finish :parameters (?x - t) :precondition (and) :effect (g)))\n"
    return "\n".join(lines).rstrip()[:-1] + "\n" + finish, problem_text


def _amount(e) -> float | None:
    """The signed amount of a reward or cost effect (None: another effect)."""
    if e and e[0] in ("increase", "decrease") and e[1] in (["reward"], ["total-cost"]):
        return float(e[2]) * (1.0 if e[0] == "increase" and e[1] == ["reward"] else -1.0)
    return None


def action_cost(e) -> tuple[float, bool]:
    """The cost effect ``e`` states whatever happens (its negative amounts reached through
    ``and`` alone) and whether it states one anywhere (a negative amount, at any depth)."""
    def anywhere(x) -> bool:
        amount = _amount(x)
        return (amount is not None and amount < 0) or \
            any(isinstance(y, list) and anywhere(y) for y in x)

    def top(x) -> float:
        amount = _amount(x)
        if amount is not None:
            return -amount if amount < 0 else 0.0
        return sum(top(y) for y in x[1:]) if x and x[0] == "and" else 0.0

    return top(e), anywhere(e)


def paying_outcomes(e, b: dict[str, str], state: frozenset[str],
                    at_top: bool = True) -> list[tuple[float, frozenset, frozenset, float]]:
    """``[(probability, adds, deletes, reward)]`` of effect ``e`` in ``state``: the reward
    its rewards and costs pay, those of :func:`action_cost` (the action's) left out."""
    head = e[0] if e else "and"
    amount = _amount(e)
    if amount is not None:
        paid = 0.0 if at_top and amount < 0 else amount
        return [(1.0, frozenset(), frozenset(), paid)]

    def both(out, more):
        return [(p * q, a | a2, d | d2, r + r2) for p, a, d, r in out for q, a2, d2, r2 in more]

    nothing = [(1.0, frozenset(), frozenset(), 0.0)]
    if head == "and":
        out = nothing
        for x in e[1:]:
            out = both(out, paying_outcomes(x, b, state, at_top))
        return out
    if head == "forall":
        out = nothing
        for o in OBJECTS:
            out = both(out, paying_outcomes(e[2], {**b, e[1][0]: o}, state, False))
        return out
    if head == "when":
        return paying_outcomes(e[2], b, state, False) if holds(e[1], b, state) else nothing
    if head == "probabilistic":
        out, total = [], 0.0
        for p_text, sub in zip(e[1::2], e[2::2], strict=True):
            p = float(Fraction(p_text))
            total += p
            out += [(p * q, a, d, r) for q, a, d, r in paying_outcomes(sub, b, state, False)]
        return out + [(1.0 - total, frozenset(), frozenset(), 0.0)]
    return [(p, a, d, 0.0) for p, a, d in effect(e, b, state)]


def interpreted_rewards_agree(domain_text: str, problem_text: str, own: bool,
                              online: bool) -> None:
    """In every reachable state, each ground action's outcomes as the true model has them
    (next state and what the step pays besides the action's cost, probabilities merged)
    and the action's cost are the interpreter's, on the problem's own scale (``own``) or
    the goal scale (an action stating no cost costs 1 there); ``online``: as a problem
    explored online finds them (every state expanded), else enumerated."""
    from gdq_pddl.envs.online import OnlineInstance
    from gdq_pddl.envs.pddl_env import PDDLInstance

    metric = "(:metric maximize (reward))" if own else "(:metric minimize (total-cost))"
    inst = PDDLInstance.from_texts(domain_text, problem_text.rstrip()[:-1] + f" {metric})")
    assert inst.reward_scale == ("problem" if own else "goal")
    schemas = {a[1]: a[7] for a in sexp(domain_text)[0]
               if isinstance(a, list) and a[0] == ":action"}
    task = inst.problem.learner_task
    statics = frozenset(task.statics)
    for a, cost in enumerate(inst.costs):
        schema = task.ops[a].name.strip("()").split()[0]
        top, stated = action_cost(schemas[schema])
        assert (cost.kind, cost.a) == ("const", top if stated or own else 1.0), \
            (domain_text, task.ops[a].name)

    def expected(state: frozenset[str], name: str) -> dict[tuple, float]:
        schema, arg = name.strip("()").split()
        out: dict[tuple, float] = {}
        for p, adds, dels, r in paying_outcomes(schemas[schema], {"?x": arg}, state):
            key = ((state - dels) | adds, round(r, 9))
            out[key] = out.get(key, 0.0) + p
        return {k: p for k, p in out.items() if p > 1e-12}

    def compare(state, name, rows) -> None:
        got: dict[tuple, float] = {}
        for p, t, r in rows:
            key = (t, round(r, 9))
            got[key] = got.get(key, 0.0) + p
        want = expected(state, name)
        assert got.keys() == want.keys(), (domain_text, name, sorted(state), own, online)
        for k, p in want.items():
            assert got[k] == pytest.approx(p), (domain_text, name, own, online)

    if online:
        graph = OnlineInstance(inst).graph
        x = 0
        while x < graph.n_states:  # (g) never holds: every state is expanded
            graph.expand([x])
            state = graph.atoms(x) | statics
            offered = graph.offered(x)
            column, prob, nxt, _, gain = graph.outcomes(x)
            for j, k in enumerate(offered.tolist()):
                rows = [(p, graph.atoms(int(t)) | statics, g) for c, p, t, g in
                        zip(column, prob, nxt, gain, strict=True) if c == j]
                compare(state, task.ops[k].name, rows)
            x += 1
        return
    m = inst.model
    gains = m.gain if m.gain.size else np.zeros(len(m.prob))
    for s in np.flatnonzero(~inst.learner_goal).tolist():  # goal states: not expanded
        state = inst.atoms(s) | statics
        for j, k in enumerate(m.acts[s].tolist()):
            if k < 0:
                continue
            i = s * m.acts.shape[1] + j
            rows = [(m.prob[o], inst.atoms(int(m.next[o])) | statics, gains[o])
                    for o in range(m.ptr[i], m.ptr[i + 1])]
            compare(state, task.ops[k].name, rows)


# --- the interpreter against factored ground actions ----------------------------------------

def product_distribution(op, state: int) -> dict[int, float]:
    """Where factored ``op`` leads from ``state``, its parts' product listed (small cases
    only): next state -> probability."""
    out: dict[int, float] = {}
    for pick in product(*op.parts):
        o = combine(pick)
        t = state if o.stuck else o.apply(state)
        out[t] = out.get(t, 0.0) + o.probability
    return out


def interpreted_factored_agrees(domain_text: str, problem_text: str, rng,
                                draws: int = 0) -> int:
    """Every state the interpreter reaches: the library applies the same ground actions,
    and each leads to the interpreter's distribution: a listed one by its outcomes, a
    factored one by its parts' product, and, in the first three states with ``draws``,
    by that many draws of its parts (:func:`~gdq_pddl.pddl.factored.sample_parts` from
    ``rng``), each next state's frequency within 5 standard deviations (plus one draw)
    of its probability. Returns how many (state, factored action) were compared."""

    learner, planner = grounded(domain_text, problem_text)
    planner_agrees(learner, planner)
    tree = sexp(domain_text)[0]
    schemas = {a[1]: (a[5], a[7]) for a in tree if isinstance(a, list) and a[0] == ":action"}
    init = frozenset("(" + " ".join(a) + ")" for a in sexp(problem_text)[0][4][1:])
    statics = learner.statics
    ops = {op.name: op for op in learner.ops}

    interpret = interpreter(schemas)
    compared = 0
    for i, state in enumerate(reached(interpret, init)):
        s = learner.mask(state - statics)
        expected = interpret(state)
        assert {op.name for op in learner.applicable(s)} == set(expected), domain_text
        for name, want in expected.items():
            op = ops[name]
            if op.factored:
                got = product_distribution(op, s)
                compared += 1
            else:
                got = {}
                for o in op.outcomes:
                    t = o.apply(s)
                    got[t] = got.get(t, 0.0) + o.probability
            got = {learner.atoms(t) | statics: p for t, p in got.items() if p > 1e-12}
            assert got.keys() == want.keys(), (domain_text, name, sorted(state))
            for t, p in want.items():
                assert got[t] == pytest.approx(p), (domain_text, name)
            if op.factored and draws and i < 3:
                counts: dict[frozenset[str], int] = {}
                for _ in range(draws):
                    o = combine(sample_parts(op.parts, rng))
                    t = learner.atoms(s if o.stuck else o.apply(s)) | statics
                    counts[t] = counts.get(t, 0) + 1
                assert counts.keys() <= want.keys(), (domain_text, name)
                for t, p in want.items():
                    sd = (max(0.0, p * (1 - p)) / draws) ** 0.5
                    assert abs(counts.get(t, 0) / draws - p) <= 5 * sd + 1 / draws, \
                        (domain_text, name, p, counts.get(t, 0))
    return compared
