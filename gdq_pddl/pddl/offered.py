"""The offered table: each state's applicable ground actions, the layout of every table
over states and actions of a PDDL problem.

Row ``i`` of an offered table (:attr:`~gdq_pddl.pddl.reachable.StateGraph.offered`)
lists the ground actions offered in state ``i`` in increasing order, padded with -1 to
the longest row; a state where none applies lists ground action 0. A learner's tables,
the true model, the prior and the plan tables are indexed by ``(state, column)``, so a
ground action is found by its column in its state's row.

:func:`column_of` and :func:`columns_in` find the column of a ground action in a row
(the enumeration, :func:`~gdq_pddl.pddl.reachable.reachable_graph`, builds the table).
"""

from __future__ import annotations

import numpy as np


def column_of(offered: np.ndarray, state: np.ndarray, action: np.ndarray) -> np.ndarray:
    """int64: the column of ``action[i]`` in the row of ``state[i]`` of an offered table
    (-1 where it is not offered there)."""
    return columns_in(offered)(state, action)


def columns_in(offered: np.ndarray):
    """:func:`column_of` over one ``offered`` table, its index built once: each call then
    costs a binary search per query, not a pass over the whole table."""
    n_states = offered.shape[0]
    live = offered >= 0
    big = int(offered.max(initial=0)) + 1
    keys = (np.arange(n_states, dtype=np.int64)[:, None] * big + offered)[live]
    start = np.zeros(n_states + 1, dtype=np.int64)
    np.cumsum(live.sum(axis=1), out=start[1:])
    del live

    def column(state: np.ndarray, action: np.ndarray) -> np.ndarray:
        state = np.asarray(state, dtype=np.int64)
        action = np.asarray(action, dtype=np.int64)
        want = state * big + action
        at = np.minimum(np.searchsorted(keys, want), len(keys) - 1)
        found = (keys[at] == want) & (action >= 0) & (action < big)
        return np.where(found, at - start[state], -1)

    return column
