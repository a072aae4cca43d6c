"""One state of a problem explored online (:mod:`gdq_pddl.envs.online`) at a time: its
true model alone (:func:`one_state_model`, what each step of the env reads) and its
applicable ground actions (:class:`RowMasks`, the env's ``action_masks``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from gdq_pddl.envs.model import with_noops
from gdq_pddl.envs.pddl_env import GOAL_POS
from gdq_pddl.envs.step import ModelArrays
from gdq_pddl.pddl.lazy import LazyGraph


def one_state_model(graph: LazyGraph, x: int, offered: np.ndarray, constants: ModelArrays,
                    own: bool) -> tuple[ModelArrays, np.ndarray]:
    """The true model of expanded state ``x`` alone: its row is full state 0, its
    successors 1, 2, ...; ``offered`` its columns' ground actions (``[0]`` at a dead end,
    whose column changes nothing, as an enumerated model's no-op); costs, ``r_max`` and
    the step limit from ``constants`` (and its scale, :attr:`ModelArrays.own_scale`);
    ``own``: with the outcomes' rewards even where all are 0 (on the goal scale they are
    kept only where one is not, as :func:`~gdq_pddl.envs.model.compile_true_model` keeps
    them). Returns it and the graph states of its full states."""
    column, prob, nxt, stuck, gain = graph.outcomes(x)
    moves = nxt != x  # most outcomes stay (boxworld: 1,800 ground actions, a few move)
    others, local = np.unique(nxt[moves], return_inverse=True)
    states = np.r_[np.int64(x), others]
    to = np.zeros(len(nxt), dtype=np.int64)
    to[moves] = local.ravel() + 1
    fields = [to, np.asarray(stuck, dtype=np.bool_), np.asarray(gain, dtype=np.float64)]
    counts = np.bincount(column, minlength=len(offered))
    if counts.all():  # every column has its outcomes, in column order: the CSR as it is
        ptr = np.zeros(len(offered) + 1, dtype=np.int64)
        np.cumsum(counts, out=ptr[1:])
        prob, nxt = np.array(prob, dtype=np.float64), fields[0]
        stuck, gain = fields[1].copy(), fields[2].copy()  # not the graph's own arrays
    else:  # a pair with no outcome (a dead end's column) changes nothing: state 0 stays
        ptr, prob, (nxt, stuck, gain) = with_noops(column, prob, fields, len(offered),
                                                   len(offered), offered[None, :])
    return constants._replace(
        ptr=ptr, prob=prob, next=nxt, stuck=stuck,
        obs_of=np.zeros(len(states), dtype=np.int64),
        pos_of=np.where(graph.is_goal[states], GOAL_POS, 0).astype(np.int64),
        **({"gain": gain} if own or gain.any() else {}), acts=offered[None, :]), states


class RowMasks:
    """``mask_table[row]``: int8[n_actions], 1 where the ground action is applicable."""

    def __init__(self, instance: Any) -> None:
        self.instance = instance

    def __getitem__(self, row: int) -> np.ndarray:
        inst = self.instance
        out = np.zeros(inst.n_actions, dtype=np.int8)
        x = inst.state_of(int(row))
        if x >= 0:  # a state's row (a goal's too); none for an estimate row
            out[inst.graph.applicable(x)] = 1
        return out


