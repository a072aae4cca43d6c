"""Delete-relaxation heuristics (Bonet & Geffner 2001) of a grounded task, with unit
action costs, compiled: h_max (:class:`HMax`, admissible and consistent: a breadth-first
search over facts) and h_add (:class:`HAdd`, not admissible, but it sums the costs of all
the goal facts where h_max takes the dearest: a generalized Dijkstra over facts).

Both read the same *relaxed actions* of the task (:func:`relaxed_actions`): positive
preconditions and adds only. A plain :class:`~gdq_pddl.pddl.grounding.GroundOp` is one;
a :class:`~gdq_pddl.pddl.ppddl.ProbabilisticOp` (reality's ground action of a PPDDL
problem) gives one per outcome the planner knows (``op.known``) and per conditional
effect of such an outcome, times each alternative of a disjunctive precondition: a
:class:`~gdq_pddl.pddl.ppddl.ProbabilisticTask` is relaxed as the planner's
determinisation of it (the same values where no action has a conditional effect; where
one has, each conditional effect is its own relaxed action, while the determinisation's
STRIPS variants join them, so its values are never lower). Every state is a Python-int
bitmask over ``task.facts`` (or, for :meth:`HAdd.many`, a row of uint64 words, as
:mod:`gdq_pddl.pddl.wordrows`).
"""

from __future__ import annotations

import weakref

import numba
import numpy as np

from gdq_pddl.pddl.grounding import GroundTask
from gdq_pddl.pddl.ppddl import ProbabilisticOp

INFINITE = -1
"""What :meth:`HMax.__call__` and :class:`HAdd` return when the goal is unreachable even
relaxed."""


