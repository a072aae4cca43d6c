"""Ground a typed STRIPS problem into bitmask operators (states: ``int`` bitmasks over
the fluent facts). Parameters are bound by joining the static preconditions against the
initial state, most constrained first; operators unreachable with deletes ignored are
dropped."""

from __future__ import annotations

import itertools
from collections import Counter, defaultdict
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property

from gdq_pddl.errors import PDDLError
from gdq_pddl.limits import slow_progress
from gdq_pddl.pddl.formulas import is_subtype
from gdq_pddl.pddl.model import Action, Atom, CostTerm, Domain, Literal, Problem


@dataclass(frozen=True)
class GroundOp:
    """A ground action: its name and precondition/effect bitmasks."""

    name: str
    pre: int
    neg: int
    add: int
    dele: int
    cost: float | None = field(default=None, kw_only=True)
    """What the action costs whatever happens (the costs it writes outside every
    ``when``, ``forall`` and ``probabilistic``, function terms valued: :func:`action_cost`);
    costs and rewards inside them are its outcomes'
    (:class:`~gdq_pddl.pddl.ppddl_effects.GroundOutcome`). None: it states no cost
    anywhere (the goal scale's default applies)."""

    def applicable(self, state: int) -> bool:
        return state & self.pre == self.pre and not state & self.neg

    def apply(self, state: int) -> int:
        return (state & ~self.dele) | self.add


@dataclass(frozen=True)
class GroundTask:
    """A grounded problem. States are int bitmasks over :attr:`facts`."""

    facts: tuple[str, ...]
    ops: tuple[GroundOp, ...]
    init: int
    goal_pos: int
    goal_neg: int
    goal_possible: bool
    statics: frozenset[str]
    fact_index: dict[str, int] = field(repr=False, default_factory=dict)
    goal_alternatives: tuple[tuple[int, int], ...] = ()
    """A goal with alternatives: ``(must hold, must not hold)`` masks, one of which must
    be met besides ``goal_pos``/``goal_neg`` (the part they share). Empty: none."""
    incomplete: str = ""
    """Why some ground actions have no planner action here (a PPDDL action whose
    conditional effects need too many STRIPS variants); planners asked a query on such a
    task refuse with it. Empty: every ground action is here."""

    @cached_property
    def ops_by_fact(self) -> dict[int, tuple[GroundOp, ...]]:
        """Operators keyed by one positive precondition bit (or -1 for none)."""
        out: dict[int, list[GroundOp]] = defaultdict(list)
        counts = Counter(bit for op in self.ops for bit in set_bits(op.pre))
        for op in self.ops:
            out[min(set_bits(op.pre), key=counts.__getitem__, default=-1)].append(op)
        return {k: tuple(v) for k, v in out.items()}

    def applicable(self, state: int) -> list[GroundOp]:
        """Every operator whose precondition holds in ``state``."""
        table = self.ops_by_fact
        return [op for key in (-1, *set_bits(state)) for op in table.get(key, ())
                if state & op.pre == op.pre and not state & op.neg]

    def successors(self, state: int) -> list[tuple[GroundOp, int]]:
        """``(op, next state)`` for every operator applicable in ``state``."""
        return [(op, (state & ~op.dele) | op.add) for op in self.applicable(state)]

    def outcome_states(self, state: int) -> list[int]:
        """States reality can reach from ``state`` besides :meth:`successors`' (none here)."""
        return []

    def is_goal(self, state: int, goal: tuple[int, int] | None = None) -> bool:
        """Whether ``goal`` (default: the problem's) holds in ``state``; never, for a
        problem goal that can never hold (:attr:`goal_possible`)."""
        if goal is not None:
            return state & goal[0] == goal[0] and not state & goal[1]
        return self.goal_possible and state & self.goal_pos == self.goal_pos \
            and not state & self.goal_neg and (not self.goal_alternatives or any(
                state & p == p and not state & n for p, n in self.goal_alternatives))

    def atoms(self, state: int) -> frozenset[str]:
        """The fluent atoms true in ``state``."""
        return frozenset(self.facts[b] for b in set_bits(state))

    def mask(self, atoms: frozenset[str] | set[str]) -> int:
        """Bitmask of fluent atoms; raises KeyError naming an unknown atom."""
        return sum(1 << self.fact_index[a] for a in set(atoms))


