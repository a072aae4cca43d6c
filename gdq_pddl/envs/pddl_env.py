"""Any PDDL problem as a Gymnasium environment (``gdq_pddl/PDDL-v0``; docs/domains.md).

The domain and problem (files or shipped names) are the robot's knowledge. Reality is a
dynamics file (:mod:`gdq_pddl.dynamics`) for a STRIPS domain, or a PPDDL domain's own
probabilistic effects (the planner knows their ``determinisation``) with an optional
overlay. The true model is a :class:`~gdq_pddl.envs.step.ModelArrays`, as the office's.

- Actions: ``Discrete(n_ops)``, the ground actions in the grounder's order; one whose
  precondition does not hold costs its cost and changes nothing.
- Observations: ``Discrete(n_states)``, the states reachable from the initial state (goal
  states not expanded), breadth first, 0 the initial state (``env.unwrapped.atoms(s)``);
  ``reset(options={"start": "(at c12) (open c11) ..."})`` starts elsewhere.
- Rewards: as the office's, or the problem's own (:attr:`PDDLInstance.reward_scale`).
- ``info``: ``action_mask`` (1 where the precondition holds), ``plan_action`` (the first
  action of a shortest plan of the knowledge, -1: none; docs/python.md), ``area`` (0),
  ``cause``, ``full_state`` (the observation) and ``step``; ``render_mode`` ``"ansi"`` or
  ``"rgb_array"`` shows the state's atoms.
"""

from __future__ import annotations

import copy
import re
from collections.abc import Iterable
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from gdq_pddl.abstraction import PlanTable, build_plan_table
from gdq_pddl.abstraction.masks import graph_action_mask
from gdq_pddl.abstraction.pddl import PDDLAbstraction, graph_plan_table
from gdq_pddl.abstraction.prior import (
    PriorModel,
    dead_end_states,
    prior_from_graph,
    with_dead_chances,
)
from gdq_pddl.dynamics import CostDist, Dynamics, split_action
from gdq_pddl.envs.base import CompiledEnv
from gdq_pddl.envs.identity import file_entry
from gdq_pddl.envs.model import StateSpace, compile_true_model
from gdq_pddl.envs.pddl_checks import (
    DEFAULT_R_MAX,
    check_determinisation,
    check_goal,
    check_reality,
    check_step_limit,
    check_step_rewards,
    default_step_limit,
    limit_key,
    parse_reality,
)
from gdq_pddl.envs.render import text_image
from gdq_pddl.envs.solve import value_within
from gdq_pddl.envs.solve_compact import successor_capacity
from gdq_pddl.envs.step import ModelArrays, env_act
from gdq_pddl.errors import ConfigError, PlanningError, WorldError
from gdq_pddl.inputs import read_text, text_hash
from gdq_pddl.limits import check_memory
from gdq_pddl.pddl.outcomes import reality_outcomes
from gdq_pddl.pddl.ppddl import DETERMINISATIONS
from gdq_pddl.pddl.reachable import MAX_STATES, PAIR_BYTES, StateGraph, reachable_graph
from gdq_pddl.planning import get_planner
from gdq_pddl.planning.base import PlanningProblem
from gdq_pddl.resources import resolve_pddl, shipped_names

GOAL_POS = 1
"""``pos_of`` of a goal state in a PDDL model (0 elsewhere); what ``env_step`` compares."""