def _bit_list(mask: int, n_facts: int) -> np.ndarray:
    """Indices of the set bits of a Python-int bitmask, as int64."""
    raw = np.frombuffer(mask.to_bytes((n_facts + 7) // 8 or 1, "little"), dtype=np.uint8)
    return np.flatnonzero(np.unpackbits(raw, bitorder="little")).astype(np.int64)


def relaxed_actions(task: GroundTask) -> list[tuple[int, int]]:
    """The relaxed actions ``(positive preconditions, adds)`` of ``task``'s ground actions
    (negative preconditions and deletes ignored), in the order of ``task.ops``, those that
    add nothing left out and each distinct pair once.

    A plain ground action is ``(pre, add)``. A :class:`ProbabilisticOp` gives, for each
    alternative ``(must hold, must not hold)`` of its precondition (``op.alternatives``;
    none: ``(pre, neg)`` alone) and each outcome the planner knows (``op.known``, what
    its determinisation keeps: reality's other outcomes are no knowledge to plan with),
    ``(pre | alternative, outcome.add)``, and for each conditional effect ``(cp, cn, a,
    d)`` of that outcome ``(pre | alternative | cp, a)`` -- but for a conditional effect
    whose condition contradicts that alternative (a fact both required and excluded),
    which can never fire there (the planner's determinisation drops it too).
    """
    out: dict[tuple[int, int], None] = {}
    for op in task.ops:
        if not isinstance(op, ProbabilisticOp):
            out[(op.pre, op.add)] = None
            continue
        for p, n in op.alternatives or ((op.pre, op.neg),):
            p, n = p | op.pre, n | op.neg
            for k in op.known:
                outcome = op.outcomes[k]
                out[(p, outcome.add)] = None
                for cp, cn, a, _ in outcome.conditional:
                    if not (p | cp) & (n | cn):
                        out[(p | cp, a)] = None
    return [(pre, add) for pre, add in out if add]


class _Compiled:
    """A task's relaxed actions as flat arrays: for each action its number of
    precondition facts (``n_pre``) and its adds (``add_idx[add_ptr[i]:add_ptr[i + 1]]``),
    for each fact the actions it is a precondition of (``pre_ops[pre_ptr[f]:...]``), and
    the actions without preconditions (``free``)."""

    def __init__(self, task: GroundTask) -> None:
        n_facts = len(task.facts)
        actions = relaxed_actions(task)
        self.n_facts = n_facts
        pre_of: list[list[int]] = [[] for _ in range(n_facts)]
        n_pre = np.zeros(len(actions), dtype=np.int64)
        add_ptr = [0]
        add_idx: list[int] = []
        free: list[int] = []
        for i, (pre_mask, add_mask) in enumerate(actions):
            pre = _bit_list(pre_mask, n_facts)
            n_pre[i] = len(pre)
            for f in pre.tolist():
                pre_of[f].append(i)
            if not len(pre):
                free.append(i)
            add_idx += _bit_list(add_mask, n_facts).tolist()
            add_ptr.append(len(add_idx))
        self.n_actions = len(actions)
        self.n_pre = n_pre
        self.pre_ptr = np.cumsum([0] + [len(x) for x in pre_of]).astype(np.int64)
        self.pre_ops = np.array([i for x in pre_of for i in x], dtype=np.int64)
        self.add_ptr = np.array(add_ptr, dtype=np.int64)
        self.add_idx = np.array(add_idx, dtype=np.int64)
        self.free = np.array(free, dtype=np.int64)


class HMax:
    """h_max of any state of one grounded task to a goal (positive facts only), over the
    task's :func:`relaxed_actions`."""

    def __init__(self, task: GroundTask) -> None:
        c = _Compiled(task)
        self.n_facts = c.n_facts
        self.n_pre, self.pre_ptr, self.pre_ops = c.n_pre, c.pre_ptr, c.pre_ops
        self.add_ptr, self.add_idx, self.free = c.add_ptr, c.add_idx, c.free
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


class HAdd:
    """h_add of any state of one grounded task (GroundTask or ProbabilisticTask) to its goal.

    With unit action costs, ``c(f) = 0`` for a fact ``f`` of the state, else the least
    ``1 + sum of c(p) over the preconditions p`` of a relaxed action adding ``f``
    (:func:`relaxed_actions`: negative conditions and deletes ignored; a PPDDL action's
    outcomes the planner knows and their conditional effects, per alternative of a
    disjunctive precondition). h_add is the sum of ``c`` over the positive goal facts
    ``task.goal_pos``; a goal with alternatives (``task.goal_alternatives``, one of which
    must hold besides ``goal_pos``) adds the least sum of ``c`` over an alternative's
    positive facts not in ``goal_pos`` (the additive reading of a disjunction: its
    cheapest disjunct). Negative goal facts are ignored. :data:`INFINITE` (-1) where the
    goal is unreachable even relaxed, or ``task.goal_possible`` is False; 0 exactly where
    the relaxed goal (its positive facts) holds. Unlike h_max it counts each goal fact's
    own cost, so it tells apart states that h_max finds equally far, which is what an
    estimate of the distance of a state never expanded needs (not admissible, so no
    bound for an optimal plan search).

    Computed by a compiled generalized Dijkstra over facts (a fact's cost is final when it
    leaves the heap; an action fires once all its preconditions are final), stopped once
    every goal fact is final. A fact's cost saturates at ``2**62 // n_facts`` (the heap's
    keys are ``cost * n_facts + fact``), which only costs that double along a chain of
    actions reach.
    """

    def __init__(self, task: GroundTask) -> None:
        c = _Compiled(task)
        self.n_facts = n = c.n_facts
        self._c = c
        self.possible = bool(task.goal_possible)
        goal = _bit_list(task.goal_pos, n)
        alts = [_bit_list(p & ~task.goal_pos, n) for p, _ in task.goal_alternatives]
        self.goal = goal
        self.alt_ptr = np.cumsum([0] + [len(a) for a in alts]).astype(np.int64)
        self.alt_idx = np.concatenate(alts) if alts else np.zeros(0, dtype=np.int64)
        relevant = np.zeros(n, dtype=np.bool_)
        relevant[goal] = True
        relevant[self.alt_idx] = True
        self.relevant = relevant
        self._heap_size = n + len(c.add_idx) + 1  # the most pushes one state makes
        # the most a fact's cost counts: heap keys are cost * n_facts + fact, and sums of
        # up to n_facts costs stay in int64; reached only where costs double along a
        # chain of actions, far past any plan length
        self.cap = (1 << 62) // max(n, 1) - 1

    def __call__(self, state: int) -> int:
        """h_add of the bitmask ``state`` to the task's goal (:data:`INFINITE`: none)."""
        if not self.possible:
            return INFINITE
        c = self._c
        return int(_hadd(_bit_list(state, self.n_facts), self.goal, self.alt_ptr, self.alt_idx,
                         self.relevant, self.n_facts, c.n_pre, c.pre_ptr, c.pre_ops,
                         c.add_ptr, c.add_idx, c.free, self._heap_size, self.cap))

    def many(self, words: np.ndarray) -> np.ndarray:
        """int64 h_add of each row of uint64 words ``words[n, n_words]`` (fact ``f``: bit
        ``f % 64`` of word ``f // 64``; bits past the task's facts ignored), -1 where
        unreachable."""
        rows = np.ascontiguousarray(words, dtype=np.uint64)
        if rows.ndim != 2:
            raise ValueError(f"HAdd.many takes a 2-d array of word rows, not shape {rows.shape}")
        if not self.possible:
            return np.full(len(rows), INFINITE, dtype=np.int64)
        c = self._c
        return _hadd_rows(rows, self.goal, self.alt_ptr, self.alt_idx, self.relevant,
                          self.n_facts, c.n_pre, c.pre_ptr, c.pre_ops, c.add_ptr, c.add_idx,
                          c.free, self._heap_size, self.cap)


@numba.njit(cache=True)
def _push(heap: np.ndarray, size: int, key: int) -> int:
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
def _pop(heap: np.ndarray, size: int) -> int:
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
def _hadd(state: np.ndarray, goal: np.ndarray, alt_ptr: np.ndarray, alt_idx: np.ndarray,
          relevant: np.ndarray, n_facts: int, n_pre: np.ndarray, pre_ptr: np.ndarray,
          pre_ops: np.ndarray, add_ptr: np.ndarray, add_idx: np.ndarray, free: np.ndarray,
          heap_size: int, cap: int) -> int:
    big = np.iinfo(np.int64).max
    cost = np.full(n_facts, big, dtype=np.int64)
    done = np.zeros(n_facts, dtype=np.bool_)
    heap = np.empty(heap_size, dtype=np.int64)  # keys cost * n_facts + fact
    size = 0
    for f in state:
        if cost[f] != 0:
            cost[f] = 0
            size = _push(heap, size, f)
    left = 0
    for f in range(n_facts):
        if relevant[f] and cost[f] != 0:
            left += 1
    if left > 0:
        for i in free:  # relaxed actions without preconditions: cost 1
            for k in range(add_ptr[i], add_ptr[i + 1]):
                g = add_idx[k]
                if cost[g] > 1:
                    cost[g] = 1
                    size = _push(heap, size, n_facts + g)
        acc = np.zeros(len(n_pre), dtype=np.int64)
        waiting = n_pre.copy()
        while size > 0 and left > 0:
            key = heap[0]
            size = _pop(heap, size)
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
                            size = _push(heap, size, ca * n_facts + g)
    total = 0
    for f in goal:
        if cost[f] == big:
            return -1
        total += cost[f]
    n_alts = len(alt_ptr) - 1
    if n_alts > 0:
        best = big
        for a in range(n_alts):
            s = 0
            for k in range(alt_ptr[a], alt_ptr[a + 1]):
                if cost[alt_idx[k]] == big:
                    s = big
                    break
                s += cost[alt_idx[k]]
            if s < best:
                best = s
        if best == big:
            return -1
        total += best
    return total


@numba.njit(cache=True)
def _hadd_rows(rows: np.ndarray, goal: np.ndarray, alt_ptr: np.ndarray, alt_idx: np.ndarray,
               relevant: np.ndarray, n_facts: int, n_pre: np.ndarray, pre_ptr: np.ndarray,
               pre_ops: np.ndarray, add_ptr: np.ndarray, add_idx: np.ndarray,
               free: np.ndarray, heap_size: int, cap: int) -> np.ndarray:
    out = np.empty(rows.shape[0], dtype=np.int64)
    state = np.empty(n_facts, dtype=np.int64)
    one = np.uint64(1)
    for r in range(rows.shape[0]):
        n = 0
        for w in range(rows.shape[1]):
            word = rows[r, w]
            for b in range(64):
                f = 64 * w + b
                if f >= n_facts:
                    break
                if (word >> np.uint64(b)) & one:
                    state[n] = f
                    n += 1
        out[r] = _hadd(state[:n], goal, alt_ptr, alt_idx, relevant, n_facts, n_pre, pre_ptr,
                       pre_ops, add_ptr, add_idx, free, heap_size, cap)
    return out


_CACHE: dict[tuple[type, int], tuple[weakref.ref, HMax | HAdd]] = {}


def _cached(kind: type, task: GroundTask):
    """The (cached) heuristic ``kind`` of ``task``: building one reads every ground
    action, and online exploration asks for it once per run."""
    hit = _CACHE.get((kind, id(task)))
    if hit is not None and hit[0]() is task:
        return hit[1]
    h = kind(task)
    _CACHE[kind, id(task)] = (weakref.ref(task), h)
    return h


def hmax_for(task: GroundTask) -> HMax:
    """The (cached) :class:`HMax` of ``task``."""
    return _cached(HMax, task)


def hadd_for(task: GroundTask) -> HAdd:
    """The (cached) :class:`HAdd` of ``task``."""
    return _cached(HAdd, task)