def set_bits(mask: int):
    """The indices of the bits set in ``mask``, lowest first."""
    while mask:
        low = mask & -mask
        yield low.bit_length() - 1
        mask ^= low


def term_value(term: CostTerm, binding: Mapping[str, str], domain: Domain, problem: Problem,
               action: Action, what: str) -> float:
    """A cost or reward term under ``binding``: a number, or a function term valued in
    the problem's ``:init`` (refused, naming it, where it has no value or a negative one)."""
    if not isinstance(term, Atom):
        return term
    key = str(Atom(term.predicate, tuple(binding.get(a, a) for a in term.args)))
    if key not in problem.values:
        raise PDDLError(problem.source, None, f"no value for {key} in :init ({what}, "
                        f"{domain.source}:{action.line})")
    value = problem.values[key]
    if value < 0:
        raise PDDLError(problem.source, None, f"{key} = {value:g} in :init: {what} must be "
                        ">= 0")
    return value


def action_cost(action: Action, args: tuple[str, ...], domain: Domain,
                problem: Problem) -> float | None:
    """:attr:`GroundOp.cost` of ``action`` with parameters ``args``: its terms outside every
    construct summed, 0 where it states costs only inside them, None where none at all."""
    if not action.states_cost():
        return None
    binding = dict(zip((p for p, _ in action.parameters), args, strict=True))
    name = str(Atom(action.name, args))
    return float(sum(term_value(term, binding, domain, problem, action, f"the cost of {name}")
                     for term in action.cost))


def ground(domain: Domain, problem: Problem) -> GroundTask:
    """Ground ``problem``; see the module docstring for how."""
    if any(a.outcomes for a in domain.actions):
        raise ValueError("a PPDDL domain has no single effect per action: ground it with "
                         "gdq_pddl.pddl.ppddl.ground_ppddl")
    fluent, static_tuples, by_type, typed = index_problem(domain, problem)
    bindings = ((action, b) for action in domain.actions
                for b in action_bindings(action, static_tuples, by_type, typed, fluent))
    with slow_progress("grounding", " actions", iterable=bindings) as bar:
        pending = [_instantiate(action, b, fluent) for action, b in bar]
    init_fluents = {str(a) for a in problem.init if a.predicate in fluent}
    reached, live = relaxed_reachable(pending, init_fluents)
    facts = tuple(sorted(reached))
    index = {f: i for i, f in enumerate(facts)}

    def m(atoms: set[str]) -> int:
        return sum(1 << index[a] for a in atoms if a in index)

    with slow_progress("grounding", " actions", len(live), live) as bar:
        ops = tuple(GroundOp(name, m(pre), m(neg), m(add), m(dele - add),
                             cost=action_cost(action, args, domain, problem))
                    for name, pre, neg, add, dele, action, args in bar)
    static_strs = {str(a) for a in problem.init if a.predicate not in fluent}
    return GroundTask(facts, ops, m(init_fluents), statics=frozenset(static_strs),
                      fact_index=index, **goal_masks(problem, fluent, static_strs, index))


def relaxed_reachable(pending: list[tuple], init: set[str]) -> tuple[set[str], list[tuple]]:
    """The facts reachable from ``init`` with deletes ignored, and the ground actions
    ``(name, pre, neg, add, dele, ...)`` of ``pending`` whose positive preconditions they hold
    (in the order they were found); a bar counts those actions past 2 s."""
    reached = set(init)
    live: list[tuple] = []
    with slow_progress("relaxed reachability", " actions", len(pending)) as bar:
        changed = True
        while changed:
            changed, rest = False, []
            for op in pending:
                if op[1] <= reached:
                    live.append(op)
                    reached |= op[3]
                    changed = True
                    bar.update()
                else:
                    rest.append(op)
            pending = rest
    return reached, live


def index_problem(domain: Domain, problem: Problem) -> tuple[
        frozenset[str], dict[str, set[tuple[str, ...]]], dict[str, list[str]],
        dict[str, frozenset[str]]]:
    """The fluent predicates, the static atoms' arguments by predicate, and the objects
    of each type (sorted, and as a set): what :func:`action_bindings` reads."""
    fluent = domain.fluent_predicates()
    static_tuples: dict[str, set[tuple[str, ...]]] = defaultdict(set)
    for a in problem.init:
        if a.predicate not in fluent:
            static_tuples[a.predicate].add(a.args)
    by_type = {t: sorted(o for o, ot in problem.objects.items() if is_subtype(domain.types, ot, t))
               for t in domain.types}
    return fluent, static_tuples, by_type, {t: frozenset(o) for t, o in by_type.items()}