@dataclass(frozen=True, eq=False)
class PDDLInstance:
    """A domain, a problem and their dynamics: grounded, explored and compiled once."""

    problem: PlanningProblem
    """The domain and problem as read, with the planner's determinisation."""
    overlay: Dynamics | None
    """The dynamics file as given (None: none, for a PPDDL domain only)."""
    max_states: int | None = MAX_STATES
    """The most reachable states explored before the problem is refused as too large."""
    start_state: int = 0
    """Where episodes start (0: the problem's initial state; see :meth:`restarted`)."""
    dynamics_hash: str | None = None
    """The hash of the dynamics file's text as read (``sha256:<hex>``; None: none given,
    or an instance not made by :meth:`from_files` or :meth:`from_texts`)."""

    @classmethod
    def from_files(cls, domain: str | Path, problem: str | Path,
                   dynamics: str | Path | None = None, max_states: int | None = MAX_STATES,
                   determinisation: str = DETERMINISATIONS[0]) -> PDDLInstance:
        """Read and check the files (errors name the file and line or key). Each may be a
        shipped name instead, as ``gymnasium.make`` takes them (``"keys"``, ``"keys-2"``;
        :func:`~gdq_pddl.resources.resolve`): a shipped domain without ``dynamics`` gets
        its shipped dynamics file if there is one."""
        domain, problem, dynamics = resolve_pddl(domain, problem, dynamics)
        planning = PlanningProblem.from_files(domain, problem,
                                              check_determinisation(determinisation))
        text = None if dynamics is None else \
            read_text(dynamics, lambda src, msg: WorldError(src, "", msg))
        overlay = None if text is None else parse_reality(text, planning, str(dynamics))
        return cls._built(planning, overlay, max_states, text)

    @classmethod
    def from_texts(cls, domain: str, problem: str, dynamics: str | None = None,
                   max_states: int | None = MAX_STATES,
                   determinisation: str = DETERMINISATIONS[0]) -> PDDLInstance:
        """:meth:`from_files` of texts in memory (errors name ``<domain>``, ``<problem>``)."""
        planning = PlanningProblem.from_texts(domain, problem,
                                              determinisation=check_determinisation(determinisation))
        overlay = None if dynamics is None else parse_reality(dynamics, planning)
        return cls._built(planning, overlay, max_states, dynamics)

    @classmethod
    def _built(cls, planning: PlanningProblem, overlay: Dynamics | None,
               max_states: int | None, dynamics_text: str | None = None) -> PDDLInstance:
        domain = planning.source_domain
        if overlay is None and not domain.probabilistic:
            raise PlanningError(f"{domain.source} is a STRIPS domain: it says what actions do "
                                "when they work, not how often they do; give its dynamics "
                                "file (--dynamics), or write its outcomes in PPDDL "
                                "(docs/domains.md)")
        return cls(planning, overlay, max_states,
                   dynamics_hash=None if dynamics_text is None else text_hash(dynamics_text))

    @property
    def name(self) -> str:
        """The problem's name."""
        return self.problem.problem.name

    def identity(self) -> dict[str, str]:
        """What this problem is, as learner and policy files record it
        (:mod:`~gdq_pddl.envs.identity`): its domain, problem and dynamics files by the
        hashes of their texts, the problem's name and the planner's determinisation."""
        hashes = self.problem.text_hashes or (None, None)
        out = {"domain": file_entry(self.problem.source_domain.source, hashes[0]),
               "problem": file_entry(self.source, hashes[1]), "problem name": self.name,
               "dynamics": "none" if self.overlay is None else
               file_entry(self.overlay.source or "<dynamics>", self.dynamics_hash)}
        if self.determinisation is not None:
            out["determinisation"] = self.determinisation
        return out

    @property
    def ppddl(self) -> bool:
        """Whether the domain is PPDDL (reality is its probabilistic model)."""
        return self.problem.source_domain.probabilistic

    @property
    def determinisation(self) -> str | None:
        """What the planner knows of a PPDDL domain (None: a STRIPS domain)."""
        return getattr(self.problem.learner_task, "determinisation", None)

    @property
    def knows_dead_ends(self) -> bool:
        """Whether a state from which the knowledge cannot reach the goal is a dead end in
        reality: a PPDDL domain known by all its outcomes (most-likely knowledge lacks
        ways that reality has; a STRIPS domain's reality is its dynamics file)."""
        return self.ppddl and self.determinisation == DETERMINISATIONS[0]

    @cached_property
    def reward_scale(self) -> str:
        """``"problem"``: the file's own rewards, as the IPPC scores them (metric ``maximize
        (reward)``, ``:rewards`` or effects on ``(reward)``); ``"goal"``: +-r_max and costs."""
        domain, metric = self.problem.source_domain, self.problem.problem.metric
        own = metric == "maximize (reward)" if metric is not None else \
            domain.reward_effects or ":rewards" in domain.requirements
        return "problem" if own else "goal"

    @cached_property
    def dynamics(self) -> Dynamics:
        """Reality's r_max and step limit (and the dynamics file's outcomes, if STRIPS)."""
        overlay = self.overlay_with_r_max()
        if self.ppddl and "step_limit" not in overlay.stated:
            overlay = replace(overlay, step_limit=default_step_limit(self.graph))
        check_step_limit(self.problem, self.graph, overlay)
        return overlay

    def overlay_with_r_max(self) -> Dynamics:
        """The dynamics file (or none) with reality's r_max (the file's, the goal's, 20)."""
        overlay = self.overlay or Dynamics(source="")
        goal_reward = self.problem.problem.goal_reward
        if "r_max" not in overlay.stated and (goal_reward or self.reward_scale == "problem"):
            overlay = replace(overlay, r_max=goal_reward or 0.0)
        elif "r_max" not in overlay.stated and self.ppddl:
            overlay = replace(overlay, r_max=DEFAULT_R_MAX)
        return overlay

    @cached_property
    def graph(self) -> StateGraph:
        """Reachable states and successors (refused past ``max_states`` or the table budget,
        and by :func:`check_goal`)."""
        return self._enumerated(give_up_early=False)

    def graph_or_give_up(self) -> StateGraph:
        """:attr:`graph`, but refused as soon as the breadth-first levels' growth
        projects past the table budget, not only once past it
        (:func:`~gdq_pddl.pddl.reachable.projected_states`): what ``gdq-pddl run
        --explore auto`` asks, which goes online then."""
        if "graph" not in self.__dict__:  # where cached_property keeps it
            self.__dict__["graph"] = self._enumerated(give_up_early=True)
        return self.graph

    def _enumerated(self, give_up_early: bool) -> StateGraph:
        graph = reachable_graph(self.problem.learner_task, self.max_states,
                                self.problem.problem.source, give_up_early)
        check_goal(self.problem, graph)
        return graph

    @cached_property
    def costs(self) -> list[CostDist]:
        """Every ground action's cost: the dynamics file's, else the domain's, else 1 (0 on
        the problem's own reward scale)."""
        ops = self.problem.learner_task.ops  # the graph's task
        names, stated = [op.name for op in ops], [op.cost for op in ops]
        unstated = CostDist("const", 0.0) if self.reward_scale == "problem" else CostDist()
        return [(self.overlay.outcomes(*split_action(name)).cost if self.overlay else None)
                or (unstated if cost is None else CostDist("const", cost))
                for name, cost in zip(names, stated, strict=True)]

    @cached_property
    def model(self) -> ModelArrays:
        """The true model (read-only); refused past its memory and by :func:`check_reality`."""
        check_memory(self.graph.offered.size * PAIR_BYTES,
                     f"{self.dynamics.source or self.problem.problem.source}: the true model "
                     f"of {self.n_states} states x up to {self.graph.offered.shape[1]} "
                     f"applicable ground actions",
                     "make the problem smaller (fewer objects)")
        own = self.reward_scale == "problem"
        check_step_rewards(self.problem, self.costs, self.dynamics.r_max, own)
        model = compile_true_model(graph_space(self.graph), self.dynamics, self.costs,
                                   reality_outcomes(self.graph) if self.ppddl else None,
                                   self.ppddl, own)
        if own and not self.ppddl:  # a STRIPS domain's outcomes earn no reward of their own
            model = model._replace(gain=np.zeros(len(model.prob)))
        check_reality(self.problem, self.graph, self.dynamics, model)
        return model

    @cached_property
    def mask_table(self) -> np.ndarray:
        """``int8[n_states, n_actions]``, read-only: 1 where the ground action is applicable."""
        return graph_action_mask(self.graph)

    source = property(lambda self: self.problem.problem.source)
    """The problem file errors name."""

    @property
    def learner_start(self) -> int:
        """The learner's start state (:attr:`start_state`: states are the graph's)."""
        return self.start_state

    @cached_property
    def learner_goal(self) -> np.ndarray:
        """``bool[n_states]``: the reachable states where the goal holds."""
        return np.asarray(self.graph.is_goal, dtype=np.bool_)

    @property
    def r_max(self) -> float:
        """The goal reward (the goal scale: failure is ``-r_max``)."""
        return float(self.dynamics.r_max)

    @cached_property
    def max_successors(self) -> int:
        """:func:`~gdq_pddl.envs.solve_compact.successor_capacity` of the true model."""
        return successor_capacity(self.model)

    @cached_property
    def prior(self) -> PriorModel:
        """The knowledge's deterministic model over the graph (its ground actions); of a
        PPDDL domain, with each pair's chance of a dead end (:attr:`PriorModel.dead`, by
        the file's outcomes, which the true model samples; a dead end: no way to the goal,
        or none that fits the step limit from the start, :func:`dead_end_states`) where
        the knowledge is every outcome (:attr:`knows_dead_ends`)."""
        prior = prior_from_graph(self.graph)
        if not self.knows_dead_ends:
            return prior
        m = self.model  # over the graph's states and their applicable ground actions
        dead = dead_end_states(self.graph, self.start_state, int(self.dynamics.step_limit))
        return with_dead_chances(prior, m.ptr, m.prob, m.next, dead)

    @cached_property
    def _tables(self) -> dict[tuple[str, float], PlanTable]:
        return {}

    def plan_table(self, planner: str = "graph", tolerance: float = 0.0,
                   kind: str = "all") -> PlanTable:
        """Plans from every reachable state, cached per (planner, tolerance): the graph's
        distance layers for ``graph``, else one query per state (``kind``: the office's)."""
        key = (planner, float(tolerance))
        if key not in self._tables:
            if planner == "graph":
                table = graph_plan_table(self.graph, tolerance)
            elif self.problem.problem.goal_alternatives:
                raise PlanningError(f"{self.source}: the goal has alternatives ((or ...), "
                                    f"(exists ...) or (imply ...)); the {planner} planner "
                                    "reads one conjunctive goal: use --planner graph")
            else:
                o = PDDLAbstraction(self.graph)
                table = build_plan_table(o, self.problem, get_planner(planner), o.goal(),
                                         tolerance)
            self._tables[key] = table.in_columns(self.columns)
        return self._tables[key]

    @property
    def columns(self) -> np.ndarray:
        """int64[n_states, width]: the ground actions each state offers the learners (the
        graph's :attr:`~gdq_pddl.pddl.reachable.StateGraph.offered`, -1 padding): the
        layout of their tables, the prior and the plan tables."""
        return self.graph.offered

    @property
    def n_states(self) -> int:
        """How many reachable states (the env's observations)."""
        return self.graph.n_states

    @property
    def n_actions(self) -> int:
        """How many ground actions (the env's actions)."""
        return len(self.graph.task.ops)

    def action_name(self, a: int) -> str:
        """The ground action ``a``, e.g. ``"(move r1 r2)"``."""
        return self.graph.task.ops[a].name

    def atoms(self, s: int) -> frozenset[str]:
        """The fluent atoms of state ``s``."""
        return self.graph.task.atoms(self.graph.states[s])

    def goal_distance(self, s: int) -> int:
        """The knowledge's fewest actions from state ``s`` to the goal (the context's
        ``plans.length[s]``: 0 at a goal, -1 where the knowledge reaches no goal)."""
        return int(self.graph.distances[s])

    def plan_action(self, s: int) -> int:
        """The first action of a shortest plan of the knowledge from state ``s``: the
        lowest ground action with an outcome one action closer to the goal (the lowest
        column of ``plans.first_actions[s]``); -1 at a goal and where there is no plan."""
        g = self.graph
        d = int(g.distances[s])
        if d <= 0:
            return -1
        lo, hi = g.edge_ptr[s], g.edge_ptr[s + 1]
        return int(g.edge_op[lo:hi][g.distances[g.edge_next[lo:hi]] == d - 1].min())

    @property
    def atom_names(self) -> tuple[str, ...]:
        """The problem's fluent ground atoms, in the order of :meth:`facts`."""
        return self.graph.task.facts

    def facts(self, s: int) -> np.ndarray:
        """``int8[len(atom_names)]``: 1 for each fluent atom true in state ``s``."""
        return word_facts(self.graph.words[s], len(self.atom_names))

    def optimal(self) -> dict[str, Any]:
        """The ground truth: V* (within :data:`~gdq_pddl.envs.solve.VSTAR_BUDGET`, else a
        bound and why), the shortest plan, the sizes."""
        s0 = self.start_state
        return {"determinisation": self.determinisation, "r_max": self.dynamics.r_max,
                "reward_scale": self.reward_scale,
                "step_limit": self.dynamics.step_limit,
                **value_within(self.model, GOAL_POS, s0),
                "shortest_plan": int(self.graph.distances[s0]), "states": self.n_states,
                "actions": self.n_actions, "relevant_areas": [], "irrelevant_areas_paper": [],
                "expected_area_visits": {}}

    def state_name(self, s: int) -> str:
        """State ``s`` as its sorted fluent atoms."""
        return " ".join(sorted(self.atoms(s)))

    @property
    def step_limit_key(self) -> tuple[str, str]:
        """The file and key that give the step limit."""
        return limit_key(self.problem, self.dynamics)

    goal_pos = GOAL_POS
    """``pos_of`` of a goal state (:data:`GOAL_POS`): what a step compares to end in success."""

    def restarted(self, start: str | Iterable[str] | None = None,
                  goal: None = None) -> PDDLInstance:
        """The instance whose episodes start in the reachable state where exactly the
        fluent facts ``start`` hold (a string as ``render()`` lists them, or a list;
        statics may be left out). A ``goal`` is refused: :class:`ConfigError`."""
        if goal is not None:
            raise ConfigError(f"reset options: goal {goal!r}: a PDDL env's goal is its "
                              f"problem's ({self.source}); write another problem file")
        if start is None:
            return self
        task, graph = self.graph.task, self.graph
        facts = start_facts(start) - set(task.statics)
        unknown = sorted(facts - set(task.fact_index))
        s = None if unknown else graph.index.get(task.mask(facts))
        if s is None or graph.is_goal[s]:
            why = (f"{unknown[0]} is no fluent fact of {self.source}" if unknown else
                   "the goal holds there" if s is not None else
                   "no state reachable from the initial state has exactly these fluent "
                   "facts true (list them all, as render() does)")
            raise ConfigError(f"reset options: start {start!r}: {why}")
        new = copy.copy(self)  # shares the graph, model and plan tables
        object.__setattr__(new, "start_state", int(s))
        new.__dict__.pop("prior", None)  # its dead ends depend on the start
        return new

    def info(self, pos: int) -> dict[str, Any]:
        """What ``info`` says beyond every env's keys (at position ``pos``): nothing."""
        return {}

    def render(self, mode: str, fs: int, step: int, cause: str, action: str = ""
               ) -> str | np.ndarray:
        """The state's fluent atoms as text (``ansi``) or drawn (``rgb_array``, 640 x 480,
        under the ``action`` that led here)."""
        why = f" ({cause})" if cause else ""
        text = f"step {step}{why}: " + " ".join(sorted(self.atoms(fs)))
        if mode == "ansi":
            return text
        done = f"action taken: {action}" if action else "start of the episode"
        return text_image(f"{self.name}\n{done}\n"
                          + text.replace(" ", "\u00a0").replace(")\u00a0(", ") ("))


