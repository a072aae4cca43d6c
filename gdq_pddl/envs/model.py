"""The true dynamics of a world, compiled to flat arrays: a
:class:`~gdq_pddl.envs.step.ModelArrays` (its layout, and the one compiled step on it,
are in :mod:`gdq_pddl.envs.step`).

A model is compiled over a :class:`StateSpace`, the states an env steps through and what
the learner sees of them: a PDDL problem's reachable state graph, or every (position,
open doors) state of the office (:func:`office_space`). The gymnasium env, the fast
episode runner and value iteration all read the arrays, so there is exactly one
definition of the world's dynamics (:func:`compile_true_model`, and the office's
:func:`compile_model`).
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Hashable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from gdq_pddl.abstraction import OfficeAbstraction
from gdq_pddl.dynamics import COST_KINDS, CostDist, Dynamics, Outcomes, split_action
from gdq_pddl.envs.step import (
    CAUSE_GOAL,
    CAUSE_NONE,
    CAUSE_STUCK,
    CAUSE_TIMEOUT,
    CAUSES,
    ModelArrays,
    draw_outcome,
    env_act,
    env_step,
    file_step,
    finish_step,
    pair_of,
    sample_cost,
    width_of,
)
from gdq_pddl.limits import check_memory, slow_progress
from gdq_pddl.pddl.grounding import GroundTask
from gdq_pddl.planning.base import PlanningProblem
from gdq_pddl.resources import domain_text
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world_types import Task, World, office_problem

__all__ = [  # the step's names too, which this module held before envs/step.py
    "CAUSES", "CAUSE_GOAL", "CAUSE_NONE", "CAUSE_STUCK", "CAUSE_TIMEOUT", "NOOP_CHUNK",
    "PAIR_BYTES", "ModelArrays", "StateSpace", "compile_model", "compile_true_model",
    "cost_arrays", "draw_outcome", "env_act", "env_step", "file_step", "finish_step",
    "full_state", "ground_outcomes", "merge_outcomes", "office_costs", "office_space",
    "outcome_csr", "pair_of", "per_object", "reality_task", "sample_cost", "slip_outcomes",
    "width_of", "with_noops"]

PAIR_BYTES = 150
"""Memory one (state, action) pair takes while a model is compiled: its outcomes are
gathered as Python tuples and floats (at least one per pair) before becoming arrays."""

NOOP_CHUNK = 1 << 20
"""Pairs whose no-op states :func:`with_noops` writes at a time."""


def full_state(world: World, position: str, open_doors: frozenset[str] = frozenset()) -> int:
    """Full-state index of ``position`` with the named doors open."""
    mask = sum(1 << i for i, d in enumerate(world.doors) if d.name in open_doors)
    return world.index[position] * (1 << len(world.doors)) + mask


K = TypeVar("K", bound=Hashable)
V = TypeVar("V")
_PER_OBJECT: dict[tuple[int, Hashable], tuple[weakref.ref, object]] = {}


def per_object(obj: object, key: Hashable, build: Callable[[], V]) -> V:
    """``build()``, once per live ``obj`` (a world, a model's array...) and ``key``: the
    caches of what is slow to build from an object and shared by every env of it (an id
    that a collected object left to a new one is not a hit)."""
    hit = _PER_OBJECT.get((id(obj), key))
    if hit is None or hit[0]() is not obj:
        hit = _PER_OBJECT[id(obj), key] = (weakref.ref(obj), build())
    return hit[1]  # type: ignore[return-value]


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


def with_noops(row_pair: np.ndarray, prob: np.ndarray, fields: list[np.ndarray],
               n_pairs: int, width: int, offered: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The CSR arrays (``ptr``, ``prob``, fields) of outcome rows in pair order
    (``row_pair``: each row's pair; fields: next state, stuck, and maybe a reward) with
    every pair of the ``n_pairs`` (``width`` a state) that lists no outcome given one: a
    no-op, ``(its state, not stuck, reward 0)`` with probability 1; a padding column of
    ``offered`` (-1) gets none. Filled without a Python loop, and with no temporary over
    all pairs but the no-ops' states, a chunk at a time (a bar counts the arrays filled
    past 2 s)."""
    with slow_progress("true model", " arrays", len(fields) + 2) as bar:
        lead = np.ones(len(row_pair), dtype=np.bool_)
        lead[1:] = row_pair[1:] != row_pair[:-1]
        first = np.flatnonzero(lead)
        listed, counts = row_pair[first], np.diff(np.append(first, len(row_pair)))
        new_ptr = np.ones(n_pairs + 1, dtype=np.int64)
        new_ptr[0] = 0
        if offered is not None:
            new_ptr[1:] = offered.ravel() >= 0
        new_ptr[listed + 1] = counts
        np.cumsum(new_ptr, out=new_ptr)
        at = np.repeat(new_ptr[listed] - first, counts) + np.arange(len(prob))
        bar.update()
        out_prob = np.ones(new_ptr[-1], dtype=np.float64)
        out_prob[at] = prob
        bar.update()
        out = [np.zeros(new_ptr[-1], dtype=f.dtype) for f in fields]
        for lo in range(0, n_pairs, NOOP_CHUNK):  # a no-op stays; listed pairs overwritten next
            hi = min(lo + NOOP_CHUNK, n_pairs)
            row = new_ptr[lo:hi]
            keep = row < new_ptr[lo + 1:hi + 1]  # padding pairs have no row to write
            out[0][row[keep]] = (np.arange(lo, hi) // width)[keep]
        for field, given in zip(out, fields, strict=True):
            field[at] = given
            bar.update()
    return new_ptr, out_prob, out


def cost_arrays(costs: list[CostDist]) -> dict[str, np.ndarray]:
    """``cost_kind``, ``cost_a`` and ``cost_b`` of every model kind, from one
    :class:`~gdq_pddl.dynamics.CostDist` per action."""
    return {"cost_kind": np.array([COST_KINDS[c.kind] for c in costs], dtype=np.int64),
            "cost_a": np.array([c.a for c in costs], dtype=np.float64),
            "cost_b": np.array([c.b for c in costs], dtype=np.float64)}


@dataclass(frozen=True, eq=False)
class StateSpace:
    """The states an env steps through, as planner states of one grounded task, and what
    the learner sees of them: an observation map applied to the task.

    A PDDL problem's (:func:`graph_space`) is its reachable state graph, seen as it is;
    the office's (:func:`office_space`) is every (position, open doors) state of the
    building, seen through O (the learner's 31 states and 95 verb-major actions).
    """

    task: GroundTask
    n_states: int
    edges: Callable[[int], list[tuple[int, int]]]
    """``(ground action, next state)`` of every ground action that works in state ``i``
    (none: every action is a no-op there, as at a goal the graph does not expand), in
    the order a slip lists its outcomes: a PDDL problem's in ground-action order, the
    office's in state order (by position: "a random walking neighbour")."""
    n_actions: int
    action_of_op: tuple[int, ...]
    """The learner action of each ground action (the first applicable one acts)."""
    obs_of: np.ndarray
    """int64[n_states]: the learner state of each state."""
    pos_of: np.ndarray
    """int64[n_states]: what :func:`~gdq_pddl.envs.step.env_step`'s goal test compares
    with ``goal_pos``."""
    area_of_pos: np.ndarray
    n_doors: int = 0
    offered: np.ndarray | None = None
    """int64[n_states, width]: the actions each state offers (a PDDL problem's applicable
    ground actions, -1 padding; :attr:`~gdq_pddl.pddl.reachable.StateGraph.offered`);
    None: every learner action in every state (the office)."""


def slip_outcomes(here: Hashable, applicable: Mapping[int, Hashable],
                  action_of_op: Sequence[int], outcomes: list[Outcomes],
                  schema_of: list[str]) -> Iterator[tuple[int, list]]:
    """Per learner action, in increasing order, that the ground actions applicable
    ``here`` map to (``applicable``: ground action -> where its effect leads; the first of
    them acts): ``((next, stuck), probability)`` of its outcomes, in the order the model
    lists them: its effect, the stuck trial, then what the rest ``1 - success - stuck``
    does (nothing, or the effect of a uniformly random applicable ground action of the
    slip's schemas, in the order of ``applicable``)."""
    acting: dict[int, int] = {}
    for k in applicable:
        acting.setdefault(action_of_op[k], k)
    for a in sorted(acting):
        o = outcomes[acting[a]]
        rest = max(0.0, 1.0 - o.success - o.stuck)
        out = [((applicable[acting[a]], False), o.success), ((here, True), o.stuck)]
        slips = [u for k, u in applicable.items()
                 if isinstance(o.failure, tuple) and schema_of[k] in o.failure]
        yield a, out + ([((u, False), rest / len(slips)) for u in slips] if slips
                        else [((here, False), rest)])


def ground_outcomes(task: GroundTask, dynamics: Dynamics) -> tuple[list[Outcomes], list[str]]:
    """The :class:`~gdq_pddl.dynamics.Outcomes` and the schema of every ground action."""
    parts = [split_action(op.name) for op in task.ops]
    return [dynamics.outcomes(*part) for part in parts], [schema for schema, _ in parts]


def compile_true_model(space: StateSpace, dynamics: Dynamics, costs: list[CostDist],
                       pairs: Iterable[tuple[int, dict[tuple, float]]] | tuple | None = None,
                       gains: bool = False, own_scale: bool = False) -> ModelArrays:
    """The true model of ``space`` under ``dynamics`` as :class:`ModelArrays` (``costs``:
    one per learner action): for each (state, offered action) pair, the outcomes of the
    ground action O maps to it that works there (:func:`slip_outcomes`), else a no-op.
    ``pairs`` replaces them (a PPDDL domain's outcomes are its own; a pair it does not
    yield is a no-op; ``gains``: their keys are ``(next, stuck, reward)``, the reward
    each outcome earns besides the action's cost; kept on the goal scale only where one is
    not 0), or gives them as rows already merged and in pair order
    (``(pair index, probability, [next, stuck, reward...])`` arrays); pair indices are
    ``state * width + column`` (:mod:`gdq_pddl.envs.step`)."""
    outcomes, schema_of = ground_outcomes(space.task, dynamics)
    offered = space.offered
    n_a = space.n_actions if offered is None else offered.shape[1]

    def rule():
        for s in range(space.n_states):
            column = None if offered is None else \
                {a: j for j, a in enumerate(offered[s].tolist()) if a >= 0}
            for a, outs in slip_outcomes(s, dict(space.edges(s)), space.action_of_op,
                                         outcomes, schema_of):
                yield s * n_a + (a if column is None else column[a]), merge_outcomes(outs)

    def shown(pairs):
        with slow_progress("true model", " states", space.n_states) as bar:
            for i, merged in pairs:
                bar.update(i // n_a - bar.n)
                yield i, merged

    n_pairs = space.n_states * n_a
    if isinstance(pairs, tuple):
        row_pair, prob, fields = pairs
    else:
        ptr, prob, fields = outcome_csr(
            n_pairs, shown(rule() if pairs is None else pairs),
            (np.int64, np.bool_, np.float64) if gains else (np.int64, np.bool_))
        row_pair = np.repeat(np.arange(n_pairs), np.diff(ptr))
    ptr, prob, (nxt, stuck, *gain) = with_noops(row_pair, prob, fields, n_pairs, n_a, offered)
    if gains and not own_scale and not gain[0].any():  # the goal scale's step is -cost
        gain = []
    model = ModelArrays(
        n_actions=space.n_actions, n_doors=space.n_doors, r_max=float(dynamics.r_max),
        step_limit=int(dynamics.step_limit), ptr=ptr, prob=prob, next=nxt, stuck=stuck,
        **cost_arrays(costs), obs_of=space.obs_of, pos_of=space.pos_of,
        area_of_pos=space.area_of_pos, **({"gain": gain[0]} if gain else {}),
        **({} if offered is None else {"acts": offered}), own_scale=bool(own_scale))
    for array in model:
        if isinstance(array, np.ndarray):
            array.setflags(write=False)
    return model


def reality_task(world: World) -> GroundTask:
    """The building of ``world`` as reality has it, grounded: ``domains/office.pddl`` on
    the world's problem with every door (a locked one too: its dynamics never open it).
    Cached per world."""
    p = world.positions[0]
    return per_object(world, "reality", lambda: PlanningProblem.from_texts(
        domain_text(), office_problem(world, Task("reality", p, p), locked_is_wall=False),
        "office.pddl (built in)", f"{world.source} (as PDDL)").task)


def office_space(world: World, task: GroundTask | None = None) -> StateSpace:
    """The office's :class:`StateSpace`: every full state ``position * 2**n_doors + door
    mask`` of ``world`` (goal-independent: a task's goal is the env's ``goal_pos``),
    seen through O (:class:`~gdq_pddl.abstraction.OfficeAbstraction`)."""
    task = reality_task(world) if task is None else task
    o = OfficeAbstraction(world)
    n_doors = len(world.doors)
    n_masks = 1 << n_doors
    n_full = len(world.positions) * n_masks
    at = [1 << task.fact_index[f"(at {p})"] for p in world.positions]
    opened = [1 << task.fact_index[f"(open {d.name})"] for d in world.doors]
    closed = [1 << task.fact_index[f"(closed {d.name})"] for d in world.doors]
    doors = [sum(opened[i] if mask >> i & 1 else closed[i] for i in range(n_doors))
             for mask in range(n_masks)]
    states = [at[pi] | doors[mask] for pi in range(len(at)) for mask in range(n_masks)]
    index = {state: fs for fs, state in enumerate(states)}
    op_pos = {id(op): k for k, op in enumerate(task.ops)}

    def edges(fs: int) -> list[tuple[int, int]]:
        out = [(op_pos[id(op)], index[nxt]) for op, nxt in task.successors(states[fs])]
        return sorted(out, key=lambda e: e[1])

    read = o.mask_reader(task)
    return StateSpace(
        task=task, n_states=n_full, edges=edges, n_actions=o.n_actions,
        action_of_op=tuple(o.learner_action(op.name) for op in task.ops),
        obs_of=np.array([read(state) for state in states], dtype=np.int64),
        pos_of=np.repeat(np.arange(len(at), dtype=np.int64), n_masks),
        area_of_pos=np.array([world.area_of.get(p, 0) for p in world.positions],
                             dtype=np.int64),
        n_doors=n_doors)


def office_costs(world: World) -> list[CostDist]:
    """The cost of each of the learner's actions (``stay`` too, which no ground action
    is), door overrides first."""
    spaces = LearnerSpaces(world)
    return [world.cost(*spaces.action_parts(a)) for a in range(spaces.n_actions)]


def compile_model(world: World) -> ModelArrays:
    """The world's true model: :func:`compile_true_model` of its :func:`office_space`
    under :meth:`World.dynamics <gdq_pddl.world_types.World.dynamics>` (read-only, compiled
    once per world).

    Every env, solver and analysis of the same :class:`World` object shares one copy:
    building it is the slowest part of making an env, and experiments make thousands.
    """
    def build() -> ModelArrays:
        n_pos, n_doors = len(world.positions), len(world.doors)
        n_actions = LearnerSpaces(world).n_actions
        check_memory(n_pos * (1 << n_doors) * n_actions * PAIR_BYTES,
                     f"{world.source}: {n_doors} doors: the simulator's true model ({n_pos} "
                     f"positions x 2**{n_doors} door states x {n_actions} actions)",
                     "give the world fewer doors (generated buildings run on a compact "
                     "model: gdq-pddl scale)")
        return compile_true_model(office_space(world), world.dynamics(), office_costs(world))

    return per_object(world, "model", build)
