"""A PPDDL problem grounded once into two tasks over one set of facts: reality (every
ground action with all its outcomes, :class:`ProbabilisticTask`) and the planner's view,
a STRIPS *determinisation* (:data:`DETERMINISATIONS`, ``docs/domains.md``) whose actions
are outcomes of those ground actions, named ``<schema>_o<k>`` where an action keeps more
than one; :attr:`ProbabilisticTask.origin` maps each back to its ground action. The
ground effects of an action's outcomes, and the relaxed reachability over them, are in
:mod:`gdq_pddl.pddl.ppddl_effects`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from itertools import compress

from gdq_pddl.errors import PDDLError
from gdq_pddl.limits import slow_progress
from gdq_pddl.pddl.grounding import (
    GroundOp,
    GroundTask,
    action_bindings,
    action_cost,
    goal_masks,
    ground,
    index_problem,
    set_bits,
    term_value,
)
from gdq_pddl.pddl.model import Action, Atom, Domain, Junction, Problem
from gdq_pddl.pddl.normalise import MAX_ATOMS, MAX_DISJUNCTS, ground_dnf
from gdq_pddl.pddl.ppddl_effects import (
    Ground,
    GroundOutcome,
    ground_outcomes,
    outcomes_of,
    relaxed_reachability,
)

DETERMINISATIONS = ("all-outcomes", "most-likely")
"""What the planner knows of a PPDDL domain (see the module docstring); first: default."""

_SEP = "#"
"""Joins a schema and an outcome index while grounding (no name of a domain has it)."""


@dataclass(frozen=True)
class ProbabilisticOp(GroundOp):
    """A ground action of a PPDDL domain: a precondition and a distribution of outcomes
    (summing to 1). ``known``: the outcomes the planner's determinisation keeps."""

    outcomes: tuple[GroundOutcome, ...] = ()
    known: tuple[int, ...] = ()
    alternatives: tuple[tuple[int, int], ...] = ()
    """A disjunctive precondition: ``(must hold, must not hold)`` pairs, one of which must
    be met besides ``pre``/``neg`` (what all share); empty: ``pre``/``neg`` alone."""

    def holds(self, state: int) -> bool:
        """Whether the precondition holds in ``state``."""
        return self.applicable(state) and (not self.alternatives or any(
            state & p == p and not state & n for p, n in self.alternatives))

    def apply(self, state: int) -> int:
        raise TypeError(f"{self.name} is probabilistic: it has no single effect "
                        "(see its outcomes)")


@dataclass(frozen=True)
class ProbabilisticTask(GroundTask):
    """The learner's task of a PPDDL problem (its ops: the ground actions). :meth:`successors`
    are the planner's knowledge (the outcomes kept); :meth:`outcome_states`, reality's."""

    origin: Mapping[str, str] = field(default_factory=dict)
    """Planner action (ground, e.g. ``"(move_o2 a b)"``) -> ground action ``"(move a b)"``."""
    determinisation: str = DETERMINISATIONS[0]
    disjunctive: bool = False
    """Some op has a disjunctive precondition (:attr:`ProbabilisticOp.alternatives`)."""

    def applicable(self, state: int) -> list[GroundOp]:
        ops = super().applicable(state)
        return [op for op in ops if op.holds(state)] if self.disjunctive else ops  # type: ignore

    def successors(self, state: int) -> list[tuple[GroundOp, int]]:
        return [(op, t) for op in self.applicable(state)  # each distinct state once per op
                for t in dict.fromkeys(op.outcomes[k].apply(state)  # type: ignore[attr-defined]
                                       for k in op.known)]  # type: ignore[attr-defined]

    def outcome_states(self, state: int) -> list[int]:
        """Every state an applicable action can lead to (failed trials aside)."""
        return [o.apply(state) for op in self.applicable(state)
                for o in op.outcomes if o.probability > 0 and not o.stuck]  # type: ignore


def kept_outcomes(action: Action, determinisation: str) -> tuple[int, ...]:
    """Indices of ``action``'s outcomes that are planner actions (a STRIPS action: 0);
    ``determinisation`` is checked by :func:`planner_names`."""
    if not action.outcomes:
        return (0,)
    useful = [k for k, o in enumerate(action.outcomes)
              if o.probability > 0 and not o.stuck and (o.effect or o.conditional or o.choices)]
    if determinisation == "all-outcomes":
        return tuple(useful)
    best = max(range(len(action.outcomes)), key=lambda k: (action.outcomes[k].probability, -k))
    return (best,) if best in useful else ()


