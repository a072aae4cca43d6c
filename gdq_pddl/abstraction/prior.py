"""The action knowledge as a deterministic model over learner (state, action) pairs:
GDQ's *prior model*, where each learner action leads if the knowledge is right, or "no
change" where the knowledge says it does nothing (optimistic: PDDL has no failures or
costs). Where the knowledge is a PPDDL domain, the prior also keeps each pair's chance of
an outcome from which the goal cannot be reached (:func:`dead_chances`): the one thing
its optimism does not gamble on."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace

import numba
import numpy as np

from gdq_pddl.errors import AbstractionError
from gdq_pddl.pddl.distances import breadth_first, distances_from
from gdq_pddl.pddl.offered import column_of

NO_CHANGE = -1
"""``PriorModel.next_state`` of a knowledge-inapplicable pair."""


@dataclass(frozen=True, eq=False)
class PriorModel:
    """Where each learner action leads in each learner state, according to the knowledge."""

    next_state: np.ndarray
    """int64[n_states, n_actions]: the learner state ``a`` leads to from ``s`` if the
    knowledge is right, or :data:`NO_CHANGE` where the knowledge says ``a`` does nothing.
    A PDDL problem's is over the columns of its states' applicable ground actions
    (:func:`prior_from_graph`), where a padding column is NO_CHANGE."""

    dead: np.ndarray | None = None
    """float64[n_states, n_actions] or None: the knowledge's probability that the pair
    ends in a *dead end*, a state from which the goal cannot be reached (or not within
    the step limit: :func:`dead_end_states`; 1 where every outcome is one: the prior
    successor is one then too). None: the knowledge never says
    so (a deterministic one: the office, a STRIPS domain). ``docs/decisions.md``, "the
    prior does not gamble on dead ends"."""

    @property
    def n_states(self) -> int:
        return int(self.next_state.shape[0])

    def rows(self, rows: np.ndarray) -> PriorModel:
        """The prior of the learner states ``rows`` alone (in that order)."""
        return PriorModel(self.next_state[rows],
                          None if self.dead is None else self.dead[rows])

    @property
    def n_actions(self) -> int:
        return int(self.next_state.shape[1])

    @property
    def applicable(self) -> np.ndarray:
        """bool[n_states, n_actions]: the knowledge says the action can do something."""
        return self.next_state != NO_CHANGE

    def predecessors(self) -> tuple[np.ndarray, np.ndarray]:
        """``(ptr, pairs)``: the applicable pairs ``s * n_actions + a`` whose prior successor
        is ``x`` are ``pairs[ptr[x]:ptr[x + 1]]``, in increasing pair order."""
        flat = self.next_state.ravel()
        pairs = np.flatnonzero(flat != NO_CHANGE)
        succ = flat[pairs]
        order = np.argsort(succ, kind="stable")
        ptr = np.zeros(self.n_states + 1, dtype=np.int64)
        np.add.at(ptr, succ + 1, 1)
        return np.cumsum(ptr), pairs[order].astype(np.int64)


def prior_distances(prior: PriorModel, goal: np.ndarray) -> np.ndarray:
    """int64[n_states]: the fewest actions from each learner state to one where ``goal``
    (bool[n_states]) holds if the knowledge is right: backward breadth first over the
    prior's pairs (0 at a goal state; -1: the knowledge reaches no goal state from there).
    Of a PDDL problem's prior (:func:`prior_from_graph`) these are the graph's
    :attr:`~gdq_pddl.pddl.reachable.StateGraph.distances`."""
    ptr, pairs = prior.predecessors()
    return breadth_first(ptr, pairs // max(prior.n_actions, 1),
                         np.flatnonzero(goal).astype(np.int64), prior.n_states)


