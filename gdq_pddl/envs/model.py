"""The true dynamics of an office world, compiled to flat arrays, and one compiled step.

The simulator's hidden state is the *full* state ``(position, which doors are open)``,
indexed ``position * 2**n_doors + door_mask``. For every (full state, action) pair the
model lists its outcomes (probability, next full state, stuck flag) in CSR form:
outcomes of pair ``i = full_state * n_actions + action`` are ``ptr[i]:ptr[i+1]``.

The gymnasium env, the fast episode runner and value iteration all read these arrays,
so there is exactly one definition of the world's dynamics (:func:`compile_model`)
and one of a step (:func:`env_step`).
"""

from __future__ import annotations

import weakref
from collections.abc import Hashable, Iterable
from typing import NamedTuple, TypeVar

import numba
import numpy as np

from gdq_pddl.dynamics import COST_KINDS, CostDist
from gdq_pddl.limits import check_memory
from gdq_pddl.spaces import VERBS, LearnerSpaces
from gdq_pddl.world import World

PAIR_BYTES = 150
"""Memory one (state, action) pair takes while a model is compiled: its outcomes are
gathered as Python tuples and floats (at least one per pair) before becoming arrays."""

CAUSE_NONE, CAUSE_STUCK, CAUSE_GOAL, CAUSE_TIMEOUT = 0, 1, 2, 3
CAUSES = ("", "stuck", "goal", "timeout")
"""Why an episode ended, indexed by the cause code :func:`env_step` returns."""


class ModelArrays(NamedTuple):
    """The compiled true model (see the module docstring for the layout)."""

    n_actions: int
    n_doors: int
    r_max: float
    step_limit: int
    ptr: np.ndarray  # int64[n_full * n_actions + 1]
    prob: np.ndarray  # float64[n_outcomes]
    next: np.ndarray  # int64[n_outcomes], full state
    stuck: np.ndarray  # bool[n_outcomes]
    cost_kind: np.ndarray  # int64[n_actions], codes of COST_KINDS
    cost_a: np.ndarray  # float64[n_actions]
    cost_b: np.ndarray  # float64[n_actions]
    obs_of: np.ndarray  # int64[n_full], learner state of a full state
    pos_of: np.ndarray  # int64[n_full], position index of a full state
    area_of_pos: np.ndarray  # int64[n_positions], area number (0: none)


def full_state(world: World, position: str, open_doors: frozenset[str] = frozenset()) -> int:
    """Full-state index of ``position`` with the named doors open."""
    mask = sum(1 << i for i, d in enumerate(world.doors) if d.name in open_doors)
    return world.index[position] * (1 << len(world.doors)) + mask


def _outcomes(world: World, door_ids: dict[str, int], p: str, mask: int, verb: str,
              q: str) -> list[tuple[float, str, int, bool]]:
    """Outcomes ``(prob, position, mask, stuck)`` of ``verb q`` taken at ``p``."""
    noop = [(1.0, p, mask, False)]
    door = world.door_at.get(p)
    if verb in ("goto", "approach"):
        ns = world.walk_neighbours[p]
        wants_door = verb == "approach"
        if q not in ns or (q in world.door_at) != wants_door:
            return noop
        ok = world.navigation_success
        out = [(ok, q, mask, False)]
        out += [((1 - ok) / len(ns), n, mask, False) for n in ns]
        return out
    if verb in ("opendoor", "gothrough") and door is not None:
        bit = 1 << door_ids[door.name]
        is_open = bool(mask & bit)
        if verb == "opendoor" and q == p and not is_open:
            result = (door.success, p, mask | bit, False)
        elif verb == "gothrough" and is_open and q != p and q in door.sides:
            result = (door.success, q, mask, False)
        else:
            return noop
        out = [result, (door.stuck, p, mask, True)]
        out.append((1.0 - door.success - door.stuck, p, mask, False))
        return out
    return noop


K = TypeVar("K", bound=Hashable)