def planner_names(domain: Domain, determinisation: str) -> dict[tuple[str, int], str]:
    """``(schema, outcome index) -> planner schema name`` of every kept outcome."""
    if determinisation not in DETERMINISATIONS:
        raise ValueError(f"unknown determinisation {determinisation!r} (known: "
                         f"{', '.join(DETERMINISATIONS)})")
    taken = {a.name for a in domain.actions}
    out: dict[tuple[str, int], str] = {}
    for action in domain.actions:
        kept = kept_outcomes(action, determinisation)
        for k in kept:
            name = action.name if len(kept) == 1 else f"{action.name}_o{k + 1}"
            if name != action.name and name in taken:
                raise PDDLError(domain.source, action.line, f"action {action.name}: its "
                                f"outcome {k + 1} would be the planner action {name}, which is "
                                "already an action of the domain; rename one of them")
            out[(action.name, k)] = name
    return out


def determinise(domain: Domain, determinisation: str = DETERMINISATIONS[0]) -> Domain:
    """The STRIPS domain of the planner's actions (to write as PDDL for other planners)."""
    names = planner_names(domain, determinisation)
    actions = []
    for action in domain.actions:
        for k in kept_outcomes(action, determinisation):
            effect = action.outcomes[k].effect if action.outcomes else action.effect
            actions.append(replace(action, name=names[(action.name, k)], effect=effect,
                                   outcomes=(), cost=()))
    reqs = domain.requirements - {":probabilistic-effects", ":action-costs", ":rewards"}
    return replace(domain, requirements=reqs, actions=tuple(actions), functions={})


def ground_ppddl(domain: Domain, problem: Problem,
                 determinisation: str = DETERMINISATIONS[0]) -> tuple[ProbabilisticTask,
                                                                      GroundTask]:
    """Ground every outcome of every action once; return reality's task (the learner's
    ground actions) and the planner's (the determinisation), over the same facts."""
    for action in domain.actions:
        if _SEP in action.name:
            raise PDDLError(domain.source, action.line or None, f"action {action.name}: "
                            f"{_SEP!r} cannot be part of an action name")
    names = planner_names(domain, determinisation)
    if any(a.condition is not None or any(o.conditional or o.rewards or o.choices
                                              for o in a.outcomes)
           for a in domain.actions):
        return _ground_normalised(domain, problem, determinisation, names)
    # one deterministic schema per outcome: the grounder's relaxed reachability then gives
    # every fact some outcome can make true
    every = [replace(action, name=f"{action.name}{_SEP}{k}", effect=o.effect, outcomes=(),
                     cost=()) if action.outcomes else action
             for action in domain.actions for k, o in enumerate(outcomes_of(action))]
    task = ground(replace(domain, actions=tuple(every)), problem)
    by_name = {a.name: a for a in domain.actions}
    groups: dict[tuple[str, ...], dict[int, GroundOp]] = {}  # (schema, *args) -> outcome -> op
    for op in slow_progress("grounding", " actions", len(task.ops), task.ops):
        schema, *args = op.name.strip("()").split()
        base, _, k = schema.partition(_SEP)
        groups.setdefault((base, *args), {})[int(k or 0)] = op
    learner_ops, planner_ops, origin = [], [], {}
    for (base, *args), by_outcome in groups.items():
        action, name = by_name[base], "(" + " ".join((base, *args)) + ")"
        ops = [by_outcome[k] for k in range(len(by_outcome))]  # all share a precondition
        outcomes = tuple(GroundOutcome(o.probability, op.add, op.dele, o.stuck)
                         for o, op in zip(outcomes_of(action), ops, strict=True))
        known = kept_outcomes(action, determinisation)
        learner_ops.append(ProbabilisticOp(name, ops[0].pre, ops[0].neg, 0, 0, outcomes, known,
                                           cost=action_cost(action, tuple(args), domain,
                                                            problem)))
        for k in known:
            pname = "(" + " ".join((names[(action.name, k)], *args)) + ")"
            planner_ops.append(GroundOp(pname, ops[0].pre, ops[0].neg, outcomes[k].add,
                                        outcomes[k].dele))
            origin[pname] = name
    same = {f.name: getattr(task, f.name) for f in fields(task)} | {"ops": tuple(learner_ops)}
    learner = ProbabilisticTask(**same, origin=origin, determinisation=determinisation)
    return learner, replace(task, ops=tuple(planner_ops))


