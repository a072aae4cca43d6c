"""What every planner returns, and the problem every planner is given."""

from __future__ import annotations

import enum
import math
import time
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import NamedTuple, Protocol, runtime_checkable

from gdq_pddl.errors import PlanningError, SizeError
from gdq_pddl.inputs import text_hash
from gdq_pddl.limits import MAX_INIT_ATOMS, MAX_TOLERANCE
from gdq_pddl.pddl.grounding import GroundOp, GroundTask, ground
from gdq_pddl.pddl.model import Domain, Problem
from gdq_pddl.pddl.parser import parse_domain
from gdq_pddl.pddl.ppddl import determinise, ground_ppddl
from gdq_pddl.pddl.problem_reader import parse_problem, problem_file
from gdq_pddl.pddl.sexpr import read_pddl_text
from gdq_pddl.pddl.writer import untold, write_domain, write_parsed_problem

State = frozenset[str]
"""A planner state: the fluent atoms that hold, e.g. ``{"(at p0)", "(closed d0)", ...}``."""


def length_bound(shortest: int, tolerance: float) -> int:
    """The most actions a plan within ``tolerance`` may have (every backend's rounding)."""
    return math.floor((1 + tolerance) * shortest + 1e-9)


class Status(enum.StrEnum):
    SOLVED = "solved"
    NO_PLAN = "no-plan"
    """The goal cannot be reached from the start: learners must cope with this."""


@dataclass(frozen=True)
class Plan:
    """A plan: ground actions and the planner states before, between and after them."""

    actions: tuple[str, ...]
    states: tuple[State, ...]
    """``len(actions) + 1`` states; ``states[0]`` is the start, the last one a goal state."""

    def __len__(self) -> int:
        return len(self.actions)

    def pairs(self) -> Iterator[tuple[State, str]]:
        """The ``(state, action)`` pairs of the plan, in order."""
        return zip(self.states[:-1], self.actions, strict=True)


@dataclass(frozen=True)
class PlanResult:
    """What a planner found for one (start, goal) query."""

    status: Status
    plans: tuple[Plan, ...]
    planner: str
    metrics: Mapping[str, float] = field(default_factory=dict)
    capped: bool = False
    """True when more plans exist within the tolerance than the cap let through."""

    @property
    def length(self) -> int | None:
        """Length of the shortest plan, or None when there is no plan."""
        return min((len(p) for p in self.plans), default=None)


def no_plan(planner: str, started: float, **metrics: float) -> PlanResult:
    """The answer "no plan", timed from ``started`` (``time.perf_counter()``)."""
    return PlanResult(Status.NO_PLAN, (), planner,
                      {"time_s": time.perf_counter() - started, **metrics, "plans": 0})


