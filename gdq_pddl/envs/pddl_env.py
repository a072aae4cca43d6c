"""Any STRIPS + typing PDDL domain as a Gymnasium environment, with a dynamics file.

The PDDL domain and problem are the robot's knowledge; the dynamics file
(:mod:`gdq_pddl.dynamics`) is reality: how often each ground action works, what a
failure does, what it costs, the rewards and the step limit. The env's true model is
compiled once into the same :class:`~gdq_pddl.envs.model.ModelArrays` as the office's,
so it steps through the same :func:`~gdq_pddl.envs.model.env_step`, the fast episode
runner works on it and :func:`gdq_pddl.envs.solve.solve` gives its V*.

## Action space
``Discrete(n_ops)``: the ground actions of the problem, in the grounder's order
(``env.unwrapped.action_name(a)``). An action whose precondition does not hold costs its
cost and changes nothing.

## Observation space
``Discrete(n_states)``: the states reachable from the problem's initial state (goal
states are not expanded), numbered breadth first; 0 is the initial state
(``env.unwrapped.atoms(s)`` lists a state's fluent atoms). The learner sees the full
planner state: nothing is hidden.

## Rewards and episode end
As in the office: ``+r_max`` on reaching a state where the problem's goal holds
(terminated), ``-r_max`` when an action leaves the robot stuck (terminated) or on the
last allowed action (truncated, after ``step_limit`` actions), otherwise minus the
action's cost.

## Outcomes of an applicable ground action
With probability ``success`` its PDDL effect; with ``stuck`` the trial fails; the rest
does nothing, or (a slip) the effect of a uniformly random applicable ground action of
the schemas the dynamics file lists.

## Information
``info`` holds ``area`` (always 0), ``cause``, ``full_state`` (= the observation) and
``step``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium.spaces import Discrete

from gdq_pddl.dynamics import Dynamics, load_dynamics, parse_dynamics, split_action
from gdq_pddl.envs.base import ModelEnv
from gdq_pddl.envs.model import PAIR_BYTES, ModelArrays, cost_arrays, merge_outcomes, outcome_csr
from gdq_pddl.errors import PlanningError, WorldError
from gdq_pddl.limits import check_memory
from gdq_pddl.pddl.reachable import MAX_STATES, StateGraph, reachable_graph
from gdq_pddl.planning.base import PlanningProblem

GOAL_POS = 1
"""``pos_of`` of a goal state in a PDDL model (0 elsewhere); what ``env_step`` compares."""


@dataclass(frozen=True, eq=False)
class PDDLInstance:
    """A domain, a problem and their dynamics: grounded, explored and compiled once."""

    problem: PlanningProblem
    dynamics: Dynamics
    max_states: int = MAX_STATES

    @classmethod
    def from_files(cls, domain: str | Path, problem: str | Path, dynamics: str | Path,
                   max_states: int = MAX_STATES) -> PDDLInstance:
        """Read and check the three files (errors name the file and line or key)."""
        planning = PlanningProblem.from_files(domain, problem)
        return cls(planning, load_dynamics(dynamics, planning.domain, planning.problem),
                   max_states)

    @classmethod
    def from_texts(cls, domain: str, problem: str, dynamics: str,
                   max_states: int = MAX_STATES) -> PDDLInstance:
        planning = PlanningProblem.from_texts(domain, problem)
        return cls(planning, parse_dynamics(dynamics, planning.domain, planning.problem),
                   max_states)

    @property
    def name(self) -> str:
        """The problem's name."""
        return self.problem.problem.name

    @cached_property
    def graph(self) -> StateGraph:
        """Reachable states and their successors; raises past ``max_states``, and for a
        task nothing can be learnt on (:func:`check_task`)."""
        graph = reachable_graph(self.problem.task, self.max_states, self.problem.problem.source)
        check_task(self.problem, graph, self.dynamics)
        return graph

    @cached_property
    def model(self) -> ModelArrays:
        """The true model (read-only arrays)."""
        model = compile_pddl_model(self.graph, self.dynamics)
        for array in model:
            if isinstance(array, np.ndarray):
                array.setflags(write=False)
        return model

    @property
    def n_states(self) -> int:
        return self.graph.n_states

    @property
    def n_actions(self) -> int:
        return len(self.problem.task.ops)

    def action_name(self, a: int) -> str:
        """The ground action ``a``, e.g. ``"(move r1 r2)"``."""
        return self.problem.task.ops[a].name

    def atoms(self, s: int) -> frozenset[str]:
        """The fluent atoms of state ``s``."""
        return self.problem.task.atoms(self.graph.states[s])