def ground_costs(domain: Domain, problem: Problem, names: list[str]) -> list[float | None]:
    """:attr:`GroundOp.cost <gdq_pddl.pddl.grounding.GroundOp.cost>` of each ground action
    ``"(schema args...)"`` (:func:`~gdq_pddl.pddl.grounding.action_cost`, which the
    grounders give every ground action)."""
    by_name = {a.name: a for a in domain.actions}
    return [action_cost(by_name[(atom := Atom.parse(name)).predicate], atom.args, domain,
                        problem) for name in names]


MAX_VARIANTS = 4096
"""Most planner actions one ground action's kept outcome may compile into."""


def _ground_normalised(domain: Domain, problem: Problem, determinisation: str,
                       names: dict[tuple[str, int], str]) -> tuple[ProbabilisticTask,
                                                                   GroundTask]:
    """:func:`ground_ppddl` of a domain with quantified or disjunctive conditions, or
    conditional or quantified effects: reality's ops keep them; the planner's are STRIPS,
    one per alternative and way the conditional effects fire."""
    fluent, static_tuples, by_type, typed = index_problem(domain, problem)
    statics = frozenset(str(a) for a in problem.init if a.predicate not in fluent)

    def objects(t: str) -> list[str]:
        return by_type.get(t, [])

    def static(atom: Atom) -> bool | None:
        return None if atom.predicate in fluent else str(atom) in statics

    raw = []
    with slow_progress("grounding", " actions") as bar:
        for action in domain.actions:
            def too_many(action: Action = action) -> PDDLError:
                return PDDLError(domain.source, action.line or None, f"action {action.name}: a "
                                 f"condition or forall effect grows past {MAX_DISJUNCTS} "
                                 f"alternatives or {MAX_ATOMS} atoms once grounded over the "
                                 "problem's objects")
            whole = Junction("and", action.precondition + ((action.condition,)
                                                           if action.condition else ()))
            for b in action_bindings(action, static_tuples, by_type, typed, fluent):
                bar.update()
                pre = ground_dnf(whole, b, objects, static, too_many)
                if pre:
                    def value(term, binding, action: Action = action) -> float:
                        return term_value(term, binding, domain, problem, action,
                                          f"a reward of {action.name}")
                    args = tuple(b[p] for p, _ in action.parameters)
                    outs = ground_outcomes(action, args, b, objects, static, fluent,
                                            too_many, value, domain.source)
                    raw.append((action, args, pre, outs))
    init = {str(a) for a in problem.init if a.predicate in fluent}
    reached, live = relaxed_reachability(raw, init)
    facts = tuple(sorted(reached))
    index = {f: i for i, f in enumerate(facts)}

    def m(atoms) -> int:
        return sum(1 << index[a] for a in atoms if a in index)

    raw = list(compress(raw, live))
    learner_names = {str(Atom(action.name, args)) for action, args, _, _ in raw}
    learner_ops, planner_ops, origin, taken = [], [], {}, set()
    incomplete = ""
    for action, args, pre, outs in slow_progress("grounding", " actions", len(raw), raw):
        name = str(Atom(action.name, args))
        alts = [(m(p), m(n)) for p, n in pre if p <= reached]
        common_pos = common_neg = -1
        for p, n in alts:
            common_pos, common_neg = common_pos & p, common_neg & n
        outcomes = tuple(GroundOutcome(
            p, m(add), m(dele - add), stuck,
            tuple((m(cp), m(cn), m(a), m(d)) for cp, cn, a, d in conds if cp <= reached),
            reward, tuple(r for r in ((tuple((m(cp), m(cn)) for cp, cn in alts if cp <= reached),
                                       amount) for alts, amount in rewards) if r[0]))
            for _, p, (add, dele, conds, reward, rewards, stuck) in outs)
        known, kept_names = _kept(action, outs, outcomes, determinisation, names)
        learner_ops.append(ProbabilisticOp(name, common_pos, common_neg, 0, 0, outcomes, known,
                                           tuple(alts) if len(alts) > 1 else (),
                                           cost=action_cost(action, args, domain, problem)))
        try:  # the STRIPS variants of each kept outcome, for the per-query planners
            variants = [(base, _variants(alts, outcomes[k], name, domain, action))
                        for k, base in zip(known, kept_names, strict=True)]
        except PDDLError as exc:  # the state graph reads conditional effects itself
            incomplete = incomplete or str(exc)
            variants = []
        for base, strips in variants:
            for j, (p, n, a, d) in enumerate(strips):
                schema = base + (f"_v{j + 1}" if j else "")
                pname = str(Atom(schema, args))
                if pname in taken or (pname != name and pname in learner_names):
                    raise PDDLError(domain.source, action.line or None, f"action "
                                    f"{action.name}: its planner action {pname} has the name "
                                    "of another ground action; rename one of them")
                taken.add(pname)
                planner_ops.append(GroundOp(pname, p, n, a, d & ~a))
                origin[pname] = name
    goal = goal_masks(problem, fluent, statics, index)
    learner = ProbabilisticTask(facts, tuple(learner_ops), m(init), statics=statics,
                                fact_index=index, origin=origin,
                                determinisation=determinisation,
                                disjunctive=any(op.alternatives for op in learner_ops), **goal)
    planner = GroundTask(facts, tuple(planner_ops), m(init), statics=statics, fact_index=index,
                         incomplete=incomplete, **goal)
    return learner, planner




