"""A PPDDL problem explored online: its states found as episodes reach them.

A problem whose reachable states do not fit the table budget (pddlgym's
manyexplodingblockssmallpiles: 23 blocks, more states than any memory) cannot be
enumerated. :class:`OnlineInstance` gives the learners and the env the same view as a
:class:`~gdq_pddl.envs.pddl_env.PDDLInstance`, over the states found so far
(:class:`~gdq_pddl.pddl.lazy.LazyGraph`): a state is *expanded* (its applicable ground
actions, the knowledge's edges, reality's outcomes) when an episode first reaches it.

The learners' rows (the env's observations) are of three kinds:

- a state an episode reached: its applicable ground actions, as an enumerated problem's
  (a goal: a goal row);
- a **chain** row ``k``, "k actions from the goal by the estimate": one column, the
  *estimate* action (ground action ``n_ops``, which the env never applies), leading to
  chain row ``k - 1``; chain row 0 is a goal; and a **dead** row, no prior successor.

A pair whose prior successor is a state not reached yet (the frontier) leads, in the
prior, to the chain row ``h - 1`` for that state's estimate ``h`` of its goal distance
(:func:`~gdq_pddl.planning.heuristic.hadd_for`: h_add of the knowledge's relaxation;
the dead row where the relaxation cannot reach the goal), until the state is reached
and has its own row.

So GDQ's prior, DARLING's plan lengths and GDQ's warm start read estimates exactly as
they read shortest plans on an enumerated problem, without any change to their rules.
Distances of expanded states are one-step lookaheads over the estimates
(``d(s) = 1 + min d(s')``), fixed when the state is expanded.

A factored ground action (too many outcomes to list: IPPC-2008 sysadmin-slp's ``reboot``)
is stepped by drawing one outcome of each of its parts
(:meth:`~gdq_pddl.pddl.lazy.LazyGraph.draw`). What the learners see of it is what any
learner sees: the sampled steps, from which the model-based ones build their learned
model (its successor slots grow as a pair meets new next states). Its prior is the
knowledge's as for any action (the successor of the determinisation's outcomes closest
to the goal by the estimates, the parts' outcomes taken one at a time); on the problem's
own scale its prior reward is the most its outcomes can earn (each part's most, added
up); its chance of a dead end is 0 (not computed: it would need the product), but where
the state itself is one.

Rows never move; the arrays grow by doubling (a new *revision*: the learners resize);
each change logs the rows it touched (:attr:`OnlineInstance.log`), which the episode
loop hands to the learner (:class:`gdq_pddl.learners.online.Follower`). Unused rows are
inert goal rows.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import replace
from functools import cached_property
from typing import Any

import numpy as np

from gdq_pddl.abstraction import PlanTable
from gdq_pddl.abstraction.prior import NO_CHANGE, PriorModel, dead_chances, prior_rewards
from gdq_pddl.dynamics import CostDist, Dynamics
from gdq_pddl.envs.model import cost_arrays
from gdq_pddl.envs.one_state import RowMasks, one_state_model
from gdq_pddl.envs.pddl_checks import (
    MIN_STEP_LIMIT,
    STEP_LIMIT_FACTOR,
    check_step_rewards,
    limit_key,
)
from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLInstance, word_facts
from gdq_pddl.envs.solve import expected_costs
from gdq_pddl.envs.step import ModelArrays
from gdq_pddl.errors import ConfigError, PlanningError, SizeError, WorldError
from gdq_pddl.limits import MAX_TOLERANCE, check_real, human_bytes
from gdq_pddl.pddl.lazy import LazyGraph
from gdq_pddl.pddl.reachable import state_bytes, table_budget
from gdq_pddl.planning.base import length_bound
from gdq_pddl.planning.heuristic import INFINITE, hadd_for, hff_for, hmax_for

ESTIMATES = {"h_add": hadd_for, "h_FF": hff_for}
"""The distance estimates online exploration can read, by name."""

ESTIMATE = "(estimate)"
"""The name of the estimate action (ground action ``n_ops``: see the module docstring)."""

MAX_ESTIMATE_WEIGHT = 100.0
"""The largest ``estimate_weight``: a state not reached yet stands at most 100 x its
estimate from the goal (and no more chain rows than the table budget holds)."""

FIRST_ROWS = 1024
"""Rows allocated at first (doubled when full)."""

STEP_MODELS = 4096
"""The expanded states whose one-state true models :meth:`OnlineInstance.step_model`
keeps (building one takes about as long as the rest of a step)."""


class OnlineInstance:
    """A PPDDL problem (a :class:`PDDLInstance`'s files and settings) whose states are
    found as episodes reach them. One per run: the rows depend on what the run visits."""

    def __init__(self, base: PDDLInstance, darling_tolerance: float = 0.3,
                 dynamics: Dynamics | None = None, estimate: str | None = "h_add",
                 estimate_weight: float = 1.0) -> None:
        """``dynamics``: reality's constants (``r_max``, the step limit); None: the
        base's, with the default step limit by the estimate from the initial state.
        ``estimate``: the distance estimate of a state not reached yet, ``"h_add"`` (the
        default) or ``"h_FF"`` (:data:`ESTIMATES`; why h_add: ``docs/decisions.md``);
        None: no state is estimated (the prior and the plans know only the goal states),
        for a learner that reads no knowledge (Q-learning, Dyna-Q: the estimates were
        most of their time on large problems); the step limit is h_add's then.
        ``estimate_weight``: a state not reached yet stands ``ceil(w h)`` actions from
        the goal (the step limit and :attr:`h_start` read ``h`` itself)."""
        if estimate is not None and estimate not in ESTIMATES:
            raise ConfigError(f"estimate {estimate!r}: expected one of "
                              f"{', '.join(ESTIMATES)}, or None")
        check_real("estimate_weight", estimate_weight, 1.0, MAX_ESTIMATE_WEIGHT)
        check_real("darling_tolerance", darling_tolerance, 0.0, MAX_TOLERANCE)
        if not base.ppddl:
            raise PlanningError(f"{base.problem.source_domain.source}: online exploration "
                                "reads a PPDDL domain's own outcomes; a STRIPS domain with a "
                                "dynamics file has its states enumerated")
        self.base = base
        self.task = base.problem.learner_task
        self.own = base.reward_scale == "problem"
        self.graph = LazyGraph(self.task)  # with gains: costs inside effects, both scales
        self.heuristic = ESTIMATES[estimate or "h_add"](self.task)
        self.heuristic_name = estimate or "h_add"
        self.estimates = estimate is not None
        self.estimate_weight = float(estimate_weight)
        self.darling_tolerance = float(darling_tolerance)
        self.n_ops = len(self.task.ops)
        h0 = int(self.heuristic.many(self.graph.words[:1])[0])
        if h0 == INFINITE:
            raise PlanningError(_no_way(base))
        self.h_start = h0
        self.dynamics = _dynamics(base, h0) if dynamics is None else dynamics
        self._check_step_limit(h0)
        self._check_chain(h0)
        check_step_rewards(base.problem, base.costs, self.dynamics.r_max, self.own)
        self.costs = base.costs + [CostDist("const", 0.0 if self.own else 1.0)]
        self._cost_arrays = cost_arrays(self.costs)
        self.mean_cost = expected_costs(self.model)
        self.revision = 0
        self._step_models: dict[int, tuple[ModelArrays, np.ndarray]] = {}
        self.log: list[int] = []  # rows made (in order: what a row reads first)
        self.retargeted: list[int] = []  # rows whose prior successor found its own row
        self.waiting: dict[int, list[tuple[int, int]]] = {}
        self.n_rows = 0
        self.chain: list[int] = []
        self.row_of_state = np.full(FIRST_ROWS, -1, dtype=np.int64)
        self.h_of = np.full(FIRST_ROWS, INFINITE, dtype=np.int64)
        self._allocate(FIRST_ROWS, 1)
        self.dead = self._take_row()  # valued as a dead end: no prior successor
        self.goal[self.dead] = False
        self.log.append(self.dead)
        self._chain_row(0)
        self._found(np.array([0]))
        self._row(0)

    def _check_step_limit(self, h0: int) -> None:
        """Refuse, as the enumerated run does (:func:`~gdq_pddl.envs.pddl_checks.
        check_step_limit`), a step limit below h_max from the initial state, a lower bound
        on the knowledge's shortest plan (h_add and h_FF are never below h_max: only a
        limit below ``h0`` needs it computed)."""
        limit = self.dynamics.step_limit
        if limit >= h0:
            return
        bound = hmax_for(self.task)(self.graph.mask(0), self.task.goal_pos)
        if bound > limit:
            raise WorldError(*limit_key(self.base.problem, self.dynamics),
                             f"{limit} is less than the shortest plan of {self.source} (at "
                             f"least {bound} actions: h_max from the initial state, a lower "
                             "bound): no episode can reach the goal")

    def _check_chain(self, h0: int) -> None:
        """Refuse an ``estimate_weight`` whose chain rows for the initial state's estimate
        alone (``ceil(w h0)``, each as wide as the actions) pass the table budget."""
        rows = math.ceil(self.estimate_weight * h0)
        need = rows * state_bytes(self.n_ops + 1)
        if need > table_budget():
            raise ConfigError(f"estimate_weight {self.estimate_weight:g}: the initial state's "
                              f"estimate ({h0} actions) would stand {rows:,} chain rows from "
                              f"the goal, {human_bytes(need)} of tables, past the table "
                              f"budget of {human_bytes(table_budget())}; give a smaller "
                              "weight (1 reads the estimates as they are)")

    # -- what the learners' context reads (the Instance protocol of learners.context) -----
    name = property(lambda self: self.base.name)
    source = property(lambda self: self.base.source)
    ppddl = True
    reward_scale = property(lambda self: self.base.reward_scale)
    determinisation = property(lambda self: self.base.determinisation)
    n_states = property(lambda self: len(self.goal))  # rows allocated (tables, observations)
    n_actions = property(lambda self: self.n_ops + 1)  # the ground actions and the estimate
    learner_start = property(lambda self: int(self.row_of_state[0]))
    learner_goal = property(lambda self: self.goal)
    r_max = property(lambda self: float(self.dynamics.r_max))
    goal_pos = GOAL_POS

    def identity(self, rows: int | None = None) -> dict[str, str]:
        """What this instance is, as learner and policy files record it
        (:mod:`~gdq_pddl.envs.identity`): its problem's (:meth:`PDDLInstance.identity`),
        how it is explored, and the states its rows number now (a digest of each row's
        state, or of its estimate): another instance of the same files numbers the states
        its own episodes reached in their order. ``rows``: of its first ``rows`` rows
        only (rows never move: a policy taken earlier numbers a prefix of them)."""
        n = self.n_rows if rows is None else min(int(rows), self.n_rows)
        real = self.state_of_row[:n] >= 0
        digest = hashlib.sha256(np.packbits(real).tobytes())
        digest.update(np.ascontiguousarray(self.graph.words[self.state_of_row[:n][real]])
                      .tobytes())
        digest.update(np.ascontiguousarray(self.dist[:n][~real]).tobytes())
        estimate = "none" if not self.estimates else \
            f"{self.heuristic_name} x {self.estimate_weight:g}"
        return {**self.base.identity(), "explored": f"online (estimate {estimate})",
                "states": f"{n} rows sha256:{digest.hexdigest()}"}

    @property
    def successors_grow(self) -> bool:
        """Whether a ground action is factored: its pairs' next states are more than
        :attr:`max_successors` lists, and the learners make room as they meet them."""
        return bool(self.graph.factored.any())

    @property
    def max_successors(self) -> int:
        """Distinct next states a pair can have at most: its outcomes of probability > 0;
        of a factored ground action (too many to list), as many as its determinisation
        lists plus one, a start: a learner's model makes room for more as it meets them
        (:attr:`successors_grow`)."""
        return max([len(op.outcomes) + 1 if op.factored else
                    sum(o.probability > 0 for o in op.outcomes) for op in self.task.ops] + [1])

    @property
    def prior(self) -> PriorModel:
        return PriorModel(self.prior_next,
                          self._prior_dead if self.base.knows_dead_ends else None)

    @cached_property
    def model(self) -> ModelArrays:
        """The env's constants (costs, ``r_max``, the step limit) with no outcomes: each
        step reads the current state's (:meth:`step_model`)."""
        return ModelArrays(n_actions=self.n_actions, n_doors=0, r_max=self.r_max,
                           step_limit=int(self.dynamics.step_limit),
                           ptr=np.zeros(1, dtype=np.int64), prob=np.zeros(0),
                           next=np.zeros(0, dtype=np.int64), stuck=np.zeros(0, dtype=np.bool_),
                           **self._cost_arrays, obs_of=np.zeros(0, dtype=np.int64),
                           pos_of=np.zeros(0, dtype=np.int64),
                           area_of_pos=np.zeros(GOAL_POS + 1, dtype=np.int64),
                           own_scale=self.own)

    def plan_table(self, planner: str = "graph", tolerance: float = 0.0,
                   kind: str = "all") -> PlanTable:
        """The plans' first actions and lengths by the estimates (tolerance 0, or the
        DARLING tolerance this instance was made with); only the ``graph`` planner."""
        if planner != "graph":
            raise PlanningError(f"{self.source}: explored online, plans come from the "
                                f"heuristic's estimates, not a planner: use --planner graph "
                                f"(not {planner})")
        if tolerance and not math.isclose(tolerance, self.darling_tolerance):
            raise PlanningError(f"{self.source}: explored online with DARLING tolerance "
                                f"{self.darling_tolerance}, asked for {tolerance}")
        first = self.first_tolerant if tolerance else self.first_shortest
        return PlanTable(first, self.dist, _not_enumerated,
                         np.zeros((0, 3), dtype=np.int64))

    @property
    def prior_reward(self) -> np.ndarray | None:
        return self._prior_reward if self.own else None

    # -- the env's view ------------------------------------------------------------------
    def state_of(self, row: int) -> int:
        """The graph state of a row of a real state (-1: a chain or unused row)."""
        return int(self.state_of_row[row])

    def visit(self, x: int) -> int:
        """The row of graph state ``x``, which an episode reached: made, and ``x``
        expanded, on the first visit."""
        return self._row(x)

    def step_model(self, x: int) -> tuple[ModelArrays, np.ndarray]:
        """The true model of expanded state ``x`` alone (its row is full state 0, its
        successors 1, 2, ...) and the graph states of those full states; the last
        :data:`STEP_MODELS` made are kept."""
        hit = self._step_models.pop(x, None)
        if hit is None:
            hit = self._step_model(x)
            if len(self._step_models) >= STEP_MODELS:
                del self._step_models[next(iter(self._step_models))]
        self._step_models[x] = hit  # the most recently used last
        return hit

    def _step_model(self, x: int) -> tuple[ModelArrays, np.ndarray]:
        return one_state_model(self.graph, x, self._offered(x), self.model, self.own)

    def action_name(self, a: int) -> str:
        return ESTIMATE if a == self.n_ops else self.task.ops[a].name

    def state_name(self, row: int) -> str:
        x = self.state_of(row)
        if x < 0:
            return "(estimate: a dead end)" if row == self.dead else \
                f"(estimate: {self.dist[row]} actions to the goal)"
        return " ".join(sorted(self.graph.atoms(x)))

    def atoms(self, row: int) -> frozenset[str]:
        x = self.state_of(row)
        return frozenset() if x < 0 else self.graph.atoms(x)

    def goal_distance(self, row: int) -> int:
        """The plans' length from a row (:meth:`plan_table`'s ``length``): a reached
        state's one-step lookahead over the estimates, fixed when it was expanded (0 at a
        goal; -1: no successor the estimates reach the goal from)."""
        return int(self.dist[row])

    def plan_action(self, row: int) -> int:
        """The lowest ground action starting a shortest plan by the estimates from a row
        (the first of :meth:`plan_table`'s ``first_actions[row]``); -1 where none."""
        first = np.flatnonzero(self.first_shortest[row])
        return int(self.columns[row, first[0]]) if len(first) else -1

    atom_names = property(lambda self: self.task.facts)
    """The problem's fluent ground atoms, in the order of :meth:`facts`."""

    def facts(self, row: int) -> np.ndarray:
        """``int8[len(atom_names)]``: the fluent atoms true in a row's state (none: a
        chain or unused row)."""
        x = self.state_of(row)
        if x < 0:
            return np.zeros(len(self.task.facts), dtype=np.int8)
        return word_facts(self.graph.words[x], len(self.task.facts))

    @property
    def mask_table(self) -> RowMasks:
        return RowMasks(self)

    info = staticmethod(lambda pos: {})

    def restarted(self, start: Any = None, goal: None = None) -> OnlineInstance:
        if start is None and goal is None:
            return self
        raise ConfigError("reset options: a problem explored online starts at its initial "
                          "state (its states are not enumerated)")

    def optimal(self) -> dict[str, Any]:
        """What is known without enumerating: no V* (value iteration needs every state),
        a bound on it where one is cheap (:meth:`v_star_bound`), the estimate from the
        start."""
        bound, why = self.v_star_bound()
        return {"determinisation": self.determinisation, "r_max": self.dynamics.r_max,
                "reward_scale": self.reward_scale, "step_limit": self.dynamics.step_limit,
                "v_star": None, "v_star_note": "not computed: the problem was explored "
                f"online (its states are not enumerated, and value iteration needs them "
                f"all); {why}", "v_star_upper_bound": bound, "explored": "online",
                "estimate_from_start": self.h_start, "shortest_plan": None,
                "states": None, "actions": self.n_ops, "relevant_areas": [],
                "irrelevant_areas_paper": [], "expected_area_visits": {}}

    def v_star_bound(self) -> tuple[float | None, str]:
        """``(bound, what it is)``: an upper bound on V* from the start, or None and why
        there is none. No episode reaches the goal in fewer actions than h_max of the
        initial state (the delete relaxation's fewest actions, over every outcome of
        reality: a lower bound on the actions of any outcome sequence that reaches the
        goal), and each action before the goal's costs at least the least mean cost c:
        V* <= max(r_max - (h_max - 1) c, -r_max), and -r_max when h_max passes the step
        limit. Only with the ``all-outcomes`` determinisation (it leaves out only outcomes
        that change nothing or fail the trial; ``most-likely`` leaves out outcomes that
        may lead to the goal), and on the library's reward scale (on the problem's own, a
        step may pay)."""
        if self.own:
            return None, ("no cheap bound on V* on the problem's own reward scale (a step "
                          "may pay)")
        if self.determinisation != "all-outcomes":  # it leaves out only outcomes that
            # change nothing or fail the trial, which bring no goal nearer
            return None, (f"no cheap bound on V*: the {self.determinisation} "
                          "determinisation leaves some of reality's outcomes out of h_max")
        h = hmax_for(self.task)(self.task.init, self.task.goal_pos)
        r_max, limit = self.dynamics.r_max, self.dynamics.step_limit
        if h == INFINITE or h > limit:
            return -r_max, (f"V* <= {-r_max:g}: the goal needs at least {h} actions (h_max "
                            f"of the initial state), more than the step limit of {limit}"
                            if h != INFINITE else f"V* <= {-r_max:g}: no action sequence "
                            "reaches the goal even with deletes ignored")
        c = max(0.0, float(self.mean_cost[:self.n_ops].min())) if self.n_ops else 0.0
        bound = max(r_max - (h - 1) * c, -r_max)
        return bound, (f"V* <= {bound:g}: r_max {r_max:g} minus the least mean action cost "
                       f"{c:g} for each action before the goal's, of at least {h} actions "
                       "(h_max of the initial state, the delete relaxation over every "
                       "outcome of reality: no episode reaches the goal sooner)")

    # -- rows ----------------------------------------------------------------------------
    def _allocate(self, rows: int, width: int) -> None:
        """(Re)allocate every per-row array with ``rows`` rows and ``width`` columns,
        keeping what is there; unused rows are inert goal rows."""
        old = getattr(self, "columns", None)

        def grown(name: str, fill: Any, dtype: Any, two_d: bool = True) -> np.ndarray:
            # each element written once (the old block copied, the rest filled); zeros
            # from the allocator's zeroed pages, touched only when a row is used (rows
            # double, and a row is as wide as the ground actions: 1,800 on boxworld p05)
            shape = (rows, width) if two_d else (rows,)
            have = getattr(self, name) if old is not None else np.zeros((0,) * len(shape))
            out = np.zeros(shape, dtype=dtype) if not fill else np.empty(shape, dtype=dtype)
            out[tuple(slice(0, n) for n in have.shape)] = have
            if fill:
                out[have.shape[0]:] = fill
                if two_d:
                    out[:have.shape[0], have.shape[1]:] = fill
            return out

        self.columns = grown("columns", -1, np.int64)
        if old is None:
            self.columns[:, 0] = self.n_ops
        else:
            self.columns[len(old):, 0] = self.n_ops
        self.prior_next = grown("prior_next", NO_CHANGE, np.int64)
        self.first_shortest = grown("first_shortest", False, np.bool_)
        self.first_tolerant = grown("first_tolerant", False, np.bool_)
        self._prior_reward = grown("_prior_reward", 0.0, np.float64)
        self._prior_dead = grown("_prior_dead", 0.0, np.float64)
        self.goal = grown("goal", True, np.bool_, False)
        self.dist = grown("dist", -1, np.int64, False)
        self.state_of_row = grown("state_of_row", -1, np.int64, False)
        self.revision += 1

    def _room(self, rows: int, width: int) -> None:
        n, w = self.columns.shape
        if rows > n or width > w:
            self._allocate(max(n, 1 << max(0, rows - 1).bit_length()), max(w, width))

    def _chain_row(self, k: int) -> int:
        """The row "k actions from the goal by the estimate", made with those below it;
        SizeError up front if the rows still to make pass the table budget (a state found
        late whose weighted estimate is far larger than the initial state's)."""
        more = k + 1 - len(self.chain)
        if more > 0 and more * state_bytes(self.columns.shape[1]) > table_budget():
            raise SizeError(f"{self.source}: a state found online stands {k + 1:,} actions "
                            f"from the goal by the estimate ({self.heuristic_name} x "
                            f"{self.estimate_weight:g}): {more:,} more chain rows would pass "
                            f"the table budget of {human_bytes(table_budget())}; give a "
                            "smaller estimate_weight (1 reads the estimates as they are)")
        while len(self.chain) <= k:
            j = len(self.chain)
            r = self._take_row()
            self.goal[r] = j == 0
            self.dist[r] = j
            if j:
                self.prior_next[r, 0] = self.chain[j - 1]
                self.first_shortest[r, 0] = self.first_tolerant[r, 0] = True
            self.chain.append(r)
            self.log.append(r)
        return self.chain[k]

    def _take_row(self) -> int:
        self._room(self.n_rows + 1, 1)
        r = self.n_rows
        self.n_rows += 1
        return r

    def _found(self, states: np.ndarray) -> None:
        """Estimates of newly found graph states (0 at a goal)."""
        g = self.graph
        if len(self.row_of_state) < g.n_states:
            size = max(g.n_states, 2 * len(self.row_of_state))
            for name, fill in (("row_of_state", -1), ("h_of", INFINITE)):
                grown = np.full(size, fill, dtype=np.int64)
                old = getattr(self, name)
                grown[:len(old)] = old
                setattr(self, name, grown)
        live = states[~g.is_goal[states]]
        self.h_of[states[g.is_goal[states]]] = 0
        if len(live) and self.estimates:  # else left INFINITE: valued as dead ends
            h = self.heuristic.many(g.words[live])
            if self.estimate_weight != 1.0:
                h = np.where(h == INFINITE, h, np.ceil(self.estimate_weight * h)
                             .astype(np.int64))
            self.h_of[live] = h

    def _row(self, x: int) -> int:
        """The row of graph state ``x``, made (and ``x`` expanded) on first call: the
        pairs whose prior successor stood for ``x`` (its estimate) then lead to it."""
        r = int(self.row_of_state[x])
        if r >= 0:
            return r
        r = self._take_row()
        self.row_of_state[x] = r
        self.state_of_row[r] = x
        self.goal[r] = bool(self.graph.is_goal[x])
        self.dist[r] = 0
        self.log.append(r)
        if not self.goal[r]:
            new = self.graph.expand([x])
            if len(new):
                self._found(new)
            self._fill_expanded(x, r)
        for pr, pj in self.waiting.pop(x, ()):
            self.prior_next[pr, pj] = r
            self.retargeted.append(pr)
        return r

    def _targets(self, x: int, r: int, nxt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The prior successor row standing for each of ``nxt`` (the edges' next states of
        graph state ``x``, whose row is ``r``) and its distance: its own row, else the
        chain row of its estimate (the dead-end row, distance -1, where the relaxation
        cannot reach the goal); ``(r, -1)`` where it is ``x`` itself. The chain rows
        needed are made in the order the edges first ask for them."""
        to = np.full(len(nxt), r, dtype=np.int64)
        d_to = np.full(len(nxt), -1, dtype=np.int64)
        at = np.flatnonzero(nxt != x)
        ys = nxt[at]
        rows = self.row_of_state[ys]
        own = rows >= 0  # reached: its own row
        to[at[own]] = rows[own]
        d_to[at[own]] = self.dist[rows[own]]
        at, h = at[~own], self.h_of[ys[~own]]
        goal, dead = h == 0, h == INFINITE
        to[at[goal]], d_to[at[goal]] = self.chain[0], 0
        to[at[dead]] = self.dead
        chained = ~goal & ~dead
        if chained.any():
            h = h[chained]
            _, first = np.unique(h, return_index=True)
            for k in h[np.sort(first)].tolist():  # the chain rows, as edge order asks
                self._chain_row(k - 1)
            to[at[chained]] = np.asarray(self.chain, dtype=np.int64)[h - 1]
            d_to[at[chained]] = h
        return to, d_to

    def _offered(self, x: int) -> np.ndarray:
        offered = self.graph.offered(x)
        return offered if len(offered) else np.zeros(1, dtype=np.int64)  # a dead end

    def _fill_expanded(self, x: int, r: int) -> None:
        """Row ``r`` of graph state ``x``, just expanded: its applicable ground actions,
        each one's prior successor (of several outcomes the knowledge keeps, the one
        closest to the goal by the estimates, then the lowest graph state), the distance
        by one step of lookahead, the plans' first actions, the prior's rewards."""
        g = self.graph
        offered = self._offered(x)
        k = len(offered)
        op, nxt = g.edges(x)
        to, d_to = self._targets(x, r, nxt)  # may make chain rows: before the widening
        self._room(self.n_rows, k)
        col = np.searchsorted(offered, op)
        other = (nxt != x) & (d_to >= 0)
        d = int(1 + d_to[other].min()) if other.any() else -1
        self.dist[r] = d
        d_to = np.where(nxt == x, d, d_to)
        key = np.where(d_to < 0, np.iinfo(np.int64).max // 4,
                       d_to * (g.n_states + 1) + nxt)
        self.columns[r] = -1
        self.columns[r, :k] = offered
        # each column's edge of the least key, the first in edge order among equals (the
        # edges come by ground action: a column's are consecutive, its least key by one
        # reduction, where a loop over hundreds of columns cost most of an expansion)
        first = _first_least(col, key)
        self.prior_next[r, col[first]] = to[first]
        ys = nxt[first]
        wait = (self.row_of_state[ys] < 0) & ~g.is_goal[ys]  # their rows are not made yet
        for j, y in zip(col[first][wait].tolist(), ys[wait].tolist(), strict=True):
            self.waiting.setdefault(y, []).append((r, j))
        if d > 0:
            bound = length_bound(d, self.darling_tolerance)
            self.first_shortest[r, col[other & (1 + d_to == d)]] = True
            self.first_tolerant[r, col[other & (1 + d_to <= bound)]] = True
        m, states = self.step_model(x)
        drawn = np.flatnonzero(g.factored[offered]) if len(g.factored) else offered[:0]
        if self.base.knows_dead_ends:  # dead ends as the distances above say (-1)
            dead = np.isin(states, nxt[d_to < 0])
            dead[0] = d < 0  # x itself
            self._prior_dead[r, :k] = dead_chances(m.ptr, m.prob, m.next, dead)
            # a factored action's outcomes are not listed: no chance of a dead end is
            # known (0, optimistic as the prior's successor is), but where x is one
            self._prior_dead[r, drawn] = float(d < 0)
        if self.own:
            pair_cost = np.where(offered >= 0, self.mean_cost[offered], 0.0)[None, :]
            self._prior_reward[r, :k] = prior_rewards(m.ptr, m.stuck, m.gain, pair_cost)[0]
            for j in drawn.tolist():  # the parts' best gains add up
                self._prior_reward[r, j] = g.best_gain(x, int(offered[j])) - pair_cost[0, j]


def _first_least(group: np.ndarray, key: np.ndarray) -> np.ndarray:
    """The index of the first item of least ``key`` in each run of equal ``group``
    values (``group`` nondecreasing), by group: a run of one item is its own; the items
    of longer runs (boxworld's drives: 2 to 4 edges a column) are sorted by group, then
    key, stably (``ufunc.reduceat`` over 1,800 short runs cost more than the sort)."""
    n = len(group)
    if not n:
        return np.zeros(0, dtype=np.int64)
    lead = np.ones(n, dtype=np.bool_)
    lead[1:] = group[1:] != group[:-1]
    starts = np.flatnonzero(lead)
    long_run = np.diff(np.append(starts, n)) > 1
    if not long_run.any():
        return starts
    longer = np.flatnonzero(long_run)
    items = np.flatnonzero(long_run[np.cumsum(lead) - 1])
    order = items[np.lexsort((key[items], group[items]))]
    first = np.ones(len(order), dtype=np.bool_)
    first[1:] = group[order[1:]] != group[order[:-1]]
    out = starts.copy()
    out[longer] = order[first]
    return out


def _no_way(base: PDDLInstance) -> str:
    """Why the relaxation from the initial state never reaches the goal, as it is true of
    the determinisation the knowledge is (the relaxed actions are its outcomes)."""
    if base.determinisation == "most-likely":
        return (f"{base.source}: the most-likely determinisation (the knowledge: each "
                "action's most likely outcome) has no way to the goal from the initial "
                "state, even ignoring delete effects, so there is no estimate to explore "
                "online by (reality's less likely outcomes may still reach it); plan on "
                "every outcome (--determinisation all-outcomes)")
    return (f"{base.source}: the goal cannot be reached from the initial state by any "
            "outcome of positive probability, even ignoring every delete effect")


def _not_enumerated():
    raise ConfigError("a problem explored online has no enumerated plans (GDQ-literal and "
                      "GDQ-code walk plans: run the default GDQ, DARLING or Q-learning)")


def _dynamics(base: PDDLInstance, h0: int) -> Dynamics:
    """The problem's reality constants as :attr:`PDDLInstance.dynamics` gives them, but
    the default step limit ``max(20, ceil(2.5 h))`` by the estimate ``h`` from the
    initial state (no state is enumerated to count the fewest actions)."""
    overlay = base.overlay_with_r_max()
    if "step_limit" not in overlay.stated:
        overlay = replace(overlay, step_limit=max(MIN_STEP_LIMIT,
                                                  math.ceil(STEP_LIMIT_FACTOR * h0)))
    return overlay
