"""The reachable state graph of a grounded task, within a table budget, and distances to
its goal.

:func:`reachable_graph` enumerates, breadth first from the initial state, every state a
sequence of ground operators can reach, *without expanding goal states* (a plan ends
where the goal first holds, as in the ``graph`` planner). States are numbered in BFS
order (the initial state is 0); the edges of state ``i`` are ``(op index, next state)``
pairs, one per applicable operator, in the order of :attr:`GroundTask.ops`. For a PPDDL
task (:class:`~gdq_pddl.pddl.ppddl.ProbabilisticTask`) the states are those reality
reaches (every outcome of every action), numbered after the edges' states, and the edges
are the planner's knowledge: one per applicable ground action and outcome its
determinisation keeps, so a state may have several edges with one op. States are rows of
``uint64`` words and the ground actions are compiled onto them
(:func:`~gdq_pddl.pddl.wordrows.compile_ops`); each
state's applicable ground actions are the graph's :attr:`StateGraph.offered` table
(:mod:`gdq_pddl.pddl.offered` reads it).

The enumeration stops with an error once the tables over states x offered actions would
pass the budget (:data:`TABLE_BUDGET`, :func:`table_budget`, :func:`state_cap`).

:func:`~gdq_pddl.pddl.distances.goal_distances` is one backward BFS over that graph:
every state's shortest number of actions to the goal (-1: the goal cannot be reached
from it). Together they give every state's shortest plans without calling a planner
once per state.

Reality's outcomes of each (state, offered action) pair of a PPDDL task are in
:mod:`gdq_pddl.pddl.outcomes`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from gdq_pddl.errors import TooManyStates
from gdq_pddl.limits import human_bytes, physical_memory, slow_progress
from gdq_pddl.pddl.distances import goal_distances
from gdq_pddl.pddl.grounding import GroundTask
from gdq_pddl.pddl.wordrows import (
    KeyIndex,
    applicable_rows,
    compile_ops,
    fact_rows,
    filter_chunk,
    goal_rows,
    positive_facts,
    row_keys,
    words,
)

PAIR_BYTES = 160
"""Peak memory one cell of the tables over states x offered actions (a state's row as
long as the longest) takes through a whole run: the graph, the true model while it is
compiled, the prior, the plan tables and a learner's tables. Measured as the peak
resident set over the cells, the interpreter's 0.14 GB taken off (docs/decisions.md,
"Size is a budget"): 148 bytes on switches 20 (21 million cells, one outcome a pair; the
peak is GDQ's tables beside the plans), 140 on a one-box, five-truck boxworld (36
million cells of 245 actions, conditional effects; the peak is the true model's
compilation), 154 on its two-box, four-truck variant (82 million cells: ``gdq-pddl run``
of GDQ, DARLING and Q-learning, 12.7 GB); rounded up."""

ROW_COPIES = 4
"""Copies of each state's row of facts (8 bytes a word of 64 facts) enumeration holds at
its peak: the rows of the levels, their sorted keys (the rows' bytes), the keys' copy
while new ones are inserted, the graph's concatenated rows. :data:`PAIR_BYTES` was
measured on rows of one or a few words; a problem of many facts and few actions a state
needs more per state than its tables: manytireworld_test problem0 (pddlgym; 2,026 facts,
32 words, up to 3 actions a state) peaks at 1.0 KB a state enumerating 4 million (4.2 GB,
``/usr/bin/time``), where its tables count 480 bytes."""

MEMORY_SHARE = 0.75
"""The share of the machine's memory (:func:`~gdq_pddl.limits.physical_memory`,
``GDQ_PDDL_MEMORY`` overrides it) the tables may take when :data:`TABLE_BUDGET` is None:
the rest is headroom for the interpreter, numba and what else the machine runs."""

TABLE_BUDGET: int | None = None
"""Bytes the tables of states x offered actions may take (:data:`PAIR_BYTES` a cell):
state enumeration stops with an error past it. None (the default): :data:`MEMORY_SHARE`
of this machine's memory (:func:`table_budget`); set a number of bytes to fix it."""