def _kept(action: Action, outs: list[tuple[int, float, Ground]],
          outcomes: tuple[GroundOutcome, ...], determinisation: str,
          names: dict[tuple[str, int], str]) -> tuple[tuple[int, ...], list[str]]:
    """The ground outcomes the planner keeps and their planner schema names: those of
    :func:`kept_outcomes` where each schema outcome is one ground outcome; where a choice
    expands one into several, each that does something (``_c<j>`` after the schema
    outcome's name), or the most likely (named as the action)."""
    if len(outs) == len(outcomes_of(action)):
        known = kept_outcomes(action, determinisation)
        return known, [names[(action.name, k)] for k in known]

    def useful(i: int) -> bool:
        o = outcomes[i]
        return o.probability > 0 and not o.stuck and bool(o.add or o.dele or o.conditional)

    if determinisation != "all-outcomes":
        best = max(range(len(outs)), key=lambda i: (outs[i][1], -i))
        return ((best,), [action.name]) if useful(best) else ((), [])
    schema = kept_outcomes(action, determinisation)
    count = {k: sum(1 for kk, _, _ in outs if kk == k) for k in schema}
    known: list[int] = []
    kept: list[str] = []
    seen: dict[int, int] = {}
    for i, (k, _, _) in enumerate(outs):
        seen[k] = seen.get(k, 0) + 1
        if k in count and useful(i):
            known.append(i)
            kept.append(names[(action.name, k)] + (f"_c{seen[k]}" if count[k] > 1 else ""))
    return tuple(known), kept




def _variants(alts: list[tuple[int, int]], outcome: GroundOutcome, name: str, domain: Domain,
              action: Action) -> list[tuple[int, int, int, int]]:
    """The STRIPS ops ``(pre, neg, add, delete)`` of one outcome of a ground action: one
    per alternative of its precondition and way each conditional effect fires or not
    (one of its literals fails), so that those that apply have the outcome's effect."""
    variants = {(p, n, outcome.add, outcome.dele): None for p, n in alts}
    for cp, cn, a, d in outcome.conditional:
        nxt: dict[tuple[int, int, int, int], None] = {}
        for p, n, add, dele in variants:
            if not (p | cp) & (n | cn):
                nxt[(p | cp, n | cn, add | a, dele | d)] = None
            for bit in set_bits(cp & ~p):
                nxt[(p, n | (1 << bit), add, dele)] = None
            for bit in set_bits(cn & ~n):
                if not (p | (1 << bit)) & n:
                    nxt[(p | (1 << bit), n, add, dele)] = None
        variants = nxt
        if len(variants) > MAX_VARIANTS:
            raise PDDLError(domain.source, action.line or None, f"action {action.name}: "
                            f"{name}'s conditional effects need more than {MAX_VARIANTS} "
                            "STRIPS actions in the planner's determinisation")
    return list(variants)
