"""Breadth-first distances over a state graph (:class:`~gdq_pddl.pddl.reachable.StateGraph`,
its edges in CSR form): every state's fewest actions to the goal
(:func:`goal_distances`, backward) and from a start (:func:`distances_from`, forward),
a level at a time."""

from __future__ import annotations

import numpy as np


def distinct(a: np.ndarray) -> np.ndarray:
    """``np.unique(a)`` of an int array by a stable sort (np.unique's hashing takes
    minutes on 10**7 distinct keys)."""
    a = np.sort(a, kind="stable")
    return a[np.r_[True, a[1:] != a[:-1]]] if len(a) else a


def goal_distances(graph) -> np.ndarray:
    """Backward BFS from the goal states: shortest plan length of every state (-1: none)."""
    n = graph.n_states
    src = np.repeat(np.arange(n), np.diff(graph.edge_ptr))
    order = np.argsort(graph.edge_next, kind="stable")
    pred_ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(graph.edge_next, minlength=n), out=pred_ptr[1:])
    return breadth_first(pred_ptr, src[order], np.flatnonzero(graph.is_goal), n)


def distances_from(graph, start: int) -> np.ndarray:
    """Forward BFS from ``start``: the fewest edges to every state (-1: not reachable)."""
    return breadth_first(graph.edge_ptr, graph.edge_next, np.array([start], dtype=np.int64),
                         graph.n_states)


def breadth_first(ptr: np.ndarray, to: np.ndarray, frontier: np.ndarray,
                  n: int) -> np.ndarray:
    """The fewest edges from ``frontier`` to each of ``n`` states (-1: none) over the CSR
    edges ``ptr``, ``to`` (state ``v``'s are ``to[ptr[v]:ptr[v + 1]]``), a level at a time."""
    dist = np.full(n, -1, dtype=np.int64)
    dist[frontier] = 0
    d = 0
    while len(frontier):
        d += 1
        count = ptr[frontier + 1] - ptr[frontier]
        at = np.repeat(ptr[frontier] - np.cumsum(count) + count, count) + \
            np.arange(count.sum())  # the edges of every frontier state
        cand = distinct(to[at])
        cand = cand[dist[cand] < 0]
        dist[cand] = d
        frontier = cand
    return dist
