"""A PPDDL problem grounded once into two tasks over one set of facts: reality and the
planner's view.

Reality is the probabilistic model: every ground action of the domain with all its
outcomes (:class:`ProbabilisticTask`, the learner's actions). The planner's knowledge is
a *determinisation* (:data:`DETERMINISATIONS`), a STRIPS task whose actions are
outcomes of those ground actions:

- ``all-outcomes`` (the default): every outcome that changes something is an action the
  planner may use. Optimistic, as GDQ's knowledge is meant to be: whatever reality can
  do, the plans know of, so no reachable goal is left without a plan.
- ``most-likely``: each action's single most probable outcome (the first one on ties;
  none if that is "no effect" or a failed trial), as FF-Replan plans. Plans that work
  more often, but a goal reached only through an unlikely outcome gets no plan.

Outcomes that change nothing, and failed trials (``(stuck)``), are never planner actions.
A planner action keeps its ground action's name when it is that action's only outcome
in the determinisation, and is named ``<schema>_o<k>`` (k-th outcome) otherwise;
:attr:`ProbabilisticTask.origin` maps every planner action back to its ground action,
which is what the abstraction O does with the plans.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl.grounding import GroundOp, GroundTask, ground
from gdq_pddl.pddl.model import Action, Atom, Domain, Problem

DETERMINISATIONS = ("all-outcomes", "most-likely")
"""What the planner knows of a PPDDL domain (see the module docstring); first: default."""

_SEP = "#"
"""Joins a schema and an outcome index in the grounding of every outcome. The reader
refuses '#' in a name, and :func:`ground_ppddl` refuses a domain built otherwise with
one, so it cannot clash with a name of the domain."""


@dataclass(frozen=True)
class GroundOutcome:
    """One outcome of a ground action: probability, add and delete masks, failed trial."""

    probability: float
    add: int
    dele: int
    stuck: bool = False

    def apply(self, state: int) -> int:
        return (state & ~self.dele) | self.add


@dataclass(frozen=True)
class ProbabilisticOp(GroundOp):
    """A ground action of a PPDDL domain: a precondition and a distribution of outcomes
    (summing to 1). ``known``: the outcomes the planner's determinisation keeps."""

    outcomes: tuple[GroundOutcome, ...] = ()
    known: tuple[int, ...] = ()

    def apply(self, state: int) -> int:
        raise TypeError(f"{self.name} is probabilistic: it has no single effect "
                        "(see its outcomes)")


@dataclass(frozen=True)
class ProbabilisticTask(GroundTask):
    """The learner's task of a PPDDL problem: its ops are the domain's ground actions.

    :meth:`successors` are the planner's knowledge (one edge per applicable action and
    outcome the determinisation keeps, as a :class:`GroundTask` has one per applicable
    operator); :meth:`outcome_states` is everywhere reality can go.
    """

    origin: Mapping[str, str] = field(default_factory=dict)
    """Planner action (ground, e.g. ``"(move_o2 a b)"``) -> ground action ``"(move a b)"``."""
    determinisation: str = DETERMINISATIONS[0]

    def successors(self, state: int) -> list[tuple[GroundOp, int]]:
        out: list[tuple[GroundOp, int]] = []
        for op in self.applicable(state):
            seen: set[int] = set()
            for k in op.known:  # type: ignore[attr-defined]
                t = op.outcomes[k].apply(state)  # type: ignore[attr-defined]
                if t not in seen:
                    seen.add(t)
                    out.append((op, t))
        return out

    def outcome_states(self, state: int) -> list[int]:
        """Every state an applicable action can lead to (failed trials aside)."""
        return [o.apply(state) for op in self.applicable(state)
                for o in op.outcomes if o.probability > 0 and not o.stuck]  # type: ignore


