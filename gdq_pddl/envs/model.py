"""The true dynamics of an office world, compiled to flat arrays, and one compiled step.

The simulator's hidden state is the *full* state ``(position, which doors are open)``,
indexed ``position * 2**n_doors + door_mask``. For every (full state, offered action)
pair the model lists its outcomes (probability, next full state, stuck flag) in CSR form:
outcomes of pair ``i = full_state * width + column`` are ``ptr[i]:ptr[i+1]``. A PDDL
problem offers in each state its applicable ground actions (``acts``, the state graph's
``offered`` rows: column ``j`` of state ``fs`` is ground action ``acts[fs, j]``, -1 pads
a row to ``width``); the office offers every learner action everywhere (``acts`` empty:
column ``j`` is action ``j``, ``width = n_actions``).

The gymnasium env, the fast episode runner and value iteration all read these arrays,
so there is exactly one definition of the world's dynamics (:func:`compile_model`)
and one of a step (:func:`env_step`).
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Hashable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple, TypeVar

import numba
import numpy as np

from gdq_pddl.abstraction import OfficeAbstraction
from gdq_pddl.dynamics import COST_KINDS, CostDist, Dynamics, Outcomes, split_action
from gdq_pddl.limits import check_memory, slow_progress
from gdq_pddl.pddl.grounding import GroundTask
from gdq_pddl.planning.base import PlanningProblem
from gdq_pddl.resources import domain_text
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world_types import Task, World, office_problem

PAIR_BYTES = 150
"""Memory one (state, action) pair takes while a model is compiled: its outcomes are
gathered as Python tuples and floats (at least one per pair) before becoming arrays."""

NOOP_CHUNK = 1 << 20
"""Pairs whose no-op states :func:`with_noops` writes at a time."""

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
    gain: np.ndarray = np.zeros(0)  # float64[n_outcomes]: the problem's own rewards
    """Empty: the library's rewards (:func:`finish_step`). Else the problem's own, as the
    IPPC scores them (:func:`file_step`): each outcome's reward besides the action's
    cost, and ``r_max`` once on reaching the goal; no penalty for a stuck or late end."""
    acts: np.ndarray = np.zeros((0, 0), dtype=np.int64)  # int64[n_full, width]
    """The action of each column (module docstring); empty: every action, column = action."""


def width_of(model: ModelArrays | tuple) -> int:
    """Columns a state's row has in ``model`` (a :class:`ModelArrays`, or a compact model,
    which has no ``acts``): ``acts``' width, or every action when ``acts`` is empty."""
    acts = getattr(model, "acts", None)
    return int(acts.shape[1]) if acts is not None and acts.shape[0] else int(model.n_actions)


def pair_of(model: ModelArrays, fs: int, action: int) -> int | None:
    """The pair index of ``action`` in full state ``fs`` (its outcomes are
    ``ptr[i]:ptr[i + 1]``), or None where ``fs`` does not offer it."""
    if not model.acts.shape[0]:
        return fs * model.n_actions + action
    hits = np.flatnonzero(model.acts[fs] == action)
    return int(fs * model.acts.shape[1] + hits[0]) if len(hits) else None


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
    """int64[n_states]: what :func:`env_step`'s goal test compares with ``goal_pos``."""
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
                       gains: bool = False) -> ModelArrays:
    """The true model of ``space`` under ``dynamics`` as :class:`ModelArrays` (``costs``:
    one per learner action): for each (state, offered action) pair, the outcomes of the
    ground action O maps to it that works there (:func:`slip_outcomes`), else a no-op.
    ``pairs`` replaces them (a PPDDL domain's outcomes are its own; a pair it does not
    yield is a no-op; ``gains``: their keys are ``(next, stuck, reward)``, on the
    problem's own scale), or gives them as rows already merged and in pair order
    (``(pair index, probability, [next, stuck, reward...])`` arrays); pair indices are
    ``state * width + column`` (module docstring)."""
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
    model = ModelArrays(
        n_actions=space.n_actions, n_doors=space.n_doors, r_max=float(dynamics.r_max),
        step_limit=int(dynamics.step_limit), ptr=ptr, prob=prob, next=nxt, stuck=stuck,
        **cost_arrays(costs), obs_of=space.obs_of, pos_of=space.pos_of,
        area_of_pos=space.area_of_pos, **({"gain": gain[0]} if gains else {}),
        **({} if offered is None else {"acts": offered}))
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
def env_step(m: ModelArrays, fs: int, column: int, t: int, goal_pos: int,
             rng: np.random.Generator) -> tuple[int, float, bool, bool, int]:
    """Take the action of ``column`` (module docstring) in full state ``fs`` at step
    ``t`` (0-based) of an episode.

    Returns ``(next full state, reward, terminated, truncated, cause)``. Draws exactly
    one uniform for the outcome, then one cost draw if the cost is not constant.
    """
    if m.acts.shape[0]:
        action = m.acts[fs, column]
        k = draw_outcome(m.ptr, m.prob, fs * m.acts.shape[1] + column, rng)
    else:
        action = column
        k = draw_outcome(m.ptr, m.prob, fs * m.n_actions + column, rng)  # never -1 here
    nxt = m.next[k]
    if m.gain.shape[0]:
        return file_step(m, action, m.gain[k], nxt, m.stuck[k], m.pos_of[nxt] == goal_pos, t,
                         rng)
    return finish_step(m, action, nxt, m.stuck[k], m.pos_of[nxt] == goal_pos, t, rng)


@numba.njit(cache=True)
def env_act(m: ModelArrays, fs: int, action: int, t: int, goal_pos: int,
            rng: np.random.Generator) -> tuple[int, float, bool, bool, int]:
    """:func:`env_step` of an action: its column in ``fs``, or, where ``fs`` does not
    offer it (its preconditions fail), a step that changes nothing at the action's cost
    (one uniform drawn for the outcome all the same)."""
    if not m.acts.shape[0]:
        return env_step(m, fs, action, t, goal_pos, rng)
    for j in range(m.acts.shape[1]):
        if m.acts[fs, j] == action:
            return env_step(m, fs, j, t, goal_pos, rng)
    rng.random()
    if m.gain.shape[0]:
        return file_step(m, action, 0.0, fs, False, False, t, rng)
    return finish_step(m, action, fs, False, False, t, rng)


@numba.njit(cache=True, inline="always")
def file_step(m: ModelArrays, action: int, gain: float, nxt: int, stuck: bool, at_goal: bool,
              t: int, rng: np.random.Generator) -> tuple[int, float, bool, bool, int]:
    """:func:`finish_step` on the problem's own scale: the outcome's ``gain``
    (:attr:`ModelArrays.gain`) less the action's cost."""
    reward = gain - sample_cost(m.cost_kind[action], m.cost_a[action], m.cost_b[action], rng)
    if stuck:
        return nxt, reward, True, False, CAUSE_STUCK
    if at_goal:
        return nxt, reward + m.r_max, True, False, CAUSE_GOAL
    return nxt, reward, False, t + 1 >= m.step_limit, \
        CAUSE_TIMEOUT if t + 1 >= m.step_limit else CAUSE_NONE
