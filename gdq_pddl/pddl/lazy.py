"""The states of a grounded task found as an agent visits them, each expanded on demand:
the online counterpart of the enumeration (:func:`~gdq_pddl.pddl.reachable.reachable_graph`
and :func:`~gdq_pddl.pddl.outcomes.reality_outcomes`), for problems whose reachable states
are too many to enumerate (10**10 and more: exploding blocks of 23 blocks, IPPC boxworld).

:class:`LazyGraph` holds the states discovered so far (state 0: the initial state) with
their word rows (:mod:`gdq_pddl.pddl.wordrows`) and goal flags. Expanding a state finds
the ground actions applicable in it (one vectorised test of every ground action's
condition facts on its row: :class:`~gdq_pddl.pddl.wordrows.RowConditions`), the
determinisation's edges and reality's outcomes of each, and gives the successors never
seen the next ids. The semantics are the enumeration's: the same
applicability (negative preconditions, a disjunctive task's alternatives), effects
(conditional ones included), edges deduplicated per ground action, outcomes of
probability 0 left out, a failed trial (stuck) staying, equal outcomes of a pair merged
with their probabilities summed in outcome order, goal states never expanded. Expanding
every state in id order numbers them exactly as the enumeration does; in any other order
the graph is the same up to renaming states.

A state is expanded in one pass over every ground action at once, no Python call per
outcome (IPPC-2008 boxworld p05: 1,800 ground actions, all applicable in every state;
one outcome at a time cost 50 ms a state). The outcomes that have something to do (an
unconditional add or delete, or a conditional effect whose condition holds, all tested
together) are applied to copies of the state's word row by their facts' bits; the rows
that changed are looked up by their bytes (a dict of the states found); the rest stay.
Edges are deduplicated, outcomes merged (probabilities summed in outcome order, as a loop
sums them) and new states numbered by sorts on whole arrays.

A factored ground action (:attr:`GroundOp.parts <gdq_pddl.pddl.grounding.GroundOp.parts>`:
a forall of probabilistic effects whose product is too large to list) has its edges (the
determinisation's outcomes, each part's taken one at a time) but no listed outcome:
reality's outcome of it is drawn part by part when an agent takes it
(:meth:`LazyGraph.draw`, :mod:`gdq_pddl.pddl.factored`), and the state it reaches is
discovered then.
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.pddl.factored import best_gain, combine, gain_terms, sample_parts
from gdq_pddl.pddl.grounding import GroundTask
from gdq_pddl.pddl.reachable import reality_ranks
from gdq_pddl.pddl.wordrows import (
    RowConditions,
    RowGains,
    effect_bits,
    goal_rows,
    spans,
    unpacked,
)

_NONE = np.zeros(0, dtype=np.int64)
_STAYS = np.iinfo(np.int64).min
"""Where an effect leads that changes nothing (the expanded state itself)."""


class LazyGraph:
    """The states of a grounded task (:class:`GroundTask` or
    :class:`~gdq_pddl.pddl.ppddl.ProbabilisticTask`) found so far, each expanded (its
    applicable ground actions, the determinisation's edges, reality's outcomes) only when
    asked.

    State 0 is ``task.init``, discovered, not expanded. Ids are given in discovery order
    and never change. ``gains`` (the default): also compute what each outcome earns
    besides the action's cost (its rewards, less its costs inside effects: on either
    reward scale), as :func:`~gdq_pddl.pddl.outcomes.reality_outcomes` does.

    For a STRIPS task reality's outcome of a ground action is its one effect,
    probability 1 and gain 0: the task's own dynamics, not a dynamics file's.
    """

    def __init__(self, task: GroundTask, gains: bool = True) -> None:
        self.task = task
        self.gains = gains
        self.n_words = max(1, -(-len(task.facts) // 64))
        self._conditions = RowConditions([(op.pre, op.neg) for op in task.ops])
        alt = [(k, p, n) for k, op in enumerate(task.ops) for p, n in op.alternatives]
        self._alt_op = np.array([k for k, _, _ in alt], dtype=np.int64)
        self._alternatives = RowConditions([(p, n) for _, p, n in alt])
        self._plain = np.ones(len(task.ops), dtype=np.bool_)  # no alternatives to meet
        self._plain[self._alt_op] = False
        self._compile(task)
        self.factored = np.array([op.factored for op in task.ops], dtype=np.bool_)
        """bool[n_ops]: the ground action is factored (:meth:`draw` its outcome)."""
        self._fixed_gains: dict[int, tuple] = {}  # best_gain's parts that do not vary
        self._index: dict[bytes, int] = {}
        self._words = np.zeros((16, self.n_words), dtype=np.uint64)
        self._goal = np.zeros(16, dtype=np.bool_)
        self._expanded = np.zeros(16, dtype=np.bool_)
        self._n = 0
        init = task.init.to_bytes(8 * self.n_words, "little")
        self._index[init] = 0
        self._append([init])
        self._offered: dict[int, np.ndarray] = {}
        self._edges: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._outcomes: dict[int, tuple[np.ndarray, ...]] = {}

    @property
    def n_states(self) -> int:
        """States discovered so far (ids ``0 .. n_states - 1``)."""
        return self._n

    @property
    def words(self) -> np.ndarray:
        """uint64[n_states, n_words]: the discovered states' rows (a view, valid until the
        next :meth:`expand` that discovers states)."""
        return self._words[:self._n]

    @property
    def is_goal(self) -> np.ndarray:
        """bool[n_states]: the goal holds (:func:`~gdq_pddl.pddl.wordrows.goal_rows`); a
        view, as :attr:`words`."""
        return self._goal[:self._n]

    @property
    def expanded(self) -> np.ndarray:
        """bool[n_states]: the state was expanded; a view, as :attr:`words`."""
        return self._expanded[:self._n]

    def expand(self, ids) -> np.ndarray:
        """Expand each listed state that is neither a goal nor expanded yet (others are
        ignored), in the order given; return the ids of the states discovered (increasing).

        Successors never seen get the next ids: by expanded state in the order given,
        then as the enumeration orders them (the determinisation's edges by ground action
        then outcome, then reality's other outcomes in the order
        :func:`~gdq_pddl.pddl.reachable.reality_ranks` gives the ground actions)."""
        order = np.asarray(ids, dtype=np.int64).ravel().tolist()
        bad = [x for x in order if not 0 <= x < self._n]
        if bad:
            raise IndexError(f"state {bad[0]} is not a discovered state (0 to "
                             f"{self._n - 1})")
        start = self._n
        for x in order:
            if not (self._expanded[x] or self._goal[x]):
                self._append(self._expand_one(x))
        return np.arange(start, self._n, dtype=np.int64)

    def _expand_one(self, x: int) -> list[int]:
        """Expand state ``x``: store its offered actions, edges and outcomes; return the
        rows of the states it discovers (already given ids in :attr:`_index`).

        Every outcome of the applicable ground actions at once: the effects that change
        something here (an unconditional add or delete, or a conditional effect whose
        condition holds: all tested together) are applied to copies of the row, one per
        effect, by their facts' bits; the changed rows are looked up by their bytes; the
        rest stay in ``x``."""
        row = self._words[x]
        bits = unpacked(row)
        ok = self._holds_bits(bits)
        acts = np.flatnonzero(ok)
        column = np.cumsum(ok) - 1  # each applicable ground action's column
        moving, rows = self._moved(row, bits, ok)
        sid, fresh = self._ids(row, rows)
        lead = self._lead  # effect -> where it leads: x unless it moves
        lead[moving] = sid

        e_pos = np.flatnonzero(ok[self._edge_op])
        e_op, e_next = self._edge_op[e_pos], lead[self._edge_eff[e_pos]]
        r_pos = np.flatnonzero(ok[self._real_op])
        col = column[self._real_op[r_pos]]
        r_next = np.where(self._real_moves[r_pos], lead[self._real_eff[r_pos]], _STAYS)
        lead[moving] = _STAYS
        e_next[e_next == _STAYS] = x
        r_next[r_next == _STAYS] = x
        n = self._n
        if fresh:  # provisional ids -1 - j: the j-th new row's
            new = self._numbered(n, fresh, e_next, r_pos, r_next)
            for ids in (e_next, r_next):
                neg = ids < 0
                ids[neg] = new[-1 - ids[neg]]
        # the determinisation's edges: each next state once a ground action, the first
        # (only ground actions with several kept outcomes can repeat one)
        keep = np.ones(len(e_pos), dtype=np.bool_)
        several = np.flatnonzero(self._edge_several[e_pos])
        if len(several):
            key = e_op[several] * (n + len(fresh) + 1) + e_next[several]
            _, first = np.unique(key, return_index=True)
            keep[several] = False
            keep[several[first]] = True
        self._offered[x] = acts
        self._edges[x] = (e_op[keep], e_next[keep])
        self._outcomes[x] = self._merged(bits, r_pos, col, r_next)
        self._expanded[x] = True
        return [fresh[j] for j in np.argsort(new)] if fresh else []

    def _moved(self, row: np.ndarray, bits: np.ndarray,
               ok: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(effects, rows)``: the outcomes (by flat effect index, increasing) of the
        applicable ground actions that have something to do in the state of ``row``
        (``bits``: its facts, :func:`~gdq_pddl.pddl.wordrows.unpacked`): an unconditional
        add or delete, or a conditional effect whose condition holds; and the row each
        leads to (adds win, as :meth:`GroundOutcome.apply
        <gdq_pddl.pddl.grounding.GroundOutcome.apply>`)."""
        plain = self._plain_eff[ok[self._eff_op[self._plain_eff]]]
        fired = np.flatnonzero(self._when.holds_bits(bits) & ok[self._when_op]) \
            if self._when.n else _NONE
        moving = np.union1d(plain, self._when_eff[fired]) if len(fired) else plain
        if not len(moving):
            return moving, np.zeros((0, len(row)), dtype=np.uint64)
        u_pos, u_own = spans(self._bit_ptr, moving)
        c_pos, c_own = spans(self._when_ptr, fired)
        own = np.concatenate([u_own, np.searchsorted(moving, self._when_eff[fired])[c_own]])
        word = np.concatenate([self._bit_word[u_pos], self._when_word[c_pos]])
        add = np.zeros((len(moving), len(row)), dtype=np.uint64)
        dele = np.zeros_like(add)
        np.bitwise_or.at(add, (own, word), np.concatenate([self._bit_add[u_pos],
                                                           self._when_add[c_pos]]))
        np.bitwise_or.at(dele, (own, word), np.concatenate([self._bit_del[u_pos],
                                                            self._when_del[c_pos]]))
        return moving, (row & ~dele) | add

    def _ids(self, row: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, list[bytes]]:
        """The id of the state each of ``rows`` is (:data:`_STAYS` where the row is
        ``row``, unchanged), and the rows never seen before, in order of first appearance
        in ``rows`` (they get provisional ids ``-1 - j`` meanwhile)."""
        sid = np.full(len(rows), _STAYS, dtype=np.int64)
        changed = np.flatnonzero((rows != row).any(axis=1))
        fresh: list[bytes] = []
        if not len(changed):
            return sid, fresh
        size = 8 * self.n_words
        data = np.ascontiguousarray(rows[changed], dtype="<u8").tobytes()
        keys = [data[i:i + size] for i in range(0, len(data), size)]
        ids = list(map(self._index.get, keys))
        if None in ids:
            new: dict[bytes, int] = {}
            for i, j in enumerate(ids):
                if j is None:
                    key = keys[i]
                    j = new.get(key)
                    if j is None:
                        j = new[key] = -1 - len(fresh)
                        fresh.append(key)
                    ids[i] = j
        sid[changed] = ids
        return sid, fresh

    def _numbered(self, n: int, fresh: list[bytes], e_next: np.ndarray, r_pos: np.ndarray,
                  r_next: np.ndarray) -> np.ndarray:
        """The ids of the new rows (by provisional id ``-1 - j``) from ``n`` on, as the
        enumeration orders them: by first appearance among the edges' next states (by
        ground action, then outcome), then among reality's other outcomes' next states (by
        :func:`~gdq_pddl.pddl.reachable.reality_ranks` of their ground action, then
        outcome); the index gets them."""
        later = np.flatnonzero(r_next < 0)
        later = later[np.argsort(self._real_rank[r_pos[later]], kind="stable")]
        seq = np.concatenate([e_next[e_next < 0], r_next[later]])
        _, first = np.unique(seq, return_index=True)  # provisional ids -k .. -1
        order = -1 - seq[np.sort(first)]  # j of each new row, in order of appearance
        new = np.empty(len(fresh), dtype=np.int64)
        new[order] = np.arange(n, n + len(fresh))
        self._index.update(zip(fresh, new.tolist(), strict=True))
        return new

    def _merged(self, bits: np.ndarray, r_pos: np.ndarray, col: np.ndarray,
                nxt: np.ndarray) -> tuple[np.ndarray, ...]:
        """Reality's outcomes ``(column, probability, next, stuck, gain)`` of the state of
        ``bits``, equal ones of a column (same next state, failed trial or not, gain)
        merged into the first, their probabilities summed in outcome order (only ground
        actions with several outcomes can have equal ones)."""
        stuck = self._real_stuck[r_pos]
        gain = self._gains.of(bits)[r_pos] if self.gains else np.zeros(len(r_pos))
        prob = self._real_prob[r_pos]
        several = np.flatnonzero(self._real_several[r_pos])
        if not len(several):
            return col, prob, nxt, stuck, gain
        c, t, s, g = col[several], nxt[several], stuck[several], gain[several]
        order = np.lexsort((g, s, t, c))  # stable: equals in outcome order
        c, t, s, g = c[order], t[order], s[order], g[order]
        starts = np.r_[True, (c[1:] != c[:-1]) | (t[1:] != t[:-1]) | (s[1:] != s[:-1])
                       | (g[1:] != g[:-1])]
        group = np.empty(len(order), dtype=np.int64)
        group[order] = np.cumsum(starts) - 1
        summed = np.bincount(group, weights=prob[several])  # in outcome order, from 0.0
        first = several[order[starts]]  # each group's first outcome
        keep = np.ones(len(r_pos), dtype=np.bool_)
        keep[several] = False
        keep[first] = True
        prob = prob.copy()
        prob[first] = summed
        return col[keep], prob[keep], nxt[keep], stuck[keep], gain[keep]

    def _compile(self, task: GroundTask) -> None:
        """Every ground action's outcomes as flat arrays (:meth:`_expand_one` reads them
        for all applicable ground actions at once). An *effect* is one outcome of one
        ground action (ground action ``k``'s from ``sum(len(ops[i].outcomes), i < k)``):
        its unconditional facts (``_bit_*``, grouped by effect) and its conditional
        effects (``_when``, ``_when_*``). The determinisation's edges (``_edge_*``: by
        ground action, then the kept outcomes in order) and reality's outcomes of
        probability > 0 (``_real_*``: by ground action, then outcome) point at their
        effects; a failed trial or an outcome that changes nothing stays (not
        ``_real_moves``)."""
        ops = task.ops
        first = np.cumsum([0] + [len(op.outcomes) for op in ops]).tolist()
        outcomes = [o for op in ops for o in op.outcomes]
        self._eff_op = np.repeat(np.arange(len(ops), dtype=np.int64),
                                 [len(op.outcomes) for op in ops])
        edges = [(k, first[k] + j) for k, op in enumerate(ops) for j in op.known]
        self._edge_op = np.array([k for k, _ in edges], dtype=np.int64)
        self._edge_eff = np.array([e for _, e in edges], dtype=np.int64)
        self._edge_ptr = np.searchsorted(self._edge_op, np.arange(len(ops) + 1))
        real = [(k, first[k] + j, o) for k, op in enumerate(ops)
                for j, o in enumerate(op.outcomes)
                if o.probability > 0 and not op.factored]  # a factored one's are drawn
        self._real = [o for _, _, o in real]
        real_op = np.array([k for k, _, _ in real], dtype=np.int64)
        self._real_ptr = np.searchsorted(real_op, np.arange(len(ops) + 1))
        self._real_eff = np.array([e for _, e, _ in real], dtype=np.int64)
        self._gains = RowGains(self._real)
        self._real_prob = np.array([o.probability for o in self._real], dtype=float)
        self._real_stuck = np.array([bool(o.stuck) for o in self._real], dtype=np.bool_)
        self._real_moves = np.array([o.moves() and not o.stuck for o in self._real],
                                    dtype=np.bool_)
        # the effects a state's edges or reality's moves read (not a failed trial's, nor
        # one of probability 0 the determinisation leaves out)
        used = {e for _, e in edges} | {e for (_, e, _), m in zip(real, self._real_moves,
                                                                   strict=True) if m}
        self._plain_eff = np.array([e for e, o in enumerate(outcomes)
                                    if e in used and (o.add or o.dele)], dtype=np.int64)
        self._bit_ptr, self._bit_word, self._bit_add, self._bit_del = effect_bits(
            [(o.add, o.dele) for o in outcomes])
        when = [(e, c) for e, o in enumerate(outcomes) if e in used for c in o.conditional]
        self._when = RowConditions([(p, n) for _, (p, n, _, _) in when])
        self._when_eff = np.array([e for e, _ in when], dtype=np.int64)
        self._when_op = self._eff_op[self._when_eff]
        self._when_ptr, self._when_word, self._when_add, self._when_del = effect_bits(
            [(a, d) for _, (_, _, a, d) in when])
        self._real_rank = reality_ranks(task)[real_op] if len(real_op) else real_op
        self._real_op = real_op
        self._real_several = np.diff(self._real_ptr)[real_op] > 1
        self._edge_several = np.diff(self._edge_ptr)[self._edge_op] > 1
        self._lead = np.full(len(outcomes), _STAYS, dtype=np.int64)

    def draw(self, x: int, k: int, rng: np.random.Generator) -> tuple[int, bool, float]:
        """Reality's outcome of factored ground action ``k`` in discovered state ``x``,
        drawn part by part from ``rng`` (:func:`~gdq_pddl.pddl.factored.sample_parts`,
        one uniform a part): ``(next id, stuck, gain)``, the next state discovered if it
        is new (a failed trial stays in ``x``; gain 0 without :attr:`gains`)."""
        op = self.task.ops[k]
        if not op.factored:
            raise ValueError(f"{op.name} is not factored: its outcomes are listed "
                             "(outcomes)")
        s = self.mask(x)
        o = combine(sample_parts(op.parts, rng))
        t = s if o.stuck else o.apply(s)
        key = t.to_bytes(8 * self.n_words, "little")
        y = self._index.get(key)
        if y is None:
            y = self._index[key] = self._n
            self._append([key])
        return y, o.stuck, (o.gain(s) if self.gains else 0.0)

    def best_gain(self, x: int, k: int) -> float:
        """The most an outcome of factored ground action ``k`` earns in state ``x`` that
        does not fail the trial (:func:`~gdq_pddl.pddl.factored.best_gain`)."""
        terms = self._fixed_gains.get(k)
        if terms is None:
            terms = self._fixed_gains[k] = gain_terms(self.task.ops[k].parts)
        return best_gain(terms, self.mask(x))

    def _holds_bits(self, bits: np.ndarray) -> np.ndarray:
        """bool[n_ops]: the ground action's precondition holds in the state of ``bits``
        (:func:`~gdq_pddl.pddl.wordrows.unpacked`; the enumeration's rule:
        :meth:`~gdq_pddl.pddl.wordrows.CompiledOp.applies`)."""
        ok = self._conditions.holds_bits(bits)
        if len(self._alt_op):  # one alternative of a disjunctive precondition
            met = np.zeros(len(ok), dtype=np.bool_)
            met[self._alt_op[self._alternatives.holds_bits(bits)]] = True
            ok &= met | self._plain
        return ok

    def _append(self, keys: list[bytes]) -> None:
        """Store newly discovered states (their rows' bytes, ids already in
        :attr:`_index`), growing the arrays by doubling."""
        if not keys:
            return
        rows = np.frombuffer(b"".join(keys), dtype="<u8").astype(np.uint64) \
            .reshape(-1, self.n_words)
        n, m = self._n, len(keys)
        if n + m > len(self._words):
            cap = max(2 * len(self._words), n + m)
            for name in ("_words", "_goal", "_expanded"):
                old = getattr(self, name)
                new = np.zeros((cap, *old.shape[1:]), dtype=old.dtype)
                new[:n] = old[:n]
                setattr(self, name, new)
        self._words[n:n + m] = rows
        self._goal[n:n + m] = goal_rows(self.task, rows)
        self._n = n + m

    def _require(self, x: int) -> bool:
        """Whether state ``x`` was expanded (False: a goal, never expanded); an error for
        a state not discovered or not expanded yet."""
        if not 0 <= x < self._n:
            raise IndexError(f"state {x} is not a discovered state (0 to {self._n - 1})")
        if self._expanded[x]:
            return True
        if self._goal[x]:
            return False
        raise ValueError(f"state {x} is not expanded yet: call expand([{x}]) first")

    def offered(self, x: int) -> np.ndarray:
        """int64[k]: the ground actions applicable in expanded state ``x``, increasing;
        empty for a dead end and a goal (unlike :attr:`StateGraph.offered
        <gdq_pddl.pddl.reachable.StateGraph.offered>`, which lists ground action 0 there)."""
        return self._offered[x] if self._require(x) else _NONE

    def applicable(self, x: int) -> np.ndarray:
        """int64: the ground actions whose precondition holds in state ``x``, expanded or
        not (a goal too), increasing."""
        return np.flatnonzero(self._holds_bits(unpacked(self.words[x])))

    def edges(self, x: int) -> tuple[np.ndarray, np.ndarray]:
        """``(op index, next id)`` of state ``x``'s determinisation edges: those
        :meth:`StateGraph.edges <gdq_pddl.pddl.reachable.StateGraph.edges>` gives, in its
        order (none for a goal)."""
        return self._edges[x] if self._require(x) else (_NONE, _NONE)

    def outcomes(self, x: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                        np.ndarray]:
        """Reality's outcomes of every offered action of expanded state ``x``: ``(column,
        probability, next id, stuck, gain)``, ``column`` an index into :meth:`offered`,
        merged and ordered as :func:`~gdq_pddl.pddl.outcomes.reality_outcomes` gives the
        state's pairs (gain all zeros without ``gains``; none for a goal). A factored
        ground action's column (:attr:`factored`) lists none: its outcome is drawn
        (:meth:`draw`), never listed."""
        if self._require(x):
            return self._outcomes[x]
        return _NONE, np.zeros(0), _NONE, np.zeros(0, dtype=np.bool_), np.zeros(0)

    def lookup(self, rows: np.ndarray) -> np.ndarray:
        """int64 id of each row of ``rows`` (``uint64[n, n_words]``), -1 where the state
        was not discovered."""
        rows = np.asarray(rows, dtype=np.uint64).reshape(-1, self.n_words)
        size = 8 * self.n_words
        data = np.ascontiguousarray(rows, dtype="<u8").tobytes()
        get = self._index.get
        return np.array([get(data[i:i + size], -1) for i in range(0, len(data), size)],
                        dtype=np.int64)

    def mask(self, x: int) -> int:
        """State ``x`` as a Python int bitmask over ``task.facts``."""
        if not 0 <= x < self._n:
            raise IndexError(f"state {x} is not a discovered state (0 to {self._n - 1})")
        return int.from_bytes(np.ascontiguousarray(self._words[x], dtype="<u8").tobytes(),
                              "little")

    def atoms(self, x: int) -> frozenset[str]:
        """The fluent atoms true in state ``x``."""
        return self.task.atoms(self.mask(x))
