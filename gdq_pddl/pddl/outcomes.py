"""Reality's outcomes of every (state, offered action) pair of a PPDDL task's graph.

:func:`reality_outcomes` applies every outcome of every ground action applicable in each
non-goal state of a :class:`~gdq_pddl.pddl.reachable.StateGraph` (reality's outcomes,
not only the determinisation's that make the graph's edges) and merges the equal ones of
a pair: the rows a PPDDL problem's true model is compiled from
(:func:`gdq_pddl.envs.model.compile_true_model`). It reads the graph's states as word
rows and applies the ground actions as the enumeration does
(:mod:`gdq_pddl.pddl.wordrows`), a chunk of states at a time.
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.limits import slow_progress
from gdq_pddl.pddl.offered import columns_in
from gdq_pddl.pddl.reachable import StateGraph, refuse_factored
from gdq_pddl.pddl.wordrows import CompiledOp, compile_ops

OUTCOME_CHUNK = 1 << 22
"""Cells (states x row width) whose outcomes :func:`reality_outcomes` sorts and merges at
a time: its work arrays (about 200 bytes an outcome) stay near 1 GB."""


def reality_outcomes(graph: StateGraph, gains: bool = True
                     ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The outcomes of every ground action applicable in each non-goal state of a PPDDL
    task's graph, as rows in pair order: ``pair`` (``state * width + column`` of the
    graph's :attr:`~StateGraph.offered` rows), probability,
    and the fields next state, stuck (a failed trial stays) and, with ``gains`` (the
    default: what the outcome earns belongs to it on either reward scale), the outcome's
    reward besides the action's cost. Equal ``(next, stuck[, reward])`` of a pair are one row, their
    probabilities summed in outcome order; outcomes of probability 0 are left out.

    Built :data:`OUTCOME_CHUNK` cells of states at a time (pairs of different states
    never merge, so the chunks' rows, in state order, are the whole's): the sort and
    merge work arrays stay bounded, and only the merged rows are kept. A bar counts the
    chunks past 2 s."""
    task = graph.task
    refuse_factored(task, "reality's outcomes")  # never listed (a graph is refused first)
    width = graph.offered.shape[1]
    n_words = graph.words.shape[1]
    ops = compile_ops(task, n_words, every=True)
    live = np.flatnonzero(~graph.is_goal)
    column = columns_in(graph.offered)
    step = max(1, OUTCOME_CHUNK // width)
    chunks = []
    with slow_progress("true model", " chunks", -(-len(live) // step)) as bar:
        for c in range(0, len(live), step):
            chunks.append(_outcomes_of(graph, ops, live[c:c + step], column, gains))
            bar.update()
    n_fields = 3 if gains else 2
    if not chunks:  # every state a goal (the initial state is one): no outcome at all
        chunks = [_outcomes_of(graph, ops, live, column, gains)]
    out = []
    for f in range(2 + n_fields):  # one field joined at a time, its pieces freed
        pieces = [chunk[f] for chunk in chunks]
        for chunk in chunks:
            chunk[f] = None
        out.append(np.concatenate(pieces))
        del pieces
    return out[0], out[1], out[2:]


def _outcomes_of(graph: StateGraph, ops: list[CompiledOp], live: np.ndarray, column,
                 gains: bool) -> list:
    """:func:`reality_outcomes` of the states ``live`` (increasing), as a list ``[pair,
    probability, next, stuck(, reward)]``."""
    task, width = graph.task, graph.offered.shape[1]
    rows = graph.words[live]
    parts: list[tuple] = []
    for k, (op, ground) in enumerate(zip(ops, task.ops, strict=True)):
        at = live[op.applies(rows)]
        if not len(at):
            continue
        here = graph.words[at]
        pair = at * width + column(at, np.full(len(at), k))
        for j, (o, effect) in enumerate(zip(ground.outcomes, op.outcomes, strict=True)):
            if o.probability > 0:
                nxt = at if o.stuck or not o.moves() else graph.lookup(effect.apply(here))
                parts.append((pair, j, o.probability, nxt, o.stuck,
                              effect.gain(here) if gains else None))
    if not parts:  # no ground action applies in these states (dead ends)
        return [np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0, dtype=np.int64),
                np.zeros(0, dtype=np.bool_)] + ([np.zeros(0)] if gains else [])
    pair = np.concatenate([p[0] for p in parts])
    j = np.concatenate([np.full(len(p[0]), p[1], dtype=np.int32) for p in parts])
    prob = np.concatenate([np.full(len(p[0]), p[2]) for p in parts])
    nxt = np.concatenate([p[3] for p in parts]).astype(np.int64, copy=False)
    stuck = np.concatenate([np.full(len(p[0]), p[4]) for p in parts])
    gain = np.concatenate([p[5] for p in parts]) if gains else None
    del parts  # one copy of the rows at a time: they are most of the peak memory
    # equal keys of a pair side by side, in outcome order; each group's first row leads
    key = (pair * graph.n_states + nxt) * 2 + stuck
    order = np.lexsort((j, gain, key) if gains else (j, key))
    key = key[order]  # one array reordered at a time: one extra copy at the peak
    pair = pair[order]
    j = j[order]
    prob = prob[order]
    nxt = nxt[order]
    stuck = stuck[order]
    gain = gain[order] if gains else None
    del order
    lead = np.ones(len(pair), dtype=np.bool_)
    lead[1:] = key[1:] != key[:-1]
    if gains:
        lead[1:] |= gain[1:] != gain[:-1]
    group = np.cumsum(lead) - 1
    total = np.zeros(group[-1] + 1 if len(group) else 0)
    place = np.arange(len(group)) - np.flatnonzero(lead)[group]
    for r in range(int(place.max(initial=-1)) + 1):  # summed in order, as merge_outcomes
        total[group[place == r]] += prob[place == r]
    first = np.flatnonzero(lead)
    keep = first[np.lexsort((j[first], pair[first]))]
    return [pair[keep], total[group[keep]], nxt[keep], stuck[keep]] + \
        ([gain[keep]] if gains else [])
