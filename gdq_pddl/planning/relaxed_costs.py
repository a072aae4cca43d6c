"""The compiled kernels of :mod:`gdq_pddl.planning.heuristic`'s h_add and h_FF: a
generalized Dijkstra over facts that gives every fact its h_add cost and its best
supporter (:func:`hadd_costs`), and the relaxed plan those supporters make
(:func:`relaxed_plan_size`, Hoffmann & Nebel 2001)."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def push(heap: np.ndarray, size: int, key: int) -> int:
    """Push ``key`` onto the binary min-heap ``heap[:size]``; the new size."""
    i = size
    heap[i] = key
    while i > 0:
        parent = (i - 1) >> 1
        if heap[parent] <= key:
            break
        heap[i] = heap[parent]
        i = parent
    heap[i] = key
    return size + 1


@numba.njit(cache=True)
def pop(heap: np.ndarray, size: int) -> int:
    """Remove the least key, ``heap[0]`` (the caller reads it first), from the binary
    min-heap ``heap[:size]``; the new size."""
    size -= 1
    last = heap[size]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= size:
            break
        if child + 1 < size and heap[child + 1] < heap[child]:
            child += 1
        if heap[child] >= last:
            break
        heap[i] = heap[child]
        i = child
    if size > 0:
        heap[i] = last
    return size


@numba.njit(cache=True)
def hadd_costs(state: np.ndarray, relevant: np.ndarray, n_facts: int, n_pre: np.ndarray,
               pre_ptr: np.ndarray, pre_ops: np.ndarray, add_ptr: np.ndarray,
               add_idx: np.ndarray, free: np.ndarray, heap_size: int, cap: int,
               cost: np.ndarray, sup: np.ndarray) -> None:
    """Fill ``cost`` (int64 max: unreached) with each fact's h_add cost from the facts
    ``state`` and ``sup`` with the relaxed action that last lowered it (-1: none), until
    every ``relevant`` fact is final (:class:`HAdd`): the supporters of a final fact and
    of its supporter's preconditions are final too."""
    big = np.iinfo(np.int64).max
    cost[:] = big
    sup[:] = -1
    done = np.zeros(n_facts, dtype=np.bool_)
    heap = np.empty(heap_size, dtype=np.int64)  # keys cost * n_facts + fact
    size = 0
    for f in state:
        if cost[f] != 0:
            cost[f] = 0
            size = push(heap, size, f)
    left = 0
    for f in range(n_facts):
        if relevant[f] and cost[f] != 0:
            left += 1
    if left == 0:
        return
    for i in free:  # relaxed actions without preconditions: cost 1
        for k in range(add_ptr[i], add_ptr[i + 1]):
            g = add_idx[k]
            if cost[g] > 1:
                cost[g] = 1
                sup[g] = i
                size = push(heap, size, n_facts + g)
    acc = np.zeros(len(n_pre), dtype=np.int64)
    waiting = n_pre.copy()
    while size > 0 and left > 0:
        key = heap[0]
        size = pop(heap, size)
        f = key % n_facts
        if done[f]:
            continue
        done[f] = True
        c = key // n_facts
        if relevant[f] and c > 0:
            left -= 1
        for k in range(pre_ptr[f], pre_ptr[f + 1]):
            op = pre_ops[k]
            acc[op] += c
            waiting[op] -= 1
            if waiting[op] == 0:
                ca = min(acc[op] + 1, cap)
                for j in range(add_ptr[op], add_ptr[op + 1]):
                    g = add_idx[j]
                    if ca < cost[g]:
                        cost[g] = ca
                        sup[g] = op
                        size = push(heap, size, ca * n_facts + g)


@numba.njit(cache=True)
def cheapest_alternative(cost: np.ndarray, alt_ptr: np.ndarray, alt_idx: np.ndarray) -> int:
    """The goal alternative whose facts cost least in sum (-1: every one unreachable, or
    there are none)."""
    big = np.iinfo(np.int64).max
    best, which = big, -1
    for a in range(len(alt_ptr) - 1):
        s = 0
        for k in range(alt_ptr[a], alt_ptr[a + 1]):
            if cost[alt_idx[k]] == big:
                s = big
                break
            s += cost[alt_idx[k]]
        if s < best:
            best, which = s, a
    return which


@numba.njit(cache=True)
def relaxed_plan_size(cost: np.ndarray, sup: np.ndarray, goal: np.ndarray,
                      alt_ptr: np.ndarray, alt_idx: np.ndarray, op_pre_ptr: np.ndarray,
                      op_pre_idx: np.ndarray) -> int:
    """h_FF: the number of distinct relaxed actions in the plan that supports each goal
    fact (and the facts of the cheapest goal alternative) by its best supporter ``sup``,
    and each precondition of a chosen action the same way, back to facts of cost 0
    (``cost``/``sup`` of :func:`hadd_costs`); -1 where a goal fact is unreached."""
    big = np.iinfo(np.int64).max
    n_facts = len(cost)
    marked = np.zeros(n_facts, dtype=np.bool_)
    used = np.zeros(len(op_pre_ptr) - 1, dtype=np.bool_)
    stack = np.empty(len(op_pre_idx) + len(goal) + len(alt_idx) + 1, dtype=np.int64)
    top = 0
    for f in goal:
        if cost[f] == big:
            return -1
        stack[top] = f
        top += 1
    if len(alt_ptr) > 1:
        a = cheapest_alternative(cost, alt_ptr, alt_idx)
        if a < 0:
            return -1
        for k in range(alt_ptr[a], alt_ptr[a + 1]):
            stack[top] = alt_idx[k]
            top += 1
    size = 0
    while top > 0:
        top -= 1
        f = stack[top]
        if marked[f] or cost[f] == 0:
            continue
        marked[f] = True
        op = sup[f]
        if used[op]:
            continue
        used[op] = True
        size += 1
        for k in range(op_pre_ptr[op], op_pre_ptr[op + 1]):
            p = op_pre_idx[k]
            if not marked[p] and cost[p] > 0:
                stack[top] = p
                top += 1
    return size
