"""States as rows of ``uint64`` words (one bit a fact), and ground actions compiled onto
them: what the enumeration (:mod:`gdq_pddl.pddl.reachable`) and reality's outcomes
(:mod:`gdq_pddl.pddl.outcomes`) apply to a whole block of states at once.

:func:`words` turns a fact bitmask into a row (:func:`unpacked`: a row into one flag a
fact), :func:`holds` tests a condition on rows (:class:`RowConditions`: many conditions on
one row; :class:`RowGains`: what many outcomes earn there; :func:`effect_bits` and
:func:`spans`: many effects' facts, flat),
:func:`row_keys` gives each row a sortable key (:class:`KeyIndex` finds them),
:func:`compile_ops` compiles a task's ground actions (:class:`CompiledOp`: when one
applies, its outcomes' effects as :class:`RowEffect`, which applies one and says what it
earns). :func:`applicable_rows`
finds where a ground action applies, testing it only on the rows where its rarest
precondition fact holds (:func:`fact_rows`, on chunks of at most :func:`filter_chunk`
rows).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gdq_pddl.pddl.grounding import GroundOutcome, GroundTask, set_bits


def words(mask: int, n_words: int) -> np.ndarray:
    """A fact bitmask as a row of ``n_words`` uint64 words (its bytes, little-endian: a
    shift per word cost 40 us a row at 256 words, and compiling pddlgym's 32,004 ground
    actions of 16,383 facts made 800,000 rows)."""
    return np.frombuffer(mask.to_bytes(8 * n_words, "little"), dtype="<u8").astype(np.uint64)


def holds(rows: np.ndarray, pos: np.ndarray, neg: np.ndarray) -> np.ndarray:
    """bool[n]: ``pos`` holds and no fact of ``neg`` in each row."""
    return ((rows & pos) == pos).all(axis=1) & ~(rows & neg).any(axis=1)


class RowConditions:
    """Conditions ``(must hold, must not hold)`` (fact bitmasks) kept as lists of facts,
    tested on one row at a time (:meth:`holds`): for one state that reads each condition's
    few facts, where :func:`holds` on a stack of every condition's rows reads every word
    of every row (pddlgym's exploding blocks of 126 blocks: 25 ms a state, 32,004 ground
    actions x 256 words)."""

    def __init__(self, conditions: list[tuple[int, int]]) -> None:
        self.n = len(conditions)
        pos = [list(set_bits(p)) for p, _ in conditions]
        neg = [list(set_bits(n)) for _, n in conditions]
        self.pos_of, self.pos_fact = _flat(pos)
        self.neg_of, self.neg_fact = _flat(neg)

    def holds(self, row: np.ndarray) -> np.ndarray:
        """bool[n]: each condition holds in the word row ``row``."""
        return self.holds_bits(unpacked(row))

    def holds_bits(self, bits: np.ndarray) -> np.ndarray:
        """bool[n]: each condition holds in the state whose facts are ``bits`` (bool, fact
        ``f`` at ``bits[f]``: a word row unpacked, little-endian bit order), for several
        sets of conditions tested on one state unpacking it once."""
        missing = np.bincount(self.pos_of[~bits[self.pos_fact]], minlength=self.n)
        present = np.bincount(self.neg_of[bits[self.neg_fact]], minlength=self.n)
        return (missing == 0) & (present == 0)


class RowGains:
    """What each of many ground outcomes (:class:`~gdq_pddl.pddl.grounding.GroundOutcome`)
    earns in one state, all at once (:meth:`of`): its fixed reward plus the amount of each
    conditional reward one of whose alternatives holds (:class:`RowConditions`)."""

    def __init__(self, outcomes: list[GroundOutcome]) -> None:
        base, entry, amount, alts, term = [], [], [], [], []
        for o in outcomes:
            base.append(o.reward if o.rewards else o.reward + 0.0)
            for alternatives, worth in o.rewards:
                term += [len(entry)] * len(alternatives)
                alts += list(alternatives)
                entry.append(len(base) - 1)
                amount.append(worth)
        self.base = np.array(base, dtype=float)
        self.entry = np.array(entry, dtype=np.int64)
        self.amount = np.array(amount, dtype=float)
        self.alt_term = np.array(term, dtype=np.int64)
        self.alts = RowConditions(alts)

    def of(self, bits: np.ndarray) -> np.ndarray:
        """float64: each outcome's reward in the state of ``bits`` (as
        :meth:`RowConditions.holds_bits` reads them), as ``GroundOutcome.gain`` sums it."""
        if not len(self.entry):
            return self.base
        held = np.zeros(len(self.entry), dtype=np.bool_)
        held[self.alt_term[self.alts.holds_bits(bits)]] = True
        return self.base + np.bincount(self.entry[held], weights=self.amount[held],
                                       minlength=len(self.base))


def _flat(lists: list[list[int]]) -> tuple[np.ndarray, np.ndarray]:
    """``(which list, item)`` of every item of ``lists``, as int64 arrays."""
    which = np.repeat(np.arange(len(lists), dtype=np.int64), [len(x) for x in lists])
    items = np.array([f for x in lists for f in x], dtype=np.int64)
    return which, items


def unpacked(row: np.ndarray) -> np.ndarray:
    """bool[64 n_words]: fact ``f`` of a word row (bit ``f % 64`` of word ``f // 64``)."""
    return np.unpackbits(np.ascontiguousarray(row, dtype="<u8").view(np.uint8),
                         bitorder="little").view(np.bool_)


def spans(ptr: np.ndarray, items: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(positions, owner)``: the positions ``ptr[i] .. ptr[i + 1] - 1`` of each listed
    item ``i`` of a flat list grouped by item (``ptr``: where each item's part starts), in
    the order listed, and the place in ``items`` of the item each belongs to."""
    starts = ptr[items]
    lengths = ptr[items + 1] - starts
    owner = np.repeat(np.arange(len(items), dtype=np.int64), lengths)
    ends = np.cumsum(lengths)
    return np.arange(int(ends[-1]) if len(ends) else 0, dtype=np.int64) + \
        np.repeat(starts - ends + lengths, lengths), owner


def effect_bits(effects: list[tuple[int, int]]) -> tuple[np.ndarray, ...]:
    """The facts ``(add, delete)`` masks of each effect set or clear as a flat list
    grouped by effect (adds first): ``(ptr, word, add bit, delete bit)``, one entry a
    fact, its bit in ``add bit`` or in ``delete bit`` (0 in the other)."""
    owner, flat = _flat([list(set_bits(m)) for pair in effects for m in pair])
    word, bit = flat >> 6, np.left_shift(np.uint64(1), (flat & 63).astype(np.uint64))
    is_add = owner % 2 == 0
    order = np.argsort(owner // 2, kind="stable")
    zero = np.zeros(len(bit), dtype=np.uint64)
    ptr = np.searchsorted(owner[order] // 2, np.arange(len(effects) + 1))
    return (ptr.astype(np.int64), word[order], np.where(is_add, bit, zero)[order],
            np.where(is_add, zero, bit)[order])


def row_keys(rows: np.ndarray) -> np.ndarray:
    """One sortable key per row (the word itself, or the row's bytes)."""
    rows = np.ascontiguousarray(rows)
    if rows.shape[1] == 1:
        return rows[:, 0]
    return rows.view(np.dtype((np.void, 8 * rows.shape[1]))).ravel()


class KeyIndex:
    """Row keys (:func:`row_keys`) and their numbers, as sorted runs of decreasing
    length (a run is merged into the one before once that is at most twice as long), so
    each key is copied O(log n) times in all, where inserting every chunk's keys into one
    sorted array copied all n keys a chunk (the enumeration of manytireworld_test problem0:
    most of its time past 5 million states)."""

    def __init__(self, keys: np.ndarray, ids: np.ndarray) -> None:
        self.runs: list[tuple[np.ndarray, np.ndarray]] = [(keys, ids)]

    def find(self, keys: np.ndarray) -> np.ndarray:
        """int64: each key's state number, -1 where it is not known."""
        out = np.full(len(keys), -1, dtype=np.int64)
        for have, ids in self.runs:
            at = np.minimum(np.searchsorted(have, keys), len(have) - 1)
            hit = have[at] == keys
            out[hit] = ids[at[hit]]
        return out

    def add(self, keys: np.ndarray, ids: np.ndarray) -> None:
        """Known from now: ``keys`` (none known yet, distinct) numbered ``ids``."""
        if not len(keys):
            return
        order = np.argsort(keys, kind="stable")
        keys, ids = keys[order], ids[order]
        while self.runs and len(self.runs[-1][0]) <= 2 * len(keys):
            have, have_ids = self.runs.pop()
            where = np.searchsorted(have, keys)
            keys, ids = np.insert(have, where, keys), np.insert(have_ids, where, ids)
        self.runs.append((keys, ids))


@dataclass(frozen=True)
class RowEffect:
    """What one outcome of a ground action does (a
    :class:`~gdq_pddl.pddl.grounding.GroundOutcome`) on word rows: its adds, deletes and
    conditional effects (:meth:`apply`), and what it earns besides the action's cost
    (:meth:`gain`), as ``GroundOutcome.apply`` and ``GroundOutcome.gain`` do on one
    state's bitmask."""

    add: np.ndarray
    dele: np.ndarray
    conditional: tuple[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], ...] = ()
    reward: float = 0.0
    rewards: tuple[tuple[tuple[tuple[np.ndarray, np.ndarray], ...], float], ...] = ()

    @classmethod
    def of(cls, outcome: GroundOutcome, n_words: int,
           zero: np.ndarray | None = None) -> RowEffect:
        """``outcome`` on rows of ``n_words`` words (``zero``: the row of no fact, shared
        by every empty mask)."""
        def w(mask: int) -> np.ndarray:
            return zero if not mask and zero is not None else words(mask, n_words)

        return cls(w(outcome.add), w(outcome.dele),
                   tuple(tuple(map(w, c)) for c in outcome.conditional), float(outcome.reward),
                   tuple((tuple((w(p), w(n)) for p, n in alts), amount)
                         for alts, amount in outcome.rewards))

    def apply(self, rows: np.ndarray) -> np.ndarray:
        """The rows after the effect (adds win)."""
        add, dele = self.add, self.dele
        if self.conditional:
            add, dele = np.broadcast_to(add, rows.shape), np.broadcast_to(dele, rows.shape)
            for pos, neg, a, d in self.conditional:
                fire = holds(rows, pos, neg)[:, None]
                add, dele = add | np.where(fire, a, 0), dele | np.where(fire, d, 0)
        return (rows & ~dele) | add

    def gain(self, rows: np.ndarray) -> np.ndarray:
        """float64[n]: what the outcome earns taken in each row (its rewards less its
        costs inside ``when``, ``forall`` and ``probabilistic``)."""
        earned = np.zeros(len(rows))
        for alts, amount in self.rewards:
            earned = earned + np.where(np.logical_or.reduce(
                [holds(rows, p, n) for p, n in alts]), amount, 0.0)
        return self.reward + earned


@dataclass(frozen=True)
class CompiledOp:
    """A ground action on word rows: when it applies, its effects (``known``: the edges,
    ``other``: the states only reality reaches, both in ``outcomes``) and their ranks in a
    state's order."""

    pre: np.ndarray
    neg: np.ndarray
    alternatives: tuple[tuple[np.ndarray, np.ndarray], ...]
    known: tuple[RowEffect, ...]
    other: tuple[RowEffect, ...]
    outcomes: tuple[RowEffect, ...] = ()
    """Every outcome of the ground action, in its order (a STRIPS action: its one); empty
    unless compiled so (``compile_ops(..., every=True)``)."""

    def applies(self, rows: np.ndarray) -> np.ndarray:
        ok = holds(rows, self.pre, self.neg)
        if self.alternatives:
            ok &= np.logical_or.reduce([holds(rows, p, n) for p, n in self.alternatives])
        return ok


FILTER_BYTES = 1 << 27
"""The most bytes :func:`fact_rows` spends on a chunk's per-fact membership (else every
ground action is tested on every state of the chunk)."""


def filter_chunk(need: list[np.ndarray]) -> int:
    """The most rows of a chunk :func:`fact_rows` lists the rows of every fact in ``need``
    for (a larger chunk gets None, and every ground action is tested on every row)."""
    n_facts = len(np.unique(np.concatenate(need))) if need else 0
    return FILTER_BYTES // max(1, n_facts)


def positive_facts(pre: np.ndarray) -> np.ndarray:
    """The facts (bit numbers) set in a word row ``pre``."""
    bits = np.unpackbits(pre.view(np.uint8), bitorder="little")
    return np.flatnonzero(bits)


def fact_rows(rows: np.ndarray, need: list[np.ndarray]) -> dict[int, np.ndarray] | None:
    """For each fact some ground action needs, the rows (increasing) where it holds; None
    when that is more than :data:`FILTER_BYTES` facts x rows to look at."""
    facts = np.unique(np.concatenate(need)) if need else np.zeros(0, dtype=np.int64)
    if not len(facts) or len(facts) * len(rows) > FILTER_BYTES:
        return None
    words = {int(w): np.ascontiguousarray(rows[:, w]) for w in np.unique(facts // 64)}
    return {f: np.flatnonzero(words[f // 64] & np.uint64(1 << f % 64))
            for f in facts.tolist()}


def applicable_rows(op: CompiledOp, rows: np.ndarray, holding: dict[int, np.ndarray] | None,
                need: np.ndarray) -> np.ndarray:
    """The rows (increasing) where ``op`` applies: tested only on the rows where its
    rarest needed fact holds, when ``holding`` lists them."""
    if holding is None or not len(need):
        return np.flatnonzero(op.applies(rows))
    cand = min((holding[int(f)] for f in need.tolist()), key=len)
    return cand[op.applies(rows[cand])] if len(cand) else cand


def compile_ops(task: GroundTask, n_words: int, every: bool = False) -> list[CompiledOp]:
    """Every ground action of ``task`` on rows of ``n_words`` words; ``every``: with all
    its outcomes (:attr:`CompiledOp.outcomes`, what reality's outcomes read), not only
    those that lead somewhere new (the enumeration's)."""
    zero = words(0, n_words)
    zero.setflags(write=False)

    def w(mask: int) -> np.ndarray:
        return words(mask, n_words)

    def effect(o) -> RowEffect:
        return RowEffect.of(o, n_words, zero)

    out = []
    for op in task.ops:
        alts = tuple((w(p), w(n)) for p, n in op.alternatives) if task.disjunctive else ()
        lead = [j for j, o in enumerate(op.outcomes) if o.probability > 0 and not o.stuck
                and j not in op.known and o.moves()]
        need = range(len(op.outcomes)) if every else (*op.known, *lead)
        made = {j: effect(op.outcomes[j]) for j in need}
        known = tuple(made[k] for k in op.known)
        other = tuple(made[j] for j in lead)
        effects = tuple(made[j] for j in range(len(op.outcomes))) if every else ()
        out.append(CompiledOp(w(op.pre), w(op.neg), alts, known, other, effects))
    return out


def goal_rows(task: GroundTask, rows: np.ndarray) -> np.ndarray:
    """bool[n]: :meth:`GroundTask.is_goal` of each row."""
    n_words = rows.shape[1]
    if not task.goal_possible:
        return np.zeros(len(rows), dtype=np.bool_)
    ok = holds(rows, words(task.goal_pos, n_words), words(task.goal_neg, n_words))
    if task.goal_alternatives:
        ok &= np.logical_or.reduce([holds(rows, words(p, n_words), words(n, n_words))
                                    for p, n in task.goal_alternatives])
    return ok