class PlanningProblem:
    """A parsed domain and problem; grounded on first use, then shared by all queries.

    For a PPDDL domain, ``domain``, ``domain_text`` and ``task`` are its determinisation
    (what planners read), ``source_domain`` and ``learner_task`` the PPDDL domain and
    reality's task (for a STRIPS domain, the same as ``domain`` and ``task``).
    """

    def __init__(self, domain: Domain, problem: Problem, domain_text: str = "",
                 problem_text: str = "", source_domain: Domain | None = None,
                 tasks: tuple[GroundTask, GroundTask] | None = None) -> None:
        self.domain, self.problem = domain, problem
        self.domain_text, self.problem_text = domain_text, problem_text
        self.source_domain = source_domain or domain
        if tasks is not None:  # (learner's, planner's): a PPDDL problem, grounded already
            self.__dict__["learner_task"], self.__dict__["task"] = tasks
        self._results: dict[tuple, PlanResult] = {}
        self.text_gap = ""  # why the text cannot carry the domain (writer.untold)
        self.text_hashes: tuple[str, str] | None = None
        """The hashes of the domain's and the problem's texts as read (:meth:`from_texts`):
        what learner and policy files record of the problem (``docs/learners.md``)."""

    @classmethod
    def from_texts(cls, domain_text: str, problem_text: str, domain_source: str = "<domain>",
                   problem_source: str = "<problem>", determinisation: str = "all-outcomes",
                   problem_name: str | None = None) -> PlanningProblem:
        """Parse a domain and problem (``problem_name``: one of several in the text); a
        PPDDL domain is planned on through ``determinisation``."""
        domain = parse_domain(domain_text, domain_source)
        problem = parse_problem(problem_text, domain, problem_source, problem_name)
        check_size(problem, problem_source)
        gap = untold(domain, problem)  # what the text cannot carry (writer.untold)
        if not domain.probabilistic:
            out = cls(domain, problem, domain_text, problem_text)
        else:
            det = determinise(domain, determinisation)
            out = cls(det, problem, "" if gap else write_domain(det),
                      write_parsed_problem(problem, domain), domain,
                      ground_ppddl(domain, problem, determinisation))
        out.text_gap, out.text_hashes = gap, (text_hash(domain_text), text_hash(problem_text))
        return out

    @classmethod
    def from_files(cls, domain_path: str | Path, problem_path: str | Path,
                   determinisation: str = "all-outcomes") -> PlanningProblem:
        """Read and parse a domain and problem file (``problem_path`` may be ``FILE:NAME``)."""
        path, name = problem_file(problem_path)
        return cls.from_texts(read_pddl_text(domain_path), read_pddl_text(path), str(domain_path),
                              str(path), determinisation, name)

    @cached_property
    def task(self) -> GroundTask:
        """The grounded problem the planners search (computed once)."""
        return ground(self.domain, self.problem)

    @cached_property
    def ops_by_name(self) -> dict[str, GroundOp]:
        """The grounded task's actions by name (what a plan's steps are looked up in)."""
        return {op.name: op for op in self.task.ops}

    @cached_property
    def learner_task(self) -> GroundTask:
        """The grounded problem whose ops are the learner's actions."""
        return self.task

    @property
    def init(self) -> State:
        """The problem's initial state (fluent atoms only)."""
        return self.task.atoms(self.task.init)

    @property
    def goal(self) -> State:
        """The problem's goal as the fluent atoms that must hold."""
        return self.task.atoms(self.task.goal_pos)

    def query(self, planner: str, start: State | None, goal: State | None, tolerance: float,
              *options: object) -> Query:
        """Resolve a query against the grounded task (every backend starts here).

        Raises :class:`~gdq_pddl.errors.PlanningError` for a tolerance out of
        ``[0, MAX_TOLERANCE]`` or an unknown start atom; a goal no action can make true
        gives ``goal`` None (a "no plan" answer).
        """
        if not isinstance(tolerance, (int, float)) or isinstance(tolerance, bool) or \
                not math.isfinite(tolerance) or not 0 <= tolerance <= MAX_TOLERANCE:
            raise PlanningError(f"tolerance must be a finite number in [0, {MAX_TOLERANCE:g}] "
                                f"(plans up to {1 + MAX_TOLERANCE:g} x the shortest), got "
                                f"{tolerance!r}")
        if self.task.incomplete:  # the graph of states reads it; a query cannot
            raise PlanningError(f"{self.task.incomplete}; the {planner} planner answers "
                                "queries on those STRIPS actions: use the state graph "
                                "(gdq-pddl run's default --planner graph)")
        key = (planner, start, goal, tolerance, *options)
        hit = self._results.get(key)
        if hit is not None:  # answered before: skip resolving the masks
            return Query(key, -1, None, hit, time.perf_counter())
        task = self.task
        if start is None:
            s0 = task.init
        else:
            try:
                s0 = task.mask(start)
            except KeyError as exc:
                known = ", ".join(task.facts[:8])
                raise PlanningError(f"unknown or unreachable atom {exc.args[0]} in a start "
                                    f"state (fluent atoms look like: {known}, ...)") from None
        if goal is None and task.goal_alternatives:
            raise PlanningError(f"{self.problem.source}: the goal has alternatives ((or ...), "
                                "(exists ...), (imply ...)); a planner query takes one "
                                "conjunctive goal (the state graph's plan tables read them)")
        if goal is None:
            masks = (task.goal_pos, task.goal_neg) if task.goal_possible else None
        elif set(goal) <= task.fact_index.keys():
            masks = (task.mask(goal), 0)
        else:  # a fluent atom no action ever makes true
            masks = None
        return Query(key, s0, masks, None, time.perf_counter())

    def remember(self, key: tuple, result: PlanResult) -> PlanResult:
        self._results[key] = result
        return result

    def solved(self, q: Query, planner: str, plans: Iterable[Plan], capped: bool,
               tolerance: float, cap: int, **metrics: float) -> PlanResult:
        """Remember and return the plans a backend found for ``q``, shortest first (then
        by name), warning when more than ``cap`` were within ``tolerance`` (``capped``)."""
        if capped:
            warnings.warn(f"{planner} planner: more than {cap} plans within tolerance "
                          f"{tolerance}; kept the first {cap}", stacklevel=3)
        ordered = tuple(sorted(plans, key=lambda p: (len(p), p.actions)))
        metrics = {"time_s": time.perf_counter() - q.started, **metrics, "plans": len(ordered)}
        return self.remember(q.key, PlanResult(Status.SOLVED, ordered, planner, metrics, capped))

    def problem_pddl(self, start: State | None = None, goal: State | None = None) -> str:
        """PDDL text of this problem with another start state and/or goal: its objects,
        its static facts and the query's fluent atoms."""
        start = start if start is not None else self.init
        goal = goal if goal is not None else self.goal
        by_type: dict[str, list[str]] = {}
        for obj, typ in self.problem.objects.items():
            if obj not in self.domain.constants:
                by_type.setdefault(typ, []).append(obj)
        objects = "\n".join(f"    {' '.join(objs)} - {typ}" for typ, objs in by_type.items())
        init = sorted(self.task.statics | set(start))
        return (f"(define (problem {self.problem.name})\n"
                f"  (:domain {self.domain.name})\n"
                f"  (:objects\n{objects})\n"
                "  (:init\n" + "\n".join(f"    {a}" for a in init) + ")\n"
                f"  (:goal (and {' '.join(sorted(goal))})))\n")


