"""The true dynamics of a large world per learner state, without enumerating door masks.

The full model has ``n_positions * 2**n_doors`` states, but an action's outcomes depend
only on the learner state (position, is its door open). So this model lists outcomes per
(learner state, action) pair in CSR form (pair ``i = state * n_actions + action`` owns
``ptr[i]:ptr[i+1]``; none: the robot stays), each a ``next_pos``, whether it ``opens``
the door it was taken at, and whether it is ``stuck``; an episode keeps the open doors
in a ``uint8`` array. Outcomes and random draws are the full model's (same rule, order
and draws), so an office episode is bit-identical to one of ``OfficeEnv`` (tested). Why
two step functions: docs/decisions.md, "One pipeline".
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from gdq_pddl.abstraction import OfficeAbstraction
from gdq_pddl.envs.model import (
    cost_arrays,
    ground_outcomes,
    merge_outcomes,
    office_costs,
    outcome_csr,
    per_object,
    reality_task,
    slip_outcomes,
)
from gdq_pddl.envs.step import draw_outcome, finish_step
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world_types import World


class CompactModel(NamedTuple):
    """The compiled dynamics per learner state (see the module docstring)."""

    n_actions: int
    r_max: float
    step_limit: int
    ptr: np.ndarray  # int64[n_states * n_actions + 1]
    prob: np.ndarray  # float64[n_outcomes]
    next_pos: np.ndarray  # int64[n_outcomes]
    opens: np.ndarray  # bool[n_outcomes]
    stuck: np.ndarray  # bool[n_outcomes]
    cost_kind: np.ndarray  # int64[n_actions]
    cost_a: np.ndarray  # float64[n_actions]
    cost_b: np.ndarray  # float64[n_actions]
    door_of_pos: np.ndarray  # int64[n_positions], door index (-1: open floor)
    state_of: np.ndarray  # int64[n_positions, 2], learner state of (position, door open)
    pos_of_state: np.ndarray  # int64[n_states]
    area_of_pos: np.ndarray  # int64[n_positions]
    n_doors: int


def compile_compact(world: World) -> CompactModel:
    """The world's :class:`CompactModel`, from each learner state's planner state (every
    other door closed); linear in learner states x actions, compiled once per world."""
    return per_object(world, "compact", lambda: _compile_compact(world))


def _compile_compact(world: World) -> CompactModel:
    spaces = LearnerSpaces(world)
    o = OfficeAbstraction(world)
    task = reality_task(world)
    outcomes, schema_of = ground_outcomes(task, world.dynamics())
    action_of_op = [o.learner_action(op.name) for op in task.ops]
    op_pos = {id(op): k for k, op in enumerate(task.ops)}
    at = {task.fact_index[f"(at {p})"]: i for i, p in enumerate(world.positions)}
    at_mask = sum(1 << bit for bit in at)
    n_states, n_actions = spaces.n_states, spaces.n_actions
    door_ids = {d.name: i for i, d in enumerate(world.doors)}

    def pairs():
        for s, (p, _) in enumerate(spaces.states):
            state = task.mask(o.planner_state(s))
            here = (world.index[p], False)
            door = world.door_at.get(p)
            bit = 1 << task.fact_index[f"(open {door.name})"] if door is not None else 0
            # where each ground action leads: (position, did the door here open)
            succ = sorted(((op_pos[id(op)], (at[(nxt & at_mask).bit_length() - 1],
                                             bool(nxt & bit & ~state)))
                           for op, nxt in task.successors(state)), key=lambda e: e[1][0])
            for a, outs in slip_outcomes(here, dict(succ), action_of_op, outcomes, schema_of):
                merged = merge_outcomes(((*there, stuck), pr) for (there, stuck), pr in outs)
                if list(merged) == [(*here, False)]:
                    continue  # a no-op after all: leave the pair empty
                yield s * n_actions + a, merged

    ptr, prob, (nxt, opens, stuck) = outcome_csr(n_states * n_actions, pairs(),
                                                 (np.int64, np.bool_, np.bool_))
    door_of = np.array([door_ids[world.door_at[p].name] if p in world.door_at else -1
                        for p in world.positions], dtype=np.int64)
    state_of = np.array([[spaces.state(p, False), spaces.state(p, True)]
                         for p in world.positions], dtype=np.int64)
    return CompactModel(
        n_actions=n_actions, r_max=float(world.r_max), step_limit=int(world.step_limit),
        ptr=ptr, prob=prob, next_pos=nxt, opens=opens, stuck=stuck,
        **cost_arrays(office_costs(world)), door_of_pos=door_of, state_of=state_of,
        pos_of_state=np.array([world.index[p] for p, _ in spaces.states], dtype=np.int64),
        area_of_pos=np.array([world.area_of.get(p, 0) for p in world.positions],
                             dtype=np.int64),
        n_doors=len(world.doors))


@numba.njit(cache=True)
def observe_state(m: CompactModel, pos: int, doors: np.ndarray) -> int:
    """The learner state of ``pos`` given the open doors."""
    d = m.door_of_pos[pos]
    return m.state_of[pos, 1 if d >= 0 and doors[d] else 0]


@numba.njit(cache=True, inline="always")
def compact_step(m: CompactModel, pos: int, doors: np.ndarray, action: int, t: int,
                 goal_pos: int, rng: np.random.Generator) -> tuple[int, float, bool, bool, int]:
    """Take ``action`` at ``pos`` (``doors[d]``: door ``d`` open; updated in place);
    returns ``(next position, reward, terminated, truncated, cause)``."""
    k = draw_outcome(m.ptr, m.prob, observe_state(m, pos, doors) * m.n_actions + action, rng)
    nxt, stuck = pos, False
    if k >= 0:
        nxt, stuck = m.next_pos[k], m.stuck[k]
        if m.opens[k]:
            doors[m.door_of_pos[pos]] = 1
    return finish_step(m, action, nxt, stuck, nxt == goal_pos, t, rng)
