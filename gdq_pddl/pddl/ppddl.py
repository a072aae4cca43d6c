"""A PPDDL problem grounded once (:func:`~gdq_pddl.pddl.grounding.ground`) into two tasks
over one set of facts: reality (every ground action with all its outcomes,
:class:`ProbabilisticTask`) and the planner's view, a STRIPS *determinisation*
(:data:`DETERMINISATIONS`, ``docs/domains.md``) whose actions are the outcomes of those
ground actions that it keeps, named ``<schema>_o<k>`` where an action keeps more than
one, and compiled into STRIPS variants where they have conditional effects;
:attr:`ProbabilisticTask.origin` maps each back to its ground action. Which outcomes are
kept and their names are in :mod:`gdq_pddl.pddl.ppddl_effects`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl.grounding import (
    GroundOp,
    GroundOutcome,
    GroundTask,
    ground_kept,
    set_bits,
)
from gdq_pddl.pddl.model import Action, Atom, Domain, Problem
from gdq_pddl.pddl.ppddl_effects import DETERMINISATIONS, kept_outcomes, planner_names

__all__ = ["DETERMINISATIONS", "MAX_VARIANTS", "ProbabilisticTask", "determinise",
           "ground_ppddl"]


@dataclass(frozen=True)
class ProbabilisticTask(GroundTask):
    """The learner's task of a PPDDL problem (its ops: the ground actions, with all their
    outcomes): :meth:`~GroundTask.successors` are the planner's knowledge (the outcomes
    kept), :meth:`~GroundTask.outcome_states` reality's."""

    origin: Mapping[str, str] = field(default_factory=dict)
    """Planner action (ground, e.g. ``"(move_o2 a b)"``) -> ground action ``"(move a b)"``."""
    determinisation: str = DETERMINISATIONS[0]


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
    ground actions) and the planner's (the determinisation: the STRIPS variants of each
    kept outcome, for the per-query planners), over the same facts."""
    task, kept = ground_kept(domain, problem, determinisation)
    by_name = {a.name: a for a in domain.actions}
    learner_names = {op.name for op in task.ops}
    planner_ops, origin, taken = [], {}, set()
    incomplete = ""
    for op, kept_names in zip(task.ops, kept, strict=True):
        atom = Atom.parse(op.name)
        action = by_name[atom.predicate]
        alts = op.alternatives or ((op.pre, op.neg),)
        try:
            variants = [(base, _variants(alts, op.outcomes[k], op.name, domain, action))
                        for k, base in zip(op.known, kept_names, strict=True)]
        except PDDLError as exc:  # the state graph reads conditional effects itself
            incomplete = incomplete or str(exc)
            variants = []
        for base, strips in variants:
            for j, (p, n, a, d) in enumerate(strips):
                pname = str(Atom(base + (f"_v{j + 1}" if j else ""), atom.args))
                if pname in taken or (pname != op.name and pname in learner_names):
                    raise PDDLError(domain.source, action.line or None, f"action "
                                    f"{action.name}: its planner action {pname} has the name "
                                    "of another ground action; rename one of them")
                taken.add(pname)
                planner_ops.append(GroundOp.strips(pname, p, n, a, d & ~a))
                origin[pname] = op.name
    same = {f.name: getattr(task, f.name) for f in fields(task)}
    learner = ProbabilisticTask(**same, origin=origin, determinisation=determinisation)
    return learner, replace(task, ops=tuple(planner_ops), incomplete=incomplete,
                            disjunctive=False)


MAX_VARIANTS = 4096
"""Most planner actions one ground action's kept outcome may compile into."""


def _variants(alts: tuple[tuple[int, int], ...], outcome: GroundOutcome, name: str,
              domain: Domain, action: Action) -> list[tuple[int, int, int, int]]:
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