def kept_outcomes(action: Action, determinisation: str) -> tuple[int, ...]:
    """Indices of ``action``'s outcomes that are planner actions (a STRIPS action: 0)."""
    if not action.outcomes:
        return (0,)
    useful = [k for k, o in enumerate(action.outcomes)
              if o.probability > 0 and not o.stuck and o.effect]
    if determinisation == "all-outcomes":
        return tuple(useful)
    if determinisation == "most-likely":
        best = max(range(len(action.outcomes)), key=lambda k: (action.outcomes[k].probability,
                                                               -k))
        return (best,) if best in useful else ()
    raise ValueError(f"unknown determinisation {determinisation!r} (known: "
                     f"{', '.join(DETERMINISATIONS)})")


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
    reqs = frozenset(domain.requirements - {":probabilistic-effects", ":action-costs",
                                            ":rewards"})
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
    every = []  # one deterministic schema per outcome: the grounder's relaxed reachability
    for action in domain.actions:  # then gives every fact some outcome can make true
        if not action.outcomes:
            every.append(action)
        for k, o in enumerate(action.outcomes):
            every.append(replace(action, name=f"{action.name}{_SEP}{k}", effect=o.effect,
                                 outcomes=(), cost=()))
    task = ground(replace(domain, actions=tuple(every)), problem)
    by_name = {a.name: a for a in domain.actions}
    groups: dict[str, dict[int, GroundOp]] = {}  # ground action -> outcome index -> op
    schema_of: dict[str, Action] = {}
    for op in task.ops:
        schema, *args = op.name.strip("()").split()
        base, _, k = schema.partition(_SEP)
        name = "(" + " ".join((base, *args)) + ")"
        groups.setdefault(name, {})[int(k or 0)] = op
        schema_of[name] = by_name[base]
    learner_ops, planner_ops, origin = [], [], {}
    for name, by_outcome in groups.items():
        action = schema_of[name]
        ops = [by_outcome[k] for k in range(len(by_outcome))]  # all share a precondition
        probs = [o.probability for o in action.outcomes] or [1.0]
        stuck = [o.stuck for o in action.outcomes] or [False]
        outcomes = tuple(GroundOutcome(p, op.add, op.dele, s)
                         for p, op, s in zip(probs, ops, stuck, strict=True))
        known = kept_outcomes(action, determinisation)
        learner_ops.append(ProbabilisticOp(name, ops[0].pre, ops[0].neg, 0, 0, outcomes, known))
        args = name.strip("()").split()[1:]
        for k in known:
            pname = "(" + " ".join((names[(action.name, k)], *args)) + ")"
            planner_ops.append(GroundOp(pname, ops[0].pre, ops[0].neg, outcomes[k].add,
                                        outcomes[k].dele))
            origin[pname] = name
    learner = ProbabilisticTask(task.facts, tuple(learner_ops), task.init, task.goal_pos,
                                task.goal_neg, task.goal_possible, task.statics,
                                task.fact_index, origin, determinisation)
    planner = replace(task, ops=tuple(planner_ops))
    return learner, planner


def ground_costs(domain: Domain, problem: Problem, names: list[str]) -> list[float | None]:
    """The cost the domain states for each ground action ``"(schema args...)"`` (None: it
    states none), its terms summed, function terms valued from the problem's ``:init``."""
    by_name = {a.name: a for a in domain.actions}
    out: list[float | None] = []
    for name in names:
        schema, *args = name.strip("()").split()
        action = by_name[schema]
        if not action.cost:
            out.append(None)
            continue
        binding = dict(zip((p for p, _ in action.parameters), args, strict=True))
        total = 0.0
        for term in action.cost:
            if isinstance(term, Atom):
                key = str(Atom(term.predicate, tuple(binding.get(a, a) for a in term.args)))
                if key not in problem.values:
                    raise PDDLError(problem.source, None, f"no value for {key} in :init (the "
                                    f"cost of {name}, {domain.source}:{action.line})")
                value = problem.values[key]
                if value < 0:
                    raise PDDLError(problem.source, None, f"{key} = {value:g} in :init: the "
                                    f"cost of {name} must be >= 0")
                total += value
            else:
                total += term
        out.append(total)
    return out
