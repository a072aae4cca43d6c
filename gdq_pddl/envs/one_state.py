"""One state of a problem explored online (:mod:`gdq_pddl.envs.online`) at a time: its
true model alone (:func:`one_state_model`, what each step of the env reads) and its
applicable ground actions (:class:`RowMasks`, the env's ``action_masks``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from gdq_pddl.envs.pddl_env import GOAL_POS
from gdq_pddl.envs.step import ModelArrays
from gdq_pddl.pddl.lazy import LazyGraph


def one_state_model(graph: LazyGraph, x: int, offered: np.ndarray, constants: ModelArrays,
                    own: bool) -> tuple[ModelArrays, np.ndarray]:
    """The true model of expanded state ``x`` alone: its row is full state 0, its
    successors 1, 2, ...; ``offered`` its columns' ground actions (``[0]`` at a dead end,
    whose column changes nothing, as an enumerated model's no-op); costs, ``r_max`` and
    the step limit from ``constants``; ``own``: with the outcomes' rewards. Returns it and
    the graph states of its full states."""
    column, prob, nxt, stuck, gain = graph.outcomes(x)
    none = np.setdiff1d(np.arange(len(offered)), column)
    if len(none):  # a pair with no outcome (a dead end's column) changes nothing
        order = np.argsort(np.r_[column, none], kind="stable")
        column = np.r_[column, none][order]
        prob = np.r_[prob, np.ones(len(none))][order]
        nxt = np.r_[nxt, np.full(len(none), x)][order]
        stuck = np.r_[np.asarray(stuck, dtype=np.bool_), np.zeros(len(none), np.bool_)][order]
        gain = np.r_[gain, np.zeros(len(none))][order]
    states, local = np.unique(np.r_[x, nxt], return_inverse=True)
    order = np.r_[np.flatnonzero(states == x), np.flatnonzero(states != x)]
    where = np.empty(len(states), dtype=np.int64)
    where[order] = np.arange(len(states))
    states = states[order]
    ptr = np.zeros(len(offered) + 1, dtype=np.int64)
    np.add.at(ptr, column + 1, 1)
    return constants._replace(
        ptr=np.cumsum(ptr), prob=prob, next=where[local[1:]],
        stuck=np.asarray(stuck, dtype=np.bool_), obs_of=np.zeros(len(states), dtype=np.int64),
        pos_of=np.where(graph.is_goal[states], GOAL_POS, 0).astype(np.int64),
        **({"gain": np.asarray(gain, dtype=np.float64)} if own else {}),
        acts=offered[None, :]), states


class RowMasks:
    """``mask_table[row]``: int8[n_actions], 1 where the ground action is applicable."""

    def __init__(self, instance: Any) -> None:
        self.instance = instance

    def __getitem__(self, row: int) -> np.ndarray:
        inst = self.instance
        out = np.zeros(inst.n_actions, dtype=np.int8)
        x = inst.state_of(int(row))
        if x >= 0 and inst.graph.expanded[x]:
            out[inst.graph.offered(x)] = 1
        elif x >= 0:  # a goal where an episode ended (or a frontier state)
            index = {id(op): k for k, op in enumerate(inst.task.ops)}
            out[[index[id(op)] for op in inst.task.applicable(inst.graph.mask(x))]] = 1
        return out


