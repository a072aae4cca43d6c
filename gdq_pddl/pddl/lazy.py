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

A factored ground action (:attr:`GroundOp.parts <gdq_pddl.pddl.grounding.GroundOp.parts>`:
a forall of probabilistic effects whose product is too large to list) has its edges (the
determinisation's outcomes, each part's taken one at a time) but no listed outcome:
reality's outcome of it is drawn part by part when an agent takes it (:meth:`LazyGraph.draw`),
and the state it reaches is discovered then.

A state's effects are applied on its Python int bitmask by the ground task's own
outcomes (:meth:`GroundOutcome.apply <gdq_pddl.pddl.grounding.GroundOutcome.apply>`,
:meth:`GroundOutcome.gain <gdq_pddl.pddl.grounding.GroundOutcome.gain>`): for one
state that is some microseconds an outcome, where a numpy call on a one-row array costs
more than the whole effect.
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.pddl.grounding import GroundOp, GroundTask, combine, sample_parts
from gdq_pddl.pddl.reachable import reality_ranks
from gdq_pddl.pddl.wordrows import RowConditions, goal_rows

_NONE = np.zeros(0, dtype=np.int64)


def _compiled(op: GroundOp) -> tuple[tuple, tuple, tuple]:
    """A ground action for one state at a time: reality's outcomes ``(probability, stuck,
    apply or None (the state stays), gain or None (it depends on the state: see
    GroundOutcome.gain), outcome)`` of probability > 0, in outcome order; the edges'
    outcomes (a place in that tuple, or an apply of its own for an outcome reality leaves
    out); the places of the outcomes only reality reaches (those with an effect that are
    not the edges', failed trials aside), as :func:`~gdq_pddl.pddl.wordrows.compile_ops`
    sorts them."""
    place, reality = {}, []
    for j, o in enumerate(op.outcomes if not op.factored else ()):  # drawn, never listed
        if o.probability > 0:
            place[j] = len(reality)
            reality.append((o.probability, bool(o.stuck), o.apply if o.moves() and not o.stuck
                            else None, None if o.rewards else o.reward + 0.0, o))
    known = tuple(place[j] if j in place and not op.outcomes[j].stuck
                  else op.outcomes[j].apply for j in op.known)
    other = tuple(place[j] for j, o in enumerate(op.outcomes) if o.probability > 0
                  and not o.stuck and j not in op.known and o.moves() and j in place)
    return tuple(reality), known, other


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
        self._rank = reality_ranks(task).tolist()
        # ground actions whose every outcome only has conditional effects (IPPC boxworld:
        # all of them), and those effects' conditions: in a state where none holds, the
        # action leaves the state as it is, and its outcomes need not be applied one by one
        quiet, fire = np.zeros(len(task.ops), dtype=np.bool_), []
        for k, op in enumerate(task.ops):
            if not op.factored and not any(o.add or o.dele for o in op.outcomes):
                quiet[k] = True
                fire += [(k, p, n) for o in op.outcomes for p, n, _, _ in o.conditional]
        self._may_stay = quiet
        self._fire_op = np.array([k for k, _, _ in fire], dtype=np.int64)
        self._fires = RowConditions([(p, n) for _, p, n in fire])
        self._reality, self._known, self._other = zip(*map(_compiled, task.ops), strict=True) \
            if task.ops else ((), (), ())
        self.factored = np.array([op.factored for op in task.ops], dtype=np.bool_)
        """bool[n_ops]: the ground action is factored (:meth:`draw` its outcome)."""
        self._fixed_gains: dict[int, tuple] = {}  # best_gain's parts that do not vary
        self._gain_terms()
        self._masks: list[int] = [task.init]
        self._index: dict[int, int] = {task.init: 0}
        self._words = np.zeros((16, self.n_words), dtype=np.uint64)
        self._goal = np.zeros(16, dtype=np.bool_)
        self._expanded = np.zeros(16, dtype=np.bool_)
        self._n = 0
        self._append([task.init])
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
        masks of the states it discovers (already given ids in :attr:`_index`)."""
        s, index, fresh = self._masks[x], self._index, []
        n = self._n

        def id_of(t: int) -> int:
            i = index.get(t)
            if i is None:
                i = index[t] = n + len(fresh)
                fresh.append(t)
            return i

        row = self._words[x]
        acts = self._applicable(row).tolist()
        reality, gains = self._reality, self.gains
        stays = self._stays(row).tolist()
        nexts = [[s] * len(reality[k]) if stays[k] else
                 [s if apply is None else apply(s) for _, _, apply, _, _ in reality[k]]
                 for k in acts]  # each outcome applied once
        edge_op, edge_next = [], []
        for k, ts in zip(acts, nexts, strict=True):  # by ground action, then kept outcome
            if stays[k]:  # every outcome the planner knows stays in x
                if self._known[k]:
                    edge_op.append(k)
                    edge_next.append(x)
                continue
            seen: dict[int, None] = {}
            for at in self._known[k]:
                t = ts[at] if isinstance(at, int) else at(s)
                if t not in seen:  # each state once a ground action
                    seen[t] = None
                    edge_op.append(k)
                    edge_next.append(id_of(t))
        for k, ts in sorted(((k, ts) for k, ts in zip(acts, nexts, strict=True)
                             if self._other[k] and not stays[k]), key=lambda e: self._rank[e[0]]):
            for at in self._other[k]:
                id_of(ts[at])
        column, prob, nxt, stuck, gain = [], [], [], [], []
        worth, first = self._gains(row) if gains else None, self._first
        for c, (k, ts) in enumerate(zip(acts, nexts, strict=True)):  # reality, merged
            if len(ts) == 1:  # one outcome (most ground actions): nothing to merge
                p, st, _, _, _ = reality[k][0]
                column.append(c)
                prob.append(p)
                nxt.append(index[ts[0]])
                stuck.append(st)
                gain.append(worth[first[k]] if worth is not None else 0.0)
                continue
            merged: dict[tuple, float] = {}
            for i, (t, (p, st, _, _, _)) in enumerate(zip(ts, reality[k], strict=True)):
                key: tuple = (index[t], st)
                if worth is not None:
                    key += (worth[first[k] + i],)
                merged[key] = merged.get(key, 0.0) + p  # summed in outcome order
            for key, p in merged.items():
                column.append(c)
                prob.append(p)
                nxt.append(key[0])
                stuck.append(key[1])
                gain.append(key[2] if gains else 0.0)
        self._offered[x] = np.array(acts, dtype=np.int64)
        self._edges[x] = (np.array(edge_op, dtype=np.int64),
                          np.array(edge_next, dtype=np.int64))
        self._outcomes[x] = (np.array(column, dtype=np.int64), np.array(prob, dtype=float),
                             np.array(nxt, dtype=np.int64), np.array(stuck, dtype=np.bool_),
                             np.array(gain, dtype=float))
        self._expanded[x] = True
        return fresh

    def draw(self, x: int, k: int, rng: np.random.Generator) -> tuple[int, bool, float]:
        """Reality's outcome of factored ground action ``k`` in discovered state ``x``,
        drawn part by part from ``rng`` (:func:`~gdq_pddl.pddl.grounding.sample_parts`,
        one uniform a part): ``(next id, stuck, gain)``, the next state discovered if it
        is new (a failed trial stays in ``x``; gain 0 without :attr:`gains`)."""
        op = self.task.ops[k]
        if not op.factored:
            raise ValueError(f"{op.name} is not factored: its outcomes are listed "
                             "(outcomes)")
        s = self._masks[x]
        o = combine(sample_parts(op, rng))
        t = s if o.stuck else o.apply(s)
        y = self._index.get(t)
        if y is None:
            y = self._index[t] = self._n
            self._append([t])
        return y, o.stuck, (o.gain(s) if self.gains else 0.0)

    def best_gain(self, x: int, k: int) -> float:
        """The most an outcome of factored ground action ``k`` earns in state ``x`` that
        does not fail the trial (where one can: every part has such an outcome; else of
        all): each part's most, added up, as the gains of its parts add up."""
        s = self._masks[x]
        fixed = self._fixed_gains.get(k)
        if fixed is None:  # the parts whose outcomes earn the same in every state, once
            parts = self.task.ops[k].parts
            same = [part for part in parts if not any(o.rewards for o in part)]
            live = [[o.reward for o in part if not o.stuck] for part in same]
            fixed = self._fixed_gains[k] = (
                all(live), sum(max(g) for g in live if g), sum(max(o.reward for o in part)
                                                              for part in same),
                [part for part in parts if any(o.rewards for o in part)])
        all_live, live_sum, any_sum, varying = fixed
        live = [[o.gain(s) for o in part if not o.stuck] for part in varying]
        if all_live and all(live):
            return float(live_sum + sum(max(g) for g in live))
        return float(any_sum + sum(max(o.gain(s) for o in part) for part in varying))

    def _gain_terms(self) -> None:
        """Reality's outcomes of every ground action as one flat list (ground action
        ``k``'s from ``_first[k]``), their fixed rewards and their conditional rewards'
        conditions, so that :meth:`_gains` values them all in a state at once."""
        first, base, entry, amount, alts, term = [], [], [], [], [], []
        for outcomes in self._reality:
            first.append(len(base))
            for _, _, _, fixed, o in outcomes:
                base.append(fixed if fixed is not None else o.reward)
                for alternatives, worth in (o.rewards if fixed is None else ()):
                    term += [len(entry)] * len(alternatives)
                    alts += list(alternatives)
                    entry.append(len(base) - 1)
                    amount.append(worth)
        self._first = first
        self._base_gain = np.array(base, dtype=float)
        self._term_entry = np.array(entry, dtype=np.int64)
        self._term_amount = np.array(amount, dtype=float)
        self._alt_term = np.array(term, dtype=np.int64)
        self._reward_alts = RowConditions(alts)

    def _gains(self, row: np.ndarray) -> list[float]:
        """Each outcome's reward in the state of ``row``, by :meth:`_gain_terms`'s flat
        list: as :meth:`GroundOutcome.gain <gdq_pddl.pddl.grounding.GroundOutcome.gain>`
        sums them (the fixed reward plus the amounts of the terms one of whose
        alternatives holds, in order)."""
        if not len(self._term_entry):
            return self._base_gain.tolist()
        held = np.zeros(len(self._term_entry), dtype=np.bool_)
        held[self._alt_term[self._reward_alts.holds(row)]] = True
        extra = np.bincount(self._term_entry[held], weights=self._term_amount[held],
                            minlength=len(self._base_gain))
        return (self._base_gain + extra).tolist()

    def _stays(self, row: np.ndarray) -> np.ndarray:
        """bool[n_ops]: the ground action leaves the state of ``row`` as it is, whatever
        its outcome (no effect but conditional ones, none of whose conditions holds)."""
        stays = self._may_stay.copy()
        if len(self._fire_op):
            stays[self._fire_op[self._fires.holds(row)]] = False
        return stays

    def _applicable(self, row: np.ndarray) -> np.ndarray:
        """int64: the ground actions whose precondition holds in ``row``, increasing (the
        enumeration's rule: :meth:`~gdq_pddl.pddl.wordrows.CompiledOp.applies`)."""
        ok = self._conditions.holds(row)
        if len(self._alt_op):  # one alternative of a disjunctive precondition
            met = np.zeros(len(ok), dtype=np.bool_)
            met[self._alt_op[self._alternatives.holds(row)]] = True
            ok &= met | self._plain
        return np.flatnonzero(ok)

    def _append(self, masks: list[int]) -> None:
        """Store newly discovered states (their ids already in :attr:`_index`), growing
        the arrays by doubling."""
        if not masks:
            return
        rows = self._rows(masks)
        n, m = self._n, len(masks)
        if n + m > len(self._words):
            cap = max(2 * len(self._words), n + m)
            for name in ("_words", "_goal", "_expanded"):
                old = getattr(self, name)
                new = np.zeros((cap, *old.shape[1:]), dtype=old.dtype)
                new[:n] = old[:n]
                setattr(self, name, new)
        self._words[n:n + m] = rows
        self._goal[n:n + m] = goal_rows(self.task, rows)
        if n:  # state 0's mask is in place from the start
            self._masks.extend(masks)
        self._n = n + m

    def _rows(self, masks: list[int]) -> np.ndarray:
        """uint64[len(masks), n_words]: bitmasks as word rows (fact ``f`` is bit ``f % 64``
        of word ``f // 64``, as :func:`~gdq_pddl.pddl.wordrows.words`)."""
        size = 8 * self.n_words
        data = b"".join(m.to_bytes(size, "little") for m in masks)
        return np.frombuffer(data, dtype="<u8").astype(np.uint64).reshape(-1, self.n_words)

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
        return self._applicable(self.words[x])

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
        data = rows.astype("<u8").tobytes()
        get = self._index.get
        return np.array([get(int.from_bytes(data[i:i + size], "little"), -1)
                         for i in range(0, len(data), size)], dtype=np.int64)

    def mask(self, x: int) -> int:
        """State ``x`` as a Python int bitmask over ``task.facts``."""
        return self._masks[x]

    def atoms(self, x: int) -> frozenset[str]:
        """The fluent atoms true in state ``x``."""
        return self.task.atoms(self._masks[x])