def word_facts(words: np.ndarray, n_facts: int) -> np.ndarray:
    """``int8[n_facts]``: the bits of a state's word row (bit ``j`` of word ``w`` is fact
    ``64 w + j``)."""
    bits = np.unpackbits(np.ascontiguousarray(words, dtype="<u8").view(np.uint8),
                         bitorder="little")
    return bits[:n_facts].astype(np.int8)


def start_facts(start: object) -> set[str]:
    """The fluent facts of a ``reset`` option's ``start``, each written ``(name args)``
    lower-cased: a string of parenthesised facts as ``render()`` lists them, or a list (a
    tuple, a set) of strings, one fact each (``"(at c12)"`` or ``"at c12"``). Anything
    else, or text that is not such facts (unbalanced or nested parentheses, words outside
    them), is refused with a :class:`ConfigError` saying what it takes."""
    takes = ("a string of fluent facts as render() lists them, \"(at c12) (open c11)\", or "
             "a list of such facts")
    if isinstance(start, str):
        why = _not_facts(start)
        if why:
            raise ConfigError(f"reset options: start {start!r}: {why}; expected {takes}")
        items = re.findall(r"\(([^()]*)\)", start)
    elif isinstance(start, (list, tuple, set, frozenset)):
        items = []
        for fact in start:
            if not isinstance(fact, str):
                raise ConfigError(f"reset options: start {start!r}: {fact!r} (of type "
                                  f"{type(fact).__name__}) is not a fact; expected {takes}")
            inner = fact.strip()
            if inner.startswith("(") and inner.endswith(")"):
                inner = inner[1:-1]
            if "(" in inner or ")" in inner or not inner.split():
                raise ConfigError(f"reset options: start {start!r}: {fact!r} is not one "
                                  f"fact; expected {takes}")
            items.append(inner)
    else:
        raise ConfigError(f"reset options: start {start!r} is of type "
                          f"{type(start).__name__}; expected {takes}")
    return {"(" + " ".join(item.lower().split()) + ")" for item in items}


