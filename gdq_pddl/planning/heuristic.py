"""Delete-relaxation heuristics (Bonet & Geffner 2001) of a grounded task, with unit
action costs, compiled: h_max (:class:`HMax`, admissible and consistent: a breadth-first
search over facts), h_add (:class:`HAdd`, not admissible, but it sums the costs of all
the goal facts where h_max takes the dearest: a generalized Dijkstra over facts,
:mod:`gdq_pddl.planning.relaxed_costs`) and h_FF (:class:`HFF`, Hoffmann & Nebel 2001:
the size of the relaxed plan h_add's best supporters make).

All read the same *relaxed actions* of the task (:func:`relaxed_actions`): positive
preconditions and adds only. A ground action (:class:`~gdq_pddl.pddl.grounding.GroundOp`)
gives one per outcome the planner knows (``op.known``; a STRIPS action: its one effect)
and per conditional effect of such an outcome, times each alternative of a disjunctive
precondition: a :class:`~gdq_pddl.pddl.ppddl.ProbabilisticTask` is relaxed as the planner's
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

from gdq_pddl.pddl.grounding import GroundTask, set_bits
from gdq_pddl.planning.relaxed_costs import cheapest_alternative, hadd_costs, relaxed_plan_size

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

    A ground action gives, for each alternative ``(must hold, must not hold)`` of its
    precondition (``op.alternatives``; none: ``(pre, neg)`` alone) and each outcome the
    planner knows (``op.known``, what its determinisation keeps: reality's other outcomes
    are no knowledge to plan with),
    ``(pre | alternative, outcome.add)``, and for each conditional effect ``(cp, cn, a,
    d)`` of that outcome ``(pre | alternative | cp, a)`` -- but for a conditional effect
    whose condition contradicts that alternative (a fact both required and excluded),
    which can never fire there (the planner's determinisation drops it too). A STRIPS
    action is ``(pre, add)``.
    """
    out: dict[tuple[int, int], None] = {}
    for op in task.ops:
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
        op_pre: list[np.ndarray] = []
        for i, (pre_mask, add_mask) in enumerate(actions):
            pre = np.array(list(set_bits(pre_mask)), dtype=np.int64)  # a few facts each
            op_pre.append(pre)
            n_pre[i] = len(pre)
            for f in pre.tolist():
                pre_of[f].append(i)
            if not len(pre):
                free.append(i)
            add_idx += set_bits(add_mask)
            add_ptr.append(len(add_idx))
        self.n_actions = len(actions)
        self.n_pre = n_pre
        self.pre_ptr = np.cumsum([0] + [len(x) for x in pre_of]).astype(np.int64)
        self.pre_ops = np.array([i for x in pre_of for i in x], dtype=np.int64)
        self.add_ptr = np.array(add_ptr, dtype=np.int64)
        self.add_idx = np.array(add_idx, dtype=np.int64)
        self.free = np.array(free, dtype=np.int64)
        self.op_pre_ptr = np.cumsum([0] + [len(x) for x in op_pre]).astype(np.int64)
        self.op_pre_idx = np.concatenate(op_pre) if op_pre else np.zeros(0, dtype=np.int64)

    def arrays(self) -> tuple[np.ndarray, ...]:
        """The arrays the compiled estimates read, in their order."""
        return (self.n_pre, self.pre_ptr, self.pre_ops, self.add_ptr, self.add_idx, self.free,
                self.op_pre_ptr, self.op_pre_idx)


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

    ff = False
    """Whether the estimate is h_FF (:class:`HFF`) rather than h_add."""

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
        """The estimate of the bitmask ``state`` to the task's goal (:data:`INFINITE`: none)."""
        if not self.possible:
            return INFINITE
        return int(_estimate(_bit_list(state, self.n_facts), self.ff, self.goal, self.alt_ptr,
                             self.alt_idx, self.relevant, self._c.arrays(), self._heap_size,
                             self.cap))

    def many(self, words: np.ndarray) -> np.ndarray:
        """The int64 estimate of each row of uint64 words ``words[n, n_words]`` (fact ``f``: bit
        ``f % 64`` of word ``f // 64``; bits past the task's facts ignored), -1 where
        unreachable."""
        rows = np.ascontiguousarray(words, dtype=np.uint64)
        if rows.ndim != 2:
            raise ValueError(f"{type(self).__name__}.many takes a 2-d array of word rows, "
                             f"not shape {rows.shape}")
        if not self.possible:
            return np.full(len(rows), INFINITE, dtype=np.int64)
        return _estimate_rows(rows, self.ff, self.goal, self.alt_ptr, self.alt_idx,
                              self.relevant, self._c.arrays(), self._heap_size, self.cap)


@numba.njit(cache=True)
def _estimate(state: np.ndarray, ff: bool, goal: np.ndarray, alt_ptr: np.ndarray,
              alt_idx: np.ndarray, relevant: np.ndarray, c: tuple, heap_size: int,
              cap: int) -> int:
    """h_add (``ff`` False) or h_FF of the facts ``state``; ``c``: :meth:`_Compiled.arrays`."""
    n_pre, pre_ptr, pre_ops, add_ptr, add_idx, free, op_pre_ptr, op_pre_idx = c
    big = np.iinfo(np.int64).max
    cost = np.empty(len(relevant), dtype=np.int64)
    sup = np.empty(len(relevant), dtype=np.int64)
    hadd_costs(state, relevant, len(relevant), n_pre, pre_ptr, pre_ops, add_ptr, add_idx,
               free, heap_size, cap, cost, sup)
    if ff:
        return relaxed_plan_size(cost, sup, goal, alt_ptr, alt_idx, op_pre_ptr, op_pre_idx)
    total = 0
    for f in goal:
        if cost[f] == big:
            return -1
        total += cost[f]
    if len(alt_ptr) > 1:
        a = cheapest_alternative(cost, alt_ptr, alt_idx)
        if a < 0:
            return -1
        for k in range(alt_ptr[a], alt_ptr[a + 1]):
            total += cost[alt_idx[k]]
    return total


@numba.njit(cache=True)
def _estimate_rows(rows: np.ndarray, ff: bool, goal: np.ndarray, alt_ptr: np.ndarray,
                   alt_idx: np.ndarray, relevant: np.ndarray, c: tuple, heap_size: int,
                   cap: int) -> np.ndarray:
    n_facts = len(relevant)
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
        out[r] = _estimate(state[:n], ff, goal, alt_ptr, alt_idx, relevant, c, heap_size, cap)
    return out


class HFF(HAdd):
    """h_FF (Hoffmann & Nebel 2001) of any state of one grounded task: the number of
    distinct relaxed actions in the relaxed plan that :class:`HAdd`'s best supporters
    make (each goal fact, and each fact of the cheapest goal alternative, supported by
    the relaxed action that gave it its h_add cost, and that action's preconditions in
    turn, back to the state's facts; ties keep the action found first). At most h_add,
    since an action that supports several facts counts once where h_add counts it for
    each (blocks: one ``stack`` gives ``handempty`` and ``on``); 0 and :data:`INFINITE`
    exactly where h_add has them. Not admissible either."""

    ff = True


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


def hff_for(task: GroundTask) -> HFF:
    """The (cached) :class:`HFF` of ``task``."""
    return _cached(HFF, task)