def merge_outcomes(outcomes: Iterable[tuple[K, float]]) -> dict[K, float]:
    """``{outcome: probability}`` of ``(outcome, probability)`` pairs: equal outcomes
    summed in the order given, those of probability 0 dropped, first appearance first."""
    merged: dict[K, float] = {}
    for key, pr in outcomes:
        if pr > 0.0:
            merged[key] = merged.get(key, 0.0) + pr
    return merged


def outcome_csr(n_pairs: int, pairs: Iterable[tuple[int, dict[tuple, float]]],
                dtypes: tuple[type, ...]) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The CSR arrays of per-pair outcome lists, as every compiled model kind stores them.

    ``pairs`` yields ``(pair index, {outcome: probability})`` in increasing pair order
    (a pair not yielded lists no outcome); an outcome is a tuple of fields, typed by
    ``dtypes``. Returns ``ptr`` (int64[n_pairs + 1]: outcomes of pair ``i`` are
    ``ptr[i]:ptr[i+1]``), ``prob`` (float64) and one array per outcome field.
    """
    counts = np.zeros(n_pairs, dtype=np.int64)
    keys: list[tuple] = []
    prob: list[float] = []
    for i, merged in pairs:
        counts[i] = len(merged)
        keys += merged
        prob += merged.values()
    ptr = np.zeros(n_pairs + 1, dtype=np.int64)
    np.cumsum(counts, out=ptr[1:])
    fields = [np.array([key[j] for key in keys], dtype=dt) for j, dt in enumerate(dtypes)]
    return ptr, np.array(prob, dtype=np.float64), fields


def cost_arrays(costs: list[CostDist]) -> dict[str, np.ndarray]:
    """``cost_kind``, ``cost_a`` and ``cost_b`` of every model kind, from one
    :class:`~gdq_pddl.world.CostDist` per action."""
    return {"cost_kind": np.array([COST_KINDS[c.kind] for c in costs], dtype=np.int64),
            "cost_a": np.array([c.a for c in costs], dtype=np.float64),
            "cost_b": np.array([c.b for c in costs], dtype=np.float64)}


_COMPILED: dict[int, tuple[weakref.ref, ModelArrays]] = {}


def compile_model(world: World) -> ModelArrays:
    """The world's true dynamics as :class:`ModelArrays` (read-only, compiled once per world).

    Every env, solver and analysis of the same :class:`World` object shares one copy:
    building it is the slowest part of making an env, and experiments make thousands.
    """
    hit = _COMPILED.get(id(world))
    if hit is not None and hit[0]() is world:
        return hit[1]
    model = _compile(world)
    for array in model:
        if isinstance(array, np.ndarray):
            array.setflags(write=False)
    _COMPILED[id(world)] = (weakref.ref(world), model)
    return model


def _compile(world: World) -> ModelArrays:
    spaces = LearnerSpaces(world)
    n_pos, n_doors = len(world.positions), len(world.doors)
    n_masks = 1 << n_doors
    n_full, n_actions = n_pos * n_masks, spaces.n_actions
    check_memory(n_full * n_actions * PAIR_BYTES,
                 f"{world.source}: {n_doors} doors: the simulator's true model ({n_pos} "
                 f"positions x 2**{n_doors} door states x {n_actions} actions)",
                 "give the world fewer doors (generated buildings run on a compact model: "
                 "gdq-pddl scale)")
    door_ids = {d.name: i for i, d in enumerate(world.doors)}
    obs_of = np.zeros(n_full, dtype=np.int64)
    pos_of = np.zeros(n_full, dtype=np.int64)
    for fs in range(n_full):
        pi, mask = divmod(fs, n_masks)
        p = world.positions[pi]
        door = world.door_at.get(p)
        pos_of[fs] = pi
        obs_of[fs] = spaces.state(p, door is not None and bool(mask >> door_ids[door.name] & 1))
    parts = [spaces.action_parts(a) for a in range(n_actions)]

    def pairs():
        for fs in range(n_full):
            pi, mask = divmod(fs, n_masks)
            p = world.positions[pi]
            for a, (verb, q) in enumerate(parts):
                yield fs * n_actions + a, merge_outcomes(
                    [((world.index[np_] * n_masks + nm, st), pr)
                     for pr, np_, nm, st in _outcomes(world, door_ids, p, mask, verb, q)])

    ptr, prob, (nxt, stuck) = outcome_csr(n_full * n_actions, pairs(), (np.int64, np.bool_))
    costs = [world.cost(*spaces.action_parts(a)) for a in range(n_actions)]
    area = np.array([world.area_of.get(p, 0) for p in world.positions], dtype=np.int64)
    return ModelArrays(
        n_actions=n_actions,
        n_doors=n_doors,
        r_max=float(world.r_max),
        step_limit=int(world.step_limit),
        ptr=ptr,
        prob=prob,
        next=nxt,
        stuck=stuck,
        **cost_arrays(costs),
        obs_of=obs_of,
        pos_of=pos_of,
        area_of_pos=area,
    )


assert VERBS[0] == "goto"  # the action layout above is verb-major from goto


@numba.njit(cache=True)
def sample_cost(kind: int, a: float, b: float, rng: np.random.Generator) -> float:
    """Draw one action cost (no draw at all for a constant)."""
    if kind == 0:
        return a
    if kind == 1:
        return a + (b - a) * rng.random()
    return max(0.0, a + b * rng.standard_normal())


@numba.njit(cache=True, inline="always")
def draw_outcome(ptr: np.ndarray, prob: np.ndarray, i: int, rng: np.random.Generator) -> int:
    """Draw one uniform and return the index of the outcome of pair ``i`` it selects from
    the CSR arrays ``ptr``/``prob`` (-1 if the pair lists no outcome).

    The one outcome draw of both model kinds (:func:`env_step`,
    :func:`gdq_pddl.envs.compact.compact_step`).
    """
    k, end = ptr[i], ptr[i + 1]
    u = rng.random()
    if end == k:
        return -1
    acc = prob[k]
    while u >= acc and k < end - 1:
        k += 1
        acc += prob[k]
    return k


@numba.njit(cache=True, inline="always")
def finish_step(m, action: int, nxt: int, stuck: bool, at_goal: bool, t: int,
                rng: np.random.Generator) -> tuple[int, float, bool, bool, int]:
    """Draw the cost of ``action`` and return ``(nxt, reward, terminated, truncated, cause)``
    for a step that led to ``nxt``: the reward and episode-end rule of both model kinds
    (``m``: :class:`ModelArrays` or :class:`~gdq_pddl.envs.compact.CompactModel`)."""
    cost = sample_cost(m.cost_kind[action], m.cost_a[action], m.cost_b[action], rng)
    if stuck:
        return nxt, -m.r_max, True, False, CAUSE_STUCK
    if at_goal:
        return nxt, m.r_max, True, False, CAUSE_GOAL
    if t + 1 >= m.step_limit:
        return nxt, -m.r_max, False, True, CAUSE_TIMEOUT
    return nxt, -cost, False, False, CAUSE_NONE


@numba.njit(cache=True, inline="always")
def env_step(m: ModelArrays, fs: int, action: int, t: int, goal_pos: int,
             rng: np.random.Generator) -> tuple[int, float, bool, bool, int]:
    """Take ``action`` in full state ``fs`` at step ``t`` (0-based) of an episode.

    Returns ``(next full state, reward, terminated, truncated, cause)``. Draws exactly
    one uniform for the outcome, then one cost draw if the cost is not constant.
    """
    k = draw_outcome(m.ptr, m.prob, fs * m.n_actions + action, rng)  # never -1 here
    nxt = m.next[k]
    return finish_step(m, action, nxt, m.stuck[k], m.pos_of[nxt] == goal_pos, t, rng)