PARENT_CHUNK = 1 << 17
"""States of a level expanded at a time at most: their successors' work arrays stay
bounded."""

EXPAND_CELLS = 1 << 21
"""(state, applicable ground action) pairs of a level expanded at a time at most, by the
widest row seen so far: a problem of wide rows (boxworld: 750 ground actions in every
state) expands fewer states at a time, so its work arrays stay near 1 GB and a problem
past the budget is refused after the chunk that passes it."""


MAX_STATES: int | None = None
"""Default cap on the number of reachable states (None: what :func:`table_budget` allows)."""


@dataclass(frozen=True, eq=False)
class StateGraph:
    """Reachable states (BFS order) and their successor edges (CSR).

    ``words`` holds state ``i`` as ``uint64`` words (fact ``f`` is bit ``f % 64`` of word
    ``f // 64``); :attr:`states` as Python int bitmasks. The edges of state ``i`` are
    ``edge_op[edge_ptr[i]:edge_ptr[i + 1]]`` (index into ``task.ops``) and
    ``edge_next[...]`` (state index); goal states have none.

    ``offered`` is what a learner may do in each state, the tables' layout (each state
    lists its applicable ground actions, not every ground action): row ``i`` holds the
    ground actions whose preconditions hold in state ``i`` (reality's outcomes included),
    in increasing order, padded with -1 to the longest row; a state where none applies (a
    goal, a dead end) lists ground action 0, which changes nothing there.
    """

    task: GroundTask
    words: np.ndarray
    edge_ptr: np.ndarray
    edge_op: np.ndarray
    edge_next: np.ndarray
    is_goal: np.ndarray
    """bool[n_states]: the task's goal holds (such states are not expanded)."""
    depth: np.ndarray
    """int64[n_states]: the fewest actions (edges and reality's outcomes) from state 0."""
    offered: np.ndarray
    """int64[n_states, width]: the ground actions offered in each state (class docstring)."""

    @property
    def n_states(self) -> int:
        return len(self.words)

    @cached_property
    def states(self) -> tuple[int, ...]:
        """The states as int bitmasks over ``task.facts``."""
        cols = [w.tolist() for w in self.words.T]
        if len(cols) == 1:
            return tuple(cols[0])
        return tuple(sum(c << (64 * j) for j, c in enumerate(row))
                     for row in zip(*cols, strict=True))

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

    @cached_property
    def _sorted(self) -> tuple[np.ndarray, np.ndarray | None]:
        keys = row_keys(self.words)
        if keys.dtype == np.uint64 and int(keys.max()) < 4 * len(keys) + 65536:
            dense = np.full(int(keys.max()) + 1, -1, dtype=np.int64)  # few facts: a table
            dense[keys] = np.arange(len(keys))
            return dense, None
        order = np.argsort(keys, kind="stable")
        return keys[order], order

    def lookup(self, rows: np.ndarray) -> np.ndarray:
        """int64 index of each reachable state in ``rows`` (``uint64[n, words]``)."""
        keys, order = self._sorted
        if order is None:
            return keys[row_keys(rows)]
        return order[np.searchsorted(keys, row_keys(rows))]


def table_budget() -> int:
    """Bytes the tables may take: :data:`TABLE_BUDGET`, or when it is None
    :data:`MEMORY_SHARE` of :func:`~gdq_pddl.limits.physical_memory`."""
    if TABLE_BUDGET is not None:
        return int(TABLE_BUDGET)
    return int(MEMORY_SHARE * physical_memory())


def state_bytes(width: int, n_words: int = 1) -> int:
    """The memory a state takes: its tables of ``width`` actions, and the copies of its row
    of ``n_words`` words past the first (which :data:`PAIR_BYTES` counts)."""
    return PAIR_BYTES * max(1, width) + ROW_COPIES * 8 * max(0, n_words - 1)