def replay(task: GroundTask, state: int, actions: tuple[str, ...]) -> Plan:
    """The plan of ``actions`` from the bitmask ``state`` on the grounded task;
    :class:`PlanningError` naming the first step that does not apply."""
    ops = {op.name: op for op in task.ops}
    states = [state]
    for i, action in enumerate(actions):
        op = ops.get(action)
        if op is None or not op.applicable(states[-1]):
            raise PlanningError(f"step {i + 1} of the plan, {action}, is not applicable in "
                                "the grounded task")
        states.append(op.apply(states[-1]))
    return Plan(actions, tuple(task.atoms(s) for s in states))


def check_size(problem: Problem, source: str) -> None:
    """Refuse, naming ``source``, a problem too large to ground (:data:`MAX_INIT_ATOMS`)."""
    if len(problem.init) > MAX_INIT_ATOMS:
        raise SizeError(f"{source}: the initial state has {len(problem.init):,} atoms, more "
                        f"than the {MAX_INIT_ATOMS:,} a problem may have to be planned over "
                        "(a building of about 30,000 positions); give a smaller problem")


class Query(NamedTuple):
    """One planning query, resolved by :meth:`PlanningProblem.query` (a tuple: cheap)."""

    key: tuple  # planner, start, goal, tolerance and the planner's options
    start: int  # bitmask of the grounded task (-1 when ``hit`` answers the query)
    goal: tuple[int, int] | None  # (must hold, must not hold) bitmasks; None: never holds
    hit: PlanResult | None  # the cached answer, if any
    started: float  # time.perf_counter() when the query was made


@runtime_checkable
class Planner(Protocol):
    """A planner backend of the ``gdq_pddl.planners`` entry points: ``all_plans`` says
    whether it returns every shortest plan, ``unusable_reason`` why it cannot run here."""

    name: str
    all_plans: bool

    @classmethod
    def unusable_reason(cls) -> str | None: ...

    def solve(self, problem: PlanningProblem, start: State | None = None,
              goal: State | None = None, tolerance: float = 0.0) -> PlanResult: ...