def action_bindings(action: Action, static_tuples: dict[str, set[tuple[str, ...]]],
                    by_type: dict[str, list[str]], typed: dict[str, frozenset[str]],
                    fluent: frozenset[str]):
    """Yield every parameter binding that satisfies the static preconditions."""
    params = dict(action.parameters)
    fixed = [lit for lit in action.precondition if lit.atom.predicate not in fluent]
    equalities = [lit for lit in fixed if lit.atom.predicate == "="]
    statics = [lit.atom for lit in fixed if lit.positive and lit.atom.predicate != "="]
    neg_statics = [lit.atom for lit in fixed if not lit.positive and lit.atom.predicate != "="]
    bindings: list[dict[str, str]] = [{}]
    todo = list(statics)
    while todo and bindings:
        bound = bindings[0].keys()
        atom = max(todo, key=lambda a: (sum(1 for x in a.args if x in bound or x[0] != "?"),
                                        -len(static_tuples.get(a.predicate, ()))))
        todo.remove(atom)
        known = tuple(i for i, x in enumerate(atom.args) if x in bound or x[0] != "?")
        index: dict[tuple[str, ...], list[tuple[str, ...]]] = defaultdict(list)
        # sorted: set order follows Python's per-process string hashing, and the order of
        # ground actions (a PDDL env's action indices) must not
        for tup in sorted(static_tuples.get(atom.predicate, ())):
            index[tuple(tup[i] for i in known)].append(tup)
        nxt = []
        for b in bindings:
            for tup in index.get(tuple(b.get(atom.args[i], atom.args[i]) for i in known), ()):
                nb = dict(b)
                if all(x[0] != "?" or nb.setdefault(x, v) == v
                       for x, v in zip(atom.args, tup, strict=True)):
                    nxt.append(nb)
        bindings = nxt
    for b in bindings:
        free = [p for p in params if p not in b]
        for values in itertools.product(*(by_type.get(params[p], ()) for p in free)):
            full = dict(b, **dict(zip(free, values, strict=True)))
            if (all(full[p] in typed.get(t, ()) for p, t in params.items())
                    and not any(tuple(full.get(x, x) for x in a.args)
                                in static_tuples.get(a.predicate, ()) for a in neg_statics)
                    and all((full.get(e.atom.args[0], e.atom.args[0])
                             == full.get(e.atom.args[1], e.atom.args[1])) == e.positive
                            for e in equalities)):
                yield full


def _instantiate(action: Action, b: dict[str, str], fluent: frozenset[str]):
    def s(atom: Atom) -> str:
        return str(Atom(atom.predicate, tuple(b.get(x, x) for x in atom.args)))

    def part(lits: tuple[Literal, ...], positive: bool) -> set[str]:
        return {s(lit.atom) for lit in lits
                if lit.positive == positive and lit.atom.predicate in fluent}

    args = tuple(b[p] for p, _ in action.parameters)
    name = "(" + " ".join((action.name, *args)) + ")"
    return (name, part(action.precondition, True), part(action.precondition, False),
            part(action.effect, True), part(action.effect, False), action, args)


def goal_masks(problem: Problem, fluent, statics, index: dict[str, int]) -> dict:
    """The goal fields of a :class:`GroundTask`, equalities and static atoms (``statics``)
    decided; alternatives that can never hold are dropped."""
    def masks(lits) -> tuple[int, int, bool]:
        pos = neg = 0
        possible = True
        for lit in lits:
            s = str(lit.atom)
            if lit.atom.predicate == "=":
                possible &= (lit.atom.args[0] == lit.atom.args[1]) == lit.positive
            elif lit.atom.predicate not in fluent:
                possible &= (s in statics) == lit.positive
            elif s not in index:
                possible &= not lit.positive
            elif lit.positive:
                pos |= 1 << index[s]
            else:
                neg |= 1 << index[s]
        return pos, neg, possible

    pos, neg, possible = masks(problem.goal)
    alternatives = [m[:2] for m in map(masks, problem.goal_alternatives) if m[2]]
    return {"goal_pos": pos, "goal_neg": neg, "goal_alternatives": tuple(alternatives),
            "goal_possible": possible and (bool(alternatives)
                                           or not problem.goal_alternatives)}