def state_cap(width: int, budget: int | None = None, n_words: int = 1) -> int:
    """The most states whose tables of ``width`` actions a state (and rows of ``n_words``
    words) fit ``budget`` bytes (None: :func:`table_budget`)."""
    budget = table_budget() if budget is None else budget
    return budget // state_bytes(width, n_words)


GROWTH_LEVELS = 3
"""Levels :func:`projected_states` projects ahead."""

PROJECTION_SLACK = 2.0
"""A breadth-first level grew as projected when it holds within this factor, either way,
of the states :func:`projected_levels` projected for it from the levels before it; only
a projection from such a level is evidence enough to give up on (:func:`backed_by`)."""


def projected_levels(levels: list[int], ahead: int) -> list[float]:
    """The sizes of the ``ahead`` breadth-first levels after ``levels`` (the sizes of the
    complete levels so far), if each grows on the last's growth times the rate at which
    growth slowed from the level before (never faster than the last growth; with only
    two levels, on the last growth); [] with fewer than 2 levels or an empty one among
    the last three."""
    if len(levels) < 2 or min(levels[-3:]) == 0:
        return []
    growth = levels[-1] / levels[-2]
    slowing = min(1.0, growth * levels[-3] / levels[-2]) if len(levels) >= 3 else 1.0
    size, out = float(levels[-1]), []
    for _ in range(ahead):
        growth *= slowing
        size *= growth
        out.append(size)
    return out


def projected_states(levels: list[int]) -> int:
    """The states the enumeration would know :data:`GROWTH_LEVELS` levels on (``levels``:
    the sizes of the complete breadth-first levels), by :func:`projected_levels`; 0 with
    fewer than 3 levels or an empty one among the last three. A breadth-first search
    nears its widest level as its growth slows: ``n`` independent switches grow
    x(n-k)/(k+1) from level k, and are never projected more than 2% past their 2**n
    states (n = 6 to 33); manytireworld_test problem0 (pddlgym) grows x1.83 a level from
    level 16 to 24 and passes a 24 GB machine's budget in level 24; pddlgym's exploding
    blocks of 126 blocks grow about x100 a level from the start."""
    ahead = projected_levels(levels, GROWTH_LEVELS) if len(levels) >= 3 else []
    return sum(levels) + round(sum(ahead)) if ahead else 0


def backed_by(levels: list[int]) -> float | None:
    """The states the levels before the last projected for it (:func:`projected_levels`),
    where the last level holds within :data:`PROJECTION_SLACK` of that; None where it
    did not grow as projected (a burst: a teleport that reaches every cell at once; a
    plateau after one), or with fewer than 3 levels. A projection from a level that did
    not grow as projected is no evidence, and the enumeration goes on."""
    if len(levels) < 3:
        return None
    before = projected_levels(levels[:-1], 1)
    if not before or before[0] < 1 or not (
            before[0] / PROJECTION_SLACK <= levels[-1] <= PROJECTION_SLACK * before[0]):
        return None
    return before[0]