def first_plan_columns(prior: PriorModel, distance: np.ndarray) -> np.ndarray:
    """int64[n_states]: in each learner state ``s``, the lowest column whose prior
    successor is one action closer to the goal by ``distance`` (the first action of a
    shortest plan of the knowledge); -1 at a goal state (distance 0) and where there is
    no plan (distance -1)."""
    nxt = prior.next_state
    d = np.asarray(distance, dtype=np.int64)
    to = np.where(nxt == NO_CHANGE, -1, d[np.where(nxt == NO_CHANGE, 0, nxt)])
    closer = (nxt != NO_CHANGE) & (to == (d - 1)[:, None]) & (d > 0)[:, None]
    return np.where(closer.any(axis=1), closer.argmax(axis=1), -1).astype(np.int64)


def prior_from_edges(n_states: int, n_actions: int,
                     edges: Iterable[tuple[int, str, int, int]]) -> PriorModel:
    """The prior of ``(state, ground action name, action, next state)`` edges;
    AbstractionError where two of one state and action lead to different states."""
    nxt = np.full((n_states, n_actions), NO_CHANGE, dtype=np.int64)
    names: dict[tuple[int, int], str] = {}
    for s, name, a, s2 in edges:
        here = nxt[s, a]
        if here != NO_CHANGE and here != s2:
            raise AbstractionError(
                f"ground actions {names[s, a]} and {name} both map to learner action {a} in "
                f"learner state {s} but lead to different learner states ({here}, {s2}): "
                "O must map the planner's actions one to one in every state")
        nxt[s, a] = s2
        names[s, a] = name
    return PriorModel(nxt)


def prior_from_task(abstraction, task, read_state: Callable[[int], int] | None = None
                    ) -> PriorModel:
    """The prior of an abstraction over a grounded task: every ground action applicable
    in each learner state's planner state (atoms the task cannot reach left out), mapped
    through O; ``read_state`` maps a state bitmask to a learner state."""
    if read_state is None:
        def read_state(mask: int) -> int:
            return abstraction.learner_state(task.atoms(mask))

    def edges():
        for s in range(abstraction.n_states):
            atoms = abstraction.planner_state(s)
            mask = task.mask({x for x in atoms if x in task.fact_index})
            for op, nxt in task.successors(mask):
                yield s, op.name, abstraction.learner_action(op.name), read_state(nxt)

    return prior_from_edges(abstraction.n_states, abstraction.n_actions, edges())


def prior_from_graph(graph) -> PriorModel:
    """The prior of a PDDL problem whose learner states are the reachable planner states
    (O the identity), over the columns of ``graph.offered``: the graph's edges; of
    several outcomes of one action (a PPDDL determinisation), the one closest to the goal
    (ties: the lowest state index)."""
    nxt = np.full(graph.offered.shape, NO_CHANGE, dtype=np.int64)
    n = graph.n_states
    op, to = graph.edge_op, graph.edge_next
    if not len(op):
        return PriorModel(nxt)
    src = np.repeat(np.arange(n), np.diff(graph.edge_ptr))
    pair = src * (int(op.max(initial=0)) + 1) + op
    if (pair[1:] < pair[:-1]).any():  # the graph lists a state's edges by action
        order = np.argsort(pair, kind="stable")
        pair, src, op, to = pair[order], src[order], op[order], to[order]
        del order
    first = np.flatnonzero(np.r_[True, pair[1:] != pair[:-1]])
    del pair  # each array dropped once read: edges are most of the graph's memory
    src, op = src[first], op[first]
    dist = np.where(graph.distances < 0, n + 1, graph.distances)  # unreachable: farthest
    key = dist[to]
    del dist
    key *= n + 2
    key += to  # closest to the goal, then the lowest state index
    best = np.minimum.reduceat(key, first)
    del key, first
    best %= n + 2
    nxt[src, column_of(graph.offered, src, op)] = best
    return PriorModel(nxt)


