"""h_max, the admissible and consistent delete-relaxation heuristic (Bonet & Geffner 2001),
compiled for a grounded task: with unit costs, a breadth-first search over facts."""

from __future__ import annotations

import weakref

import numba
import numpy as np

from gdq_pddl.pddl.grounding import GroundTask

INFINITE = -1
"""What :meth:`HMax.__call__` returns when the goal is unreachable even relaxed."""


def _bit_list(mask: int, n_facts: int) -> np.ndarray:
    """Indices of the set bits of a Python-int bitmask, as int64."""
    raw = np.frombuffer(mask.to_bytes((n_facts + 7) // 8 or 1, "little"), dtype=np.uint8)
    return np.flatnonzero(np.unpackbits(raw, bitorder="little")).astype(np.int64)


class HMax:
    """h_max of any state of one grounded task to a goal (positive facts only)."""

    def __init__(self, task: GroundTask) -> None:
        n_facts = len(task.facts)
        self.n_facts = n_facts
        pre_of = [[] for _ in range(n_facts)]
        n_pre = np.zeros(len(task.ops), dtype=np.int64)
        add_ptr = [0]
        add_idx: list[int] = []
        free: list[int] = []
        for i, op in enumerate(task.ops):
            pre = _bit_list(op.pre, n_facts)
            n_pre[i] = len(pre)
            for f in pre:
                pre_of[f].append(i)
            if not len(pre):
                free.append(i)
            add_idx += _bit_list(op.add, n_facts).tolist()
            add_ptr.append(len(add_idx))
        self.n_pre = n_pre
        self.pre_ptr = np.cumsum([0] + [len(x) for x in pre_of]).astype(np.int64)
        self.pre_ops = np.array([i for x in pre_of for i in x], dtype=np.int64)
        self.add_ptr = np.array(add_ptr, dtype=np.int64)
        self.add_idx = np.array(add_idx, dtype=np.int64)
        self.free = np.array(free, dtype=np.int64)
        self._goals: dict[int, np.ndarray] = {}

    def __call__(self, state: int, goal: int) -> int:
        """h_max of the bitmask ``state`` to the goal facts ``goal`` (:data:`INFINITE`: none)."""
        g = self._goals.get(goal)
        if g is None:
            g = self._goals[goal] = _bit_list(goal, self.n_facts)
        return int(_hmax(_bit_list(state, self.n_facts), g, self.n_facts, self.n_pre,
                         self.pre_ptr, self.pre_ops, self.add_ptr, self.add_idx, self.free))


@numba.njit(cache=True)
def _hmax(state: np.ndarray, goal: np.ndarray, n_facts: int, n_pre: np.ndarray,
          pre_ptr: np.ndarray, pre_ops: np.ndarray, add_ptr: np.ndarray, add_idx: np.ndarray,
          free: np.ndarray) -> int:
    cost = np.full(n_facts, -1, dtype=np.int64)
    queue = np.empty(n_facts, dtype=np.int64)
    head = tail = 0
    for f in state:
        cost[f] = 0
        queue[tail] = f
        tail += 1
    is_goal = np.zeros(n_facts, dtype=np.bool_)
    left = 0
    for f in goal:
        if not is_goal[f]:
            is_goal[f] = True
            if cost[f] < 0:
                left += 1
    if left == 0:
        return 0
    for i in free:  # operators without preconditions fire in layer 1
        for k in range(add_ptr[i], add_ptr[i + 1]):
            f = add_idx[k]
            if cost[f] < 0:
                cost[f] = 1
                queue[tail] = f
                tail += 1
                if is_goal[f]:
                    left -= 1
    if left == 0:
        return 1
    waiting = n_pre.copy()
    while head < tail:
        f = queue[head]
        head += 1
        c = cost[f] + 1
        for k in range(pre_ptr[f], pre_ptr[f + 1]):
            op = pre_ops[k]
            waiting[op] -= 1
            if waiting[op] == 0:
                for j in range(add_ptr[op], add_ptr[op + 1]):
                    g = add_idx[j]
                    if cost[g] < 0:
                        cost[g] = c
                        queue[tail] = g
                        tail += 1
                        if is_goal[g]:
                            left -= 1
                            if left == 0:
                                return c
    return -1


_CACHE: dict[int, tuple[weakref.ref, HMax]] = {}


def hmax_for(task: GroundTask) -> HMax:
    """The (cached) :class:`HMax` of ``task``."""
    hit = _CACHE.get(id(task))
    if hit is not None and hit[0]() is task:
        return hit[1]
    h = HMax(task)
    _CACHE[id(task)] = (weakref.ref(task), h)
    return h