def _too_many(source: str, cap: int, budget: bool, width: int, n_words: int,
              levels: list[int], projected: int = 0, backed: float = 0.0) -> TooManyStates:
    """The refusal past ``cap`` states: the need (of the states found so far, every row as
    wide as the widest), the budget and what sets it, and the breadth-first levels so far
    (``levels``: states a level, the last unfinished). A refusal before the cap
    (``projected``, by :func:`projected_states`, the levels all complete) says its
    evidence: the last level held about the ``backed`` states projected for it."""
    shown = ", ".join(f"{n:,}" for n in levels[-6:])
    grown = f"; states of breadth-first levels {max(0, len(levels) - 6)} to " \
        f"{len(levels) - 1}{'' if projected else ' (the last unfinished)'}: {shown}"
    if not budget:
        return TooManyStates(f"{source}: more than {cap:,} reachable states: past the cap "
                             f"given{grown}; the learners are tabular, so make the problem "
                             "smaller (fewer objects)")
    have, limit, found = physical_memory(), table_budget(), sum(levels)
    setting = (f"gdq_pddl.pddl.reachable.TABLE_BUDGET = {limit:,}" if TABLE_BUDGET
               is not None else f"{MEMORY_SHARE:g} of this machine's {human_bytes(have)} "
               "(gdq_pddl.pddl.reachable.MEMORY_SHARE, or TABLE_BUDGET in bytes)")
    rows = "" if n_words <= 1 else f" and {ROW_COPIES * 8} bytes a state x 64 facts " \
        f"past the first, ROW_COPIES: {n_words} words of facts here"
    cell = f"{PAIR_BYTES} bytes a state x action cell, gdq_pddl.pddl.reachable.PAIR_BYTES{rows}"
    if projected:
        return TooManyStates(
            f"{source}: likely more than {cap:,} reachable states, the budget's cap (given "
            f"up early after breadth-first level {len(levels) - 1}, {found:,} states found, "
            f"up to {width} applicable ground actions a state){grown}; level "
            f"{len(levels) - 1} grew as projected ({levels[-1]:,} states against "
            f"{round(backed):,} projected from the levels before it), and {GROWTH_LEVELS} "
            f"more levels growing as these did would make {projected:,} states, whose "
            f"tables would need about {human_bytes(projected * state_bytes(width, n_words))}"
            f" ({cell}), past the budget of {human_bytes(limit)}: {setting} "
            "(gdq_pddl.pddl.reachable.projected_states); `--explore enumerate` lists the "
            "states anyway, until they pass the budget")
    return TooManyStates(
        f"{source}: more than {cap:,} reachable states ({found:,} found so far, up to "
        f"{width} applicable ground actions a state): a run would need at least "
        f"{human_bytes(found * state_bytes(width, n_words))} ({cell}), past the budget of "
        f"{human_bytes(limit)}: {setting}{grown}; the learners are tabular, so make the "
        "problem smaller (fewer objects), or run it on a machine with more memory")


def first_seen(after: list[np.ndarray]) -> list[np.ndarray]:
    """For the rows of each outcome's successors ``after[j]`` (the same parent rows in
    each), the rows whose successor no earlier outcome gave that parent: the first outcome
    of each distinct successor. One stable sort of every (parent, successor) pair, not a
    comparison of each outcome with every earlier one: an action of 2,048 outcomes
    (IPPC-2008 sysadmin-slp, six computers) made 2 million comparisons a chunk."""
    if len(after) < 2:
        return [np.ones(len(a), dtype=np.bool_) for a in after]
    n_rows = len(after[0])
    pairs = np.concatenate(after)  # outcome-major: index j * n_rows + row
    parent = np.tile(np.arange(n_rows, dtype=pairs.dtype), len(after))
    keyed = np.column_stack([parent, pairs])
    _, first = np.unique(keyed, axis=0, return_index=True)  # first occurrences (stable)
    new = np.zeros(len(keyed), dtype=np.bool_)
    new[first] = True
    return list(new.reshape(len(after), n_rows))


