"""Which learner actions the knowledge says can do something, in every learner state:
``int8[n_states, n_actions]``, 1 where some ground action applicable in the planner state
of ``s`` (O^-1) maps to the action (O). The envs put the current row in
``info["action_mask"]``. It follows the knowledge, not reality: an action may still fail.
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.abstraction.table import Abstraction
from gdq_pddl.pddl.grounding import GroundTask
from gdq_pddl.pddl.reachable import StateGraph


def knowledge_action_mask(abstraction: Abstraction, task: GroundTask) -> np.ndarray:
    """``int8[n_states, n_actions]``: 1 where a ground action of ``task`` applicable in
    ``abstraction.planner_state(s)`` (atoms ``task`` lacks left out) maps to the learner
    action (read-only); AbstractionError for one with no learner counterpart."""
    index = task.fact_index
    learner_action = {op.name: abstraction.learner_action(op.name) for op in task.ops}
    mask = np.zeros((abstraction.n_states, abstraction.n_actions), dtype=np.int8)
    for s in range(abstraction.n_states):
        state = sum(1 << index[a] for a in abstraction.planner_state(s) if a in index)
        for op, _ in task.successors(state):
            mask[s, learner_action[op.name]] = 1
    mask.setflags(write=False)
    return mask


def graph_action_mask(graph: StateGraph) -> np.ndarray:
    """``int8[n_states, n_ops]``: 1 where the ground action applies (read-only)."""
    n_ops = len(graph.task.ops)
    mask = np.zeros((graph.n_states, n_ops), dtype=np.int8)
    source = np.repeat(np.arange(graph.n_states), np.diff(graph.edge_ptr))
    mask[source, graph.edge_op] = 1
    op_index = {id(op): k for k, op in enumerate(graph.task.ops)}
    for s in np.flatnonzero(graph.is_goal):
        for op, _ in graph.task.successors(graph.states[s]):
            mask[s, op_index[id(op)]] = 1
    mask.setflags(write=False)
    return mask