def check_task(problem: PlanningProblem, graph: StateGraph, dynamics: Dynamics) -> None:
    """Refuse a problem whose goal is empty, holds in the initial state or cannot be
    reached, and a step limit below the shortest plan: in each, no episode could teach the
    learner anything, and the results would look like a success (or a certain failure).

    Raises :class:`PlanningError` naming the problem file, or a
    :class:`~gdq_pddl.errors.WorldError` naming the dynamics file's ``step_limit``.
    """
    source = problem.problem.source
    if not problem.problem.goal:
        raise PlanningError(f"{source}: the goal is empty: it holds in every state, so "
                            "there is nothing to learn; give a goal")
    if graph.is_goal[0]:
        raise PlanningError(f"{source}: the goal already holds in the initial state: every "
                            "episode would be over before it begins")
    if not graph.is_goal.any():
        never = never_true(problem)
        why = (f"{never} can never hold (no action makes it true, and the initial state "
               "does not have it)" if never else
               f"none of the {graph.n_states} states reachable from the initial state "
               "satisfies it")
        raise PlanningError(f"{source}: no plan: the goal cannot be reached from the "
                            f"initial state: {why}")
    shortest = int(graph.distances[0])
    if shortest > dynamics.step_limit:
        raise WorldError(dynamics.source, "dynamics.step_limit",
                         f"{dynamics.step_limit} is less than the shortest plan of {source} "
                         f"({shortest} actions): no episode can reach the goal")


def never_true(problem: PlanningProblem) -> str:
    """The first goal literal of ``problem`` that can never hold ("" if none is)."""
    task = problem.task
    for lit in problem.problem.goal:
        atom = str(lit.atom)
        text = atom if lit.positive else f"(not {atom})"
        if lit.atom.predicate == "=":
            if (lit.atom.args[0] == lit.atom.args[1]) != lit.positive:
                return text
        elif lit.atom.predicate not in problem.domain.fluent_predicates():
            if (atom in task.statics) != lit.positive:
                return text
        elif lit.positive and atom not in task.fact_index:
            return atom
    return ""


def compile_pddl_model(graph: StateGraph, dynamics: Dynamics) -> ModelArrays:
    """The dynamics of every (reachable state, ground action) pair as :class:`ModelArrays`."""
    ops = graph.task.ops
    n_ops = len(ops)
    check_memory(graph.n_states * n_ops * PAIR_BYTES,
                 f"{dynamics.source}: the true model of {graph.n_states} states x {n_ops} "
                 "ground actions", "make the problem smaller (fewer objects)")
    parts = [split_action(op.name) for op in ops]
    outcomes = [dynamics.outcomes(schema, args) for schema, args in parts]
    schema_of = [schema for schema, _ in parts]

    def pairs():
        for s in range(graph.n_states):
            applicable = dict(graph.edges(s))  # op -> next state (goal states: none)
            for k in range(n_ops):
                t = applicable.get(k)
                if t is None:
                    yield s * n_ops + k, {(s, False): 1.0}
                else:
                    o = outcomes[k]
                    rest = max(0.0, 1.0 - o.success - o.stuck)
                    yield s * n_ops + k, merge_outcomes(
                        _split(s, t, o, rest, applicable, schema_of))

    ptr, prob, (nxt, stuck) = outcome_csr(graph.n_states * n_ops, pairs(),
                                          (np.int64, np.bool_))
    pos_of = np.where(graph.is_goal, GOAL_POS, 0).astype(np.int64)
    return ModelArrays(
        n_actions=n_ops, n_doors=0, r_max=float(dynamics.r_max),
        step_limit=int(dynamics.step_limit), ptr=ptr, prob=prob, next=nxt, stuck=stuck,
        **cost_arrays([o.cost for o in outcomes]),
        obs_of=np.arange(graph.n_states, dtype=np.int64), pos_of=pos_of,
        area_of_pos=np.zeros(GOAL_POS + 1, dtype=np.int64))


def _split(s: int, t: int, o, rest: float, applicable: dict[int, int],
           schema_of: list[str]) -> list[tuple[tuple[int, bool], float]]:
    """Outcomes ``((next, stuck), prob)`` of an applicable action: success, stuck, the rest."""
    out = [((t, False), o.success), ((s, True), o.stuck)]
    if isinstance(o.failure, tuple):
        slips = [u for k, u in applicable.items() if schema_of[k] in o.failure]
        if slips:
            out += [((u, False), rest / len(slips)) for u in slips]
            return out
    out.append(((s, False), rest))
    return out


class PDDLEnv(ModelEnv):
    """A PDDL problem under a dynamics file (see the module docstring)."""

    metadata = {"render_modes": ["ansi"], "render_fps": 4}

    def __init__(self, domain: str | Path | None = None, problem: str | Path | None = None,
                 dynamics: str | Path | None = None, instance: PDDLInstance | None = None,
                 render_mode: str | None = None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} "
                             f"or None, got {render_mode!r}")
        if instance is None:
            if domain is None or problem is None or dynamics is None:
                raise PlanningError("PDDLEnv needs domain, problem and dynamics files "
                                    "(or an instance)")
            instance = PDDLInstance.from_files(domain, problem, dynamics)
        self.instance = instance
        self.model = instance.model
        self.observation_space = Discrete(instance.n_states)
        self.action_space = Discrete(instance.n_actions)
        self.render_mode = render_mode
        self.goal_pos = GOAL_POS
        self.start_state = 0
        self._begin()

    def action_name(self, a: int) -> str:
        return self.instance.action_name(a)

    def atoms(self, s: int) -> frozenset[str]:
        return self.instance.atoms(s)

    def render(self) -> str | None:
        if self.render_mode is None:
            return None
        cause = f" ({self._cause})" if self._cause else ""
        return f"step {self._t}{cause}: " + " ".join(sorted(self.atoms(self._fs)))

    def _info(self) -> dict[str, Any]:
        return super()._info()