def dead_end_states(graph, start: int, step_limit: int) -> np.ndarray:
    """bool[n_states]: the states of a state graph (a PPDDL problem known by all its
    outcomes) that no episode from ``start`` can pass through on its way to the goal:
    those that cannot reach the goal, and those whose fewest actions from ``start`` and
    fewest to the goal add up to more than the ``step_limit`` (every episode through one
    runs out of steps first; both counts are the knowledge's, lower bounds on reality's).
    Goals are never dead ends."""
    dist = graph.distances
    dead = dist < 0
    if step_limit >= 2 * graph.n_states:  # no two paths add up to that: nothing runs out
        return dead
    came = distances_from(graph, start)
    dead |= (came >= 0) & (dist > 0) & (came + dist > step_limit)
    return dead


@numba.njit(cache=True)
def dead_chances(ptr: np.ndarray, prob: np.ndarray, nxt: np.ndarray,
                 dead_state: np.ndarray) -> np.ndarray:
    """float64[n_pairs]: :attr:`PriorModel.dead` of the pairs of a model in CSR form
    (outcomes of pair ``i`` are ``ptr[i]:ptr[i + 1]``, with probabilities ``prob`` and
    next states ``nxt``): the probability of the outcomes whose next state is a dead end
    (``dead_state``, bool by state); 1 where every outcome is one, 0 where there is none."""
    out = np.zeros(len(ptr) - 1)  # a loop: no array per outcome (a model has tens of millions)
    for i in range(len(ptr) - 1):
        chance, live = 0.0, False
        for k in range(ptr[i], ptr[i + 1]):
            if dead_state[nxt[k]]:
                chance += prob[k]
            else:
                live = True
        if ptr[i + 1] > ptr[i]:
            out[i] = min(chance, 1.0) if live else 1.0
    return out


def with_dead_chances(prior: PriorModel, ptr: np.ndarray, prob: np.ndarray, nxt: np.ndarray,
                      dead_state: np.ndarray) -> PriorModel:
    """``prior`` with :func:`dead_chances` of a model whose pairs are the prior's, state
    by state (``ptr`` has a pair per prior entry); unchanged where no pair can end in a
    dead end."""
    if len(ptr) != prior.next_state.size + 1:
        raise AbstractionError(f"a model of {len(ptr) - 1} pairs gives no chances for a "
                               f"prior of {prior.n_states} x {prior.n_actions}")
    if not dead_state.any():
        return prior
    dead = dead_chances(ptr, prob, nxt, dead_state)
    if not dead.any():
        return prior
    return replace(prior, dead=dead.reshape(prior.next_state.shape))


@numba.njit(cache=True)
def prior_rewards(ptr: np.ndarray, stuck: np.ndarray, gain: np.ndarray,
                  pair_cost: np.ndarray) -> np.ndarray:
    """float64[n_states, n_actions]: the most a trial of each pair can pay, on a problem's
    own reward scale, where learner states are full states (a PDDL problem): the largest
    ``gain`` of its outcomes that do not end stuck (of all, where every one does), less
    the action's mean cost ``pair_cost`` (float64[n_states, n_actions]); 0 for a pair
    with no outcome (a padding column). Optimistic, as the prior's successor is (the
    outcome closest to the goal, which may be the one that pays least: the death of the
    human to rescue in IPPC-2008 search and rescue ends the mission sooner).
    ``ptr``, ``stuck``, ``gain``: a :class:`~gdq_pddl.envs.step.ModelArrays`'."""
    n_states, n_actions = pair_cost.shape
    out = np.zeros((n_states, n_actions))
    for i in range(n_states * n_actions):
        if ptr[i] == ptr[i + 1]:
            continue
        best, any_best = -np.inf, -np.inf  # of the outcomes not stuck, of all
        for k in range(ptr[i], ptr[i + 1]):
            any_best = max(any_best, gain[k])
            if not stuck[k]:
                best = max(best, gain[k])
        s, a = i // n_actions, i % n_actions
        out[s, a] = (best if best > -np.inf else any_best) - pair_cost[s, a]
    return out