def _not_facts(text: str) -> str:
    """Why ``text`` is not parenthesised facts with blanks between them ("" if it is)."""
    depth = 0
    for i, ch in enumerate(text):
        if ch == "(":
            depth += 1
            if depth > 1:
                return f"nested parentheses at character {i + 1}"
        elif ch == ")":
            depth -= 1
            if depth < 0:
                return f"unbalanced parentheses: a ')' without its '(' at character {i + 1}"
        elif depth == 0 and not ch.isspace():
            word = text[i:].split("(")[0].split()[0]
            return f"text outside ( ) at character {i + 1}: {word!r}"
    return "unbalanced parentheses: a '(' never closed" if depth else ""


def graph_space(graph: StateGraph) -> StateSpace:
    """A PDDL problem's reachable states and ground actions as a ``StateSpace``."""
    n = graph.n_states
    return StateSpace(
        task=graph.task, n_states=n, edges=graph.edges, n_actions=len(graph.task.ops),
        action_of_op=tuple(range(len(graph.task.ops))),
        obs_of=np.arange(n, dtype=np.int64),
        pos_of=np.where(graph.is_goal, GOAL_POS, 0).astype(np.int64),
        area_of_pos=np.zeros(GOAL_POS + 1, dtype=np.int64), offered=graph.offered)