def reachable_graph(task: GroundTask, max_states: int | None = MAX_STATES,
                    source: str = "problem", give_up_early: bool = False) -> StateGraph:
    """Every state reachable from ``task.init`` (goal states not expanded), one breadth
    first level at a time on word arrays; numbered as a one-state-at-a-time BFS would.

    Raises :class:`TooManyStates` naming ``source`` when more than ``max_states`` states
    are reachable (None: more than :func:`state_cap` of the table budget); with the
    budget and ``give_up_early``, also once a complete level grew as projected
    (:func:`backed_by`) and its :func:`projected_states` passes it (what ``--explore
    auto`` asks: it goes online then, and a doomed enumeration of millions of states took
    minutes).
    """
    refuse_factored(task, source)
    n_ops = len(task.ops)
    n_words = max(1, -(-len(task.facts) // 64))
    ops = compile_ops(task, n_words)
    width = max([len(op.known) + len(op.other) for op in ops], default=1)
    reality_rank = reality_ranks(task)
    need = [positive_facts(op.pre) for op in ops]  # each op's facts that must hold
    # a chunk small enough for fact_rows to list the rows of every needed fact: else each
    # ground action is tested on every row (manytireworld: 3,299 ground actions, 2,026
    # facts; 300k states took 60 s instead of 2 s)
    filtered = filter_chunk(need)
    levels = [words(task.init, n_words)[None, :]]
    known = KeyIndex(row_keys(levels[0]).copy(), np.zeros(1, dtype=np.int64))
    goal, depth, src, op_of, nxt = [], [], [], [], []
    rows_of: list[tuple[np.ndarray, np.ndarray]] = []  # (states, their offered rows)
    op_type = np.int16 if n_ops <= np.iinfo(np.int16).max else np.int32
    width_seen = 1
    lo, n = 0, 1  # the first state of the level expanded, and the states known
    with slow_progress("reachable states", " states") as bar:
        while lo < n:
            rows = levels[-1]
            is_goal = goal_rows(task, rows)
            goal.append(is_goal)
            depth.append(np.full(len(rows), len(depth), dtype=np.int64))
            parents = np.flatnonzero(~is_goal)
            bar.update(len(rows) - len(parents))
            level_start, next_rows = n, []
            c = 0
            while c < len(parents):  # bounded work arrays: rows of the widest seen
                step = max(1, min(PARENT_CHUNK, EXPAND_CELLS // width_seen, filtered))
                parent = parents[c:c + step]
                c += step
                expand = rows[parent]
                found: list[tuple[np.ndarray, np.ndarray, int]] = []  # rows, parent, rank
                n_applicable = np.zeros(len(parent), dtype=np.int64)
                applicable: list[tuple[int, np.ndarray]] = []
                holding = fact_rows(expand, need)
                for k, op in enumerate(ops):
                    at = applicable_rows(op, expand, holding, need[k])
                    if not len(at):
                        continue
                    n_applicable[at] += 1
                    applicable.append((k, at))
                    here = expand[at]
                    after = [effect.apply(here) for effect in op.known]
                    for j, (t, new) in enumerate(zip(after, first_seen(after), strict=True)):
                        found.append((t[new], at[new], k * width + j))
                    for j, effect in enumerate(op.other):
                        found.append((effect.apply(here), at,
                                      (n_ops + reality_rank[k]) * width + j))
                cand = np.concatenate([f[0] for f in found]) if found else rows[:0]
                who = np.concatenate([f[1] for f in found]) if found else parent[:0]
                rank = np.concatenate([np.full(len(f[1]), f[2], dtype=np.int64)
                                       for f in found]) if found else parent[:0]
                del found
                order = np.argsort(who * (2 * n_ops * width) + rank, kind="stable")
                cand, who, rank = cand[order], who[order], rank[order]
                keys = row_keys(cand)
                uniq, first = np.unique(keys, return_index=True)
                fresh = np.sort(first[known.find(uniq) < 0])
                width_seen = max(width_seen, int(n_applicable.max(initial=0)))
                rows_of.append((lo + parent, _row_block(applicable, len(parent), op_type)))
                del applicable
                cap = state_cap(width_seen, n_words=n_words) if max_states is None \
                    else max_states
                if n + len(fresh) > cap:
                    raise _too_many(source, cap, max_states is None, width_seen, n_words,
                                    [len(level) for level in levels] + [n + len(fresh)
                                                                       - level_start])
                known.add(keys[fresh], np.arange(n, n + len(fresh)))
                edge = rank < n_ops * width
                src.append(lo + parent[who[edge]])
                op_of.append(rank[edge] // width)
                nxt.append(known.find(keys[edge]))
                next_rows.append(cand[fresh])
                n += len(fresh)
                bar.update(len(parent))
            levels.append(np.concatenate(next_rows) if next_rows else rows[:0])
            lo = level_start
            if give_up_early and max_states is None:
                sizes = [len(level) for level in levels]
                projected, cap = projected_states(sizes), state_cap(width_seen, n_words=n_words)
                backed = backed_by(sizes) if projected > cap else None
                if backed is not None:
                    raise _too_many(source, cap, True, width_seen, n_words, sizes, projected,
                                    backed)
    none = np.zeros(0, dtype=np.int64)  # no level expanded (the start is a goal)
    src_all = np.concatenate(src) if src else none
    del src
    ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(src_all, minlength=n), out=ptr[1:])
    del src_all
    offered = np.full((n, width_seen), -1, dtype=np.int64)
    while rows_of:  # each block freed once copied: one copy of the rows at the peak
        states, block = rows_of.pop()
        offered[states, :block.shape[1]] = block
    offered[offered[:, 0] < 0, 0] = 0  # none applies (a goal, a dead end): ground action 0
    edge_op = np.concatenate(op_of or [none]).astype(np.int64, copy=False)
    del op_of
    edge_next = np.concatenate(nxt or [none]).astype(np.int64, copy=False)
    del nxt
    return StateGraph(task, np.concatenate(levels), ptr, edge_op, edge_next,
                      np.concatenate(goal), np.concatenate(depth), offered)


def factored_reason(task: GroundTask, source: str) -> str:
    """Why ``task``'s states and true model are not enumerated where it has a factored
    ground action (:attr:`GroundOp.parts <gdq_pddl.pddl.grounding.GroundOp.parts>`):
    reality's outcomes of it are drawn part by part, never listed; "" where it has none."""
    op = next((op for op in task.ops if op.factored), None) \
        if getattr(task, "factored", ()) else None
    return "" if op is None else (
        f"{source}: {op.name} has {op.product_size():,} outcomes, kept as {len(op.parts)} "
        "independent parts (a forall of probabilistic effects): they are drawn part by part "
        "and never listed, so the states and the true model are not enumerated")


def refuse_factored(task: GroundTask, source: str) -> None:
    """Refuse (:class:`TooManyStates`: ``--explore auto`` goes online then) to enumerate
    a task with a factored ground action (:func:`factored_reason`)."""
    reason = factored_reason(task, source)
    if reason:
        raise TooManyStates(f"{reason}; explore online (--explore online, or auto)")


def reality_ranks(task: GroundTask) -> np.ndarray:
    """int64[n_ops]: each ground action's place in the order :meth:`GroundTask.applicable`
    lists them; a state's successors only reality reaches are numbered in it (after the
    edges' successors, which go by ground action), as :meth:`GroundTask.outcome_states`
    lists them. The online store (:mod:`gdq_pddl.pddl.lazy`) numbers them the same way."""
    order_of = {id(op): (key, i) for key, group in task.ops_by_fact.items()
                for i, op in enumerate(group)}
    return np.argsort(sorted(range(len(task.ops)), key=lambda k: order_of[id(task.ops[k])]))


def _row_block(applicable: list[tuple[int, np.ndarray]], n_rows: int,
               dtype: type) -> np.ndarray:
    """The :attr:`StateGraph.offered` rows (``dtype``, -1 padding) of ``n_rows`` states
    from ``(ground action, rows where it applies)`` in increasing action order."""
    count = np.zeros(n_rows, dtype=np.int64)
    for _, at in applicable:
        count[at] += 1
    block = np.full((n_rows, max(1, int(count.max(initial=0)))), -1, dtype=dtype)
    count[:] = 0
    for k, at in applicable:
        block[at, count[at]] = k
        count[at] += 1
    return block
