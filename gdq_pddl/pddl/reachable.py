"""The reachable state graph of a grounded task, and distances to its goal.

:func:`reachable_graph` enumerates, breadth first from the initial state, every state a
sequence of ground operators can reach, *without expanding goal states* (a plan ends
where the goal first holds, as in the ``graph`` planner). States are numbered in BFS
order (the initial state is 0); the edges of state ``i`` are ``(op index, next state)``
pairs, one per applicable operator, in the order of :attr:`GroundTask.ops`. For a PPDDL
task (:class:`~gdq_pddl.pddl.ppddl.ProbabilisticTask`) the states are those reality
reaches (every outcome of every action), numbered after the edges' states, and the edges
are the planner's knowledge: one per applicable ground action and outcome its
determinisation keeps, so a state may have several edges with one op.

:func:`goal_distances` is one backward BFS over that graph: every state's shortest
number of actions to the goal (-1: the goal cannot be reached from it). Together they
give every state's shortest plans without calling a planner once per state.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from tqdm import tqdm

from gdq_pddl.errors import PlanningError
from gdq_pddl.pddl.grounding import GroundTask


def slow_progress(desc: str, unit: str, total: int | None = None,
                  iterable: Iterable | None = None) -> tqdm:
    """A progress bar on stderr that shows only after 2 s, and only on a terminal
    (``TQDM_DISABLE=1`` silences it): state enumeration, models, value iteration."""
    return tqdm(iterable, total=total, desc=desc, unit=unit, delay=2.0, disable=None,
                leave=False)


MAX_STATES = 200_000
"""Default cap on the number of reachable states (beyond it, an error says so)."""


@dataclass(frozen=True, eq=False)
class StateGraph:
    """Reachable states (int bitmasks, BFS order) and their successor edges (CSR).

    The edges of state ``i`` are ``edge_op[edge_ptr[i]:edge_ptr[i + 1]]`` (index into
    ``task.ops``) and ``edge_next[...]`` (state index); goal states have none.
    """

    task: GroundTask
    states: tuple[int, ...]
    edge_ptr: np.ndarray
    edge_op: np.ndarray
    edge_next: np.ndarray
    is_goal: np.ndarray
    """bool[n_states]: the task's goal holds (such states are not expanded)."""

    @property
    def n_states(self) -> int:
        return len(self.states)

    @cached_property
    def index(self) -> dict[int, int]:
        """State bitmask -> state index."""
        return {s: i for i, s in enumerate(self.states)}

    @cached_property
    def op_index(self) -> dict[str, int]:
        """Ground operator name -> index in ``task.ops``."""
        return {op.name: i for i, op in enumerate(self.task.ops)}

    def edges(self, i: int) -> list[tuple[int, int]]:
        """``(op index, next state index)`` of every operator applicable in state ``i``."""
        lo, hi = self.edge_ptr[i], self.edge_ptr[i + 1]
        return list(zip(self.edge_op[lo:hi].tolist(), self.edge_next[lo:hi].tolist(),
                        strict=True))

    @cached_property
    def distances(self) -> np.ndarray:
        """int64[n_states]: shortest number of actions to a goal state (-1: unreachable)."""
        return goal_distances(self)


def reachable_graph(task: GroundTask, max_states: int = MAX_STATES,
                    source: str = "problem") -> StateGraph:
    """Every state reachable from ``task.init`` (goal states not expanded).

    Raises :class:`PlanningError` naming ``source`` when more than ``max_states`` states
    are reachable.
    """
    op_pos = {id(op): k for k, op in enumerate(task.ops)}
    index = {task.init: 0}
    states = [task.init]
    ptr, ops, nxt = [0], [], []
    goal = []
    queue = deque([task.init])
    bar = slow_progress("reachable states", " states")
    while queue:
        s = queue.popleft()
        bar.update()
        g = task.is_goal(s)
        goal.append(g)
        if not g:
            for op, t in sorted(task.successors(s), key=lambda e: op_pos[id(e[0])]):
                j = index.get(t)
                if j is None:
                    if len(states) >= max_states:
                        raise _too_many(source, max_states)
                    j = index[t] = len(states)
                    states.append(t)
                    queue.append(t)
                ops.append(op_pos[id(op)])
                nxt.append(j)
            for t in task.outcome_states(s):  # reality beyond the knowledge (PPDDL)
                if t not in index:
                    if len(states) >= max_states:
                        raise _too_many(source, max_states)
                    index[t] = len(states)
                    states.append(t)
                    queue.append(t)
        ptr.append(len(ops))
    bar.close()
    return StateGraph(task, tuple(states), np.array(ptr, dtype=np.int64),
                      np.array(ops, dtype=np.int64), np.array(nxt, dtype=np.int64),
                      np.array(goal, dtype=np.bool_))


def _too_many(source: str, max_states: int) -> PlanningError:
    return PlanningError(f"{source}: more than {max_states} reachable states; the learners "
                         "are tabular, so make the problem smaller (fewer objects)")


def goal_distances(graph: StateGraph) -> np.ndarray:
    """Backward BFS from the goal states: shortest plan length of every state (-1: none)."""
    n = graph.n_states
    src = np.repeat(np.arange(n), np.diff(graph.edge_ptr))
    order = np.argsort(graph.edge_next, kind="stable")
    pred_ptr = np.zeros(n + 1, dtype=np.int64)
    np.add.at(pred_ptr, graph.edge_next + 1, 1)
    pred_ptr = np.cumsum(pred_ptr)
    preds = src[order]
    dist = np.full(n, -1, dtype=np.int64)
    frontier = np.flatnonzero(graph.is_goal)
    dist[frontier] = 0
    d = 0
    while len(frontier):
        d += 1
        cand = np.concatenate([preds[pred_ptr[t]:pred_ptr[t + 1]] for t in frontier])
        cand = np.unique(cand)
        cand = cand[dist[cand] < 0]
        dist[cand] = d
        frontier = cand
    return dist