def load_instance(domain: str | Path | None, problem: str | Path | None,
                  dynamics: str | Path | None = None,
                  determinisation: str = DETERMINISATIONS[0]) -> PDDLInstance:
    """The :class:`PDDLInstance` of three files, or of shipped names (``domain="keys"``;
    a shipped domain without ``dynamics`` gets its shipped dynamics file if any)."""
    if domain is None or problem is None:
        raise PlanningError("a PDDL env needs domain= and problem= (files, or shipped names: "
                            f"domains {', '.join(shipped_names('domain'))}; problems "
                            f"{', '.join(shipped_names('problem'))})")
    return PDDLInstance.from_files(domain, problem, dynamics, determinisation=determinisation)


class PDDLEnv(CompiledEnv):
    """The env of an instance over its full true model (a PDDL problem, or a world's task:
    ``Office-v0``); what the instance says through named properties
    (``env.unwrapped.atoms(s)``, :class:`~gdq_pddl.envs.base.CompiledEnv`), the rest
    through ``env.unwrapped.instance``."""

    metadata = {"render_modes": ["ansi", "rgb_array"], "render_fps": 4}
    """Both kinds of instance draw both modes (their ``render``)."""

    def __init__(self, domain: str | Path | None = None, problem: str | Path | None = None,
                 dynamics: str | Path | None = None, instance: Any = None,
                 render_mode: str | None = None,
                 determinisation: str = DETERMINISATIONS[0]) -> None:
        self.check_render_mode(render_mode)  # before loading, which can take long
        if instance is None:
            instance = load_instance(domain, problem, dynamics, determinisation)
        super().__init__(instance, instance.model, render_mode)

    def render(self) -> str | np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode="
                            "'ansi' to gymnasium.make")
            return None
        action = self.instance.action_name(self._action) if self._action >= 0 else ""
        return self.instance.render(self.render_mode, self._fs, self._t, self._cause, action)

    def _restart(self) -> None:
        self._fs = self.instance.start_state

    def _advance(self, a: int) -> tuple[float, bool, bool, int]:
        fs, reward, terminated, truncated, cause = env_act(
            self.model, self._fs, a, self._t, self.instance.goal_pos, self.np_random)
        self._fs = int(fs)
        return reward, terminated, truncated, cause

    def _observe(self) -> int:
        return int(self.model.obs_of[self._fs])

    def _position(self) -> int:
        return int(self.model.pos_of[self._fs])

    def facts(self) -> np.ndarray:
        """The true state's atoms (``instance.atom_names``) as ``int8`` 0/1."""
        return self.instance.facts(self._fs)

    def _info(self) -> dict[str, Any]:
        return {**super()._info(), "full_state": self._fs}
