"""Checks at the entry of the compiled code, which has no bounds checks: nothing given to a
public function of the learners can make a compiled rule read or write outside an array.
Bad input raises :class:`~gdq_pddl.errors.ConfigError` (a ValueError) naming the argument.

Every array is checked against one table, :data:`TABLES` (:data:`DYNAMICS` for the
env's): dtype, shape, the range of an index array's values (what the compiled rules write
themselves, the model's slots and the queue, is in range by construction).
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from gdq_pddl.envs.compact import CompactModel
from gdq_pddl.envs.step import width_of
from gdq_pddl.errors import ConfigError
from gdq_pddl.learners.context import BuiltWhenRead, TaskContext
from gdq_pddl.learners.tables import (
    BACKUP_EXPECTED,
    BACKUP_SAMPLE,
    KIND_GDQ,
    Params,
    Plans,
    Tables,
)
from gdq_pddl.limits import MAX_NUMBER

I8, F8, B1 = np.dtype(np.int64), np.dtype(np.float64), np.dtype(np.bool_)
PTR, PTR_NONEMPTY = "pointers", "pointers to non-empty ranges"
"""Values of a CSR pointer array: from 0, never decreasing (increasing), at most a size."""

TABLES: dict[str, dict[str, tuple]] = {
    # group: {array: (dtype, shape, values)}; shape and values in the sizes of _sizes()
    # ("*": any length); values: None (not an index), (low, high) for [low, high), or
    # (PTR or PTR_NONEMPTY, the largest last pointer)
    "table": {"q": (F8, "S A", None), "v": (F8, "S", None), "allowed": (B1, "S A", None),
              "guide": (B1, "S A", None), "n_guide": (I8, "S", (1, "A+1")),
              "goal": (B1, "S", None), "n_live": (I8, "S", (1, "A+1"))},
    "model": {"slots": (I8, "S A *", None), "stuck": (I8, "S A", None),
              "visits": (I8, "S A", None), "cost_sum": (F8, "S A", None),
              "cost_n": (I8, "S A", None), "cost_all": (F8, "2", None),
              "known": (I8, "SA", (0, "SA")), "n_known": (I8, "1", (0, "SA+1"))},
    "plans": {"opt_r": (B1, "S A", None), "plan_ptr": (I8, "S+1", (PTR, "P-1")),
              "pair_ptr": (I8, "P", (PTR_NONEMPTY, "N")), "pair_state": (I8, "N", (0, "S")),
              "pair_action": (I8, "N", (0, "A"))},
    "prior": {"next_state": (I8, "S A", (-1, "S")), "pp_ptr": (I8, "S+1", (PTR, "E")),
              "pp_pair": (I8, "E", (0, "SA")), "rev_head": (I8, "S", (-1, "C")),
              "rev_next": (I8, "C", (-1, "C")), "rev_pair": (I8, "C", (0, "SA")),
              "rev_n": (I8, "1", (0, "C+1")), "reward": (F8, "R RA", None),
              "dead": (F8, "D DA", None)},
    "queue": {"heap": (I8, "S", None), "pos": (I8, "S", None), "prio": (F8, "S", None),
              "n": (I8, "1", (0, "S+1"))},
}
"""Every array of :class:`~gdq_pddl.learners.tables.Tables` the compiled rules index."""

DYNAMICS: dict[str, tuple] = {
    # the outcome arrays both kinds of compiled dynamics share (sizes of _dynamics_sizes)
    "ptr": (I8, "PA+1", (PTR, "O")), "prob": (F8, "O", None), "stuck": (B1, "O", None),
    "cost_kind": (I8, "A", None), "cost_a": (F8, "A", None), "cost_b": (F8, "A", None),
    "area_of_pos": (I8, "X", (0, "*")),
    # ModelArrays: full states
    "next": (I8, "O", (0, "F")), "obs_of": (I8, "F", (0, "S")), "pos_of": (I8, "F", (0, "X")),
    # CompactModel: positions
    "next_pos": (I8, "O", (0, "X")), "opens": (B1, "O", None),
    "door_of_pos": (I8, "X", (-1, "D")), "state_of": (I8, "X 2", (0, "S")),
}
"""Every array of the env's compiled dynamics the episode loop indexes."""
_COMPACT_ONLY = ("next_pos", "opens", "door_of_pos", "state_of")
_FULL_ONLY = ("next", "obs_of", "pos_of")


def check_arrays(where: str, group: object, spec: dict[str, tuple],
                 sizes: dict[str, int]) -> None:
    """Each array ``name`` of ``group`` as ``spec[name]`` says, in ``sizes``."""
    for name, (dtype, shape, values) in spec.items():
        x = getattr(group, name, None)
        want = [sizes[d] for d in shape.split()]
        if not isinstance(x, np.ndarray) or x.dtype != dtype or x.ndim != len(want) or \
                any(w >= 0 and h != w for h, w in zip(x.shape, want, strict=True)) or \
                not x.flags.c_contiguous:
            got = f"{x.dtype}{list(x.shape)}" if isinstance(x, np.ndarray) else type(x).__name__
            raise ConfigError(f"{where}: {name} must be a contiguous {dtype} array of shape "
                              f"({', '.join('any' if w < 0 else str(w) for w in want)}), "
                              f"got {got}")
        if values is None:
            continue
        low, high = values
        if low in (PTR, PTR_NONEMPTY):
            end, steps = sizes[high], np.diff(x)
            if len(x) == 0 or x[0] != 0 or (steps < (low == PTR_NONEMPTY)).any() or \
                    x[-1] > end:
                raise ConfigError(f"{where}: {name} must start at 0, "
                                  f"{'increase' if low == PTR_NONEMPTY else 'never decrease'}"
                                  f", and end at most at {end}")
            continue
        high = sizes.get(high, high)
        if x.size and (x.min() < low or (high >= 0 and x.max() >= high)):
            bad = x[(x < low) | ((x >= high) if high >= 0 else False)][0]
            raise ConfigError(f"{where}: {name} must hold values in [{low}, "
                              f"{high - 1 if high >= 0 else 'any'}], holds {bad}")


def _sizes(n_states: int, n_actions: int, plans: object, prior: object = None) -> dict:
    """The sizes :data:`TABLES` names: S states, A actions, and the lengths of the plan
    table (P plans + 1, N pairs) and of the prior's index arrays (E, C)."""
    n_pairs = n_states * n_actions
    sizes = {"*": -1, "0": 0, "1": 1, "2": 2, "S": n_states, "A": n_actions, "S+1": n_states + 1,
             "A+1": n_actions + 1, "SA": n_pairs, "SA+1": n_pairs + 1}
    for key, group, name in (("P", plans, "pair_ptr"), ("N", plans, "pair_state"),
                             ("E", prior, "pp_pair"), ("C", prior, "rev_pair")):
        sizes[key] = len(getattr(group, name, ()))
    sizes["P-1"], sizes["C+1"] = sizes["P"] - 1, sizes["C"] + 1
    own = getattr(getattr(prior, "reward", None), "size", 0) > 0  # else empty: 0 x 0
    sizes["R"], sizes["RA"] = (n_states, n_actions) if own else (0, 0)
    dead = getattr(getattr(prior, "dead", None), "size", 0) > 0  # else empty: 0 x 0
    sizes["D"], sizes["DA"] = (n_states, n_actions) if dead else (0, 0)
    return sizes


def check_tables(t: Tables, p: Params) -> None:
    """Everything the compiled rules index with: every array of :data:`TABLES` (the
    default GDQ's prior and queue only for it: the others never read them), the guide's
    counts, and the settings."""
    if not isinstance(t, Tables) or not isinstance(p, Params):
        raise ConfigError("a learner's tables and params must be gdq_pddl.learners.tables."
                          "Tables and Params")
    q = t.table.q
    if not isinstance(q, np.ndarray) or q.ndim != 2 or min(q.shape) < 1:
        raise ConfigError("learner tables: q must be a 2-D array of at least one state and "
                          "action")
    sizes = _sizes(*q.shape, t.plans, t.prior)
    for group in ("table", "model", "plans") + (("prior", "queue") if p.kind == KIND_GDQ
                                                 else ()):
        check_arrays(f"learner tables ({group})", getattr(t, group), TABLES[group], sizes)
    spec = getattr(type(t.own), "SPEC", None)
    if not isinstance(spec, dict) or set(spec) != set(getattr(t.own, "_fields", ())):
        raise ConfigError("learner tables: own must be a NamedTuple of arrays whose class's "
                          "SPEC gives each field's dtype, shape and values")
    check_arrays("learner tables (own)", t.own, spec, sizes)
    for name in spec:
        x = getattr(t.own, name)
        if x.dtype == np.float64 and not np.isfinite(x).all():
            raise ConfigError(f"learner tables (own): {name} must be finite")
    if p.kind == KIND_GDQ:
        _check_rewards("learner tables (prior): reward", t.prior.reward)
        _check_chances("learner tables (prior): dead", t.prior.dead)
    if not np.array_equal(t.table.n_guide, t.table.guide.sum(axis=1)):
        raise ConfigError("learner tables: every state must let exploration draw some "
                          "action (guide), and n_guide count them")
    live = np.arange(q.shape[1]) < t.table.n_live[:, None]
    if (t.table.allowed & ~live).any() or (t.table.guide & ~live).any():
        raise ConfigError("learner tables: a padding column (past n_live) is in allowed or "
                          "guide")
    where = "learner params"
    if not 0 <= p.kind <= KIND_GDQ or p.backup not in (BACKUP_EXPECTED, BACKUP_SAMPLE) \
            or p.n_backups < 0 or p.m < 0:
        raise ConfigError(f"{where}: kind, backup, n_backups or m out of range: {p}")
    check_state("s0", p.s0, q.shape[0])
    for name in ("alpha", "gamma", "epsilon", "r_max", "opt_continue", "explore_all",
                 "explore_all_last", "prior_cost", "sweep_threshold", "prior_weight",
                 "own_scale", "explore_band", "explore_loops"):
        x = getattr(p, name)
        if not math.isfinite(x) or abs(x) > MAX_NUMBER:
            raise ConfigError(f"{where}: {name} must be finite, at most {MAX_NUMBER:g} in "
                              f"size, got {x!r}")


def check_context(context: object, n_states: int | None = None,
                  n_actions: int | None = None) -> None:
    """A task context a learner can use (of ``n_states x n_actions`` when given: a task
    switch keeps the learner's size)."""
    if not isinstance(context, TaskContext):
        raise ConfigError(f"the context must be a TaskContext (office_task_context, "
                          f"pddl_task_context), got {type(context).__name__}")
    goal = context.goal
    if not isinstance(goal, np.ndarray) or goal.ndim != 1 or len(goal) == 0 or \
            goal.dtype != np.bool_:
        raise ConfigError("TaskContext.goal must be a non-empty 1-D bool array")
    size = (len(goal), context.n_actions)
    if size[1] < 1:
        raise ConfigError("TaskContext.plans must have at least one action")
    if n_states is not None and size != (n_states, n_actions):
        raise ConfigError(f"the task has {size[0]} states x {size[1]} actions, the learner "
                          f"{n_states} x {n_actions}")
    check_state("TaskContext.s0", context.s0, size[0])
    r_max = context.r_max
    if isinstance(r_max, bool) or not isinstance(r_max, numbers.Real) or \
            not 0 <= r_max <= MAX_NUMBER:
        raise ConfigError(f"TaskContext.r_max must be a finite number in [0, {MAX_NUMBER:g}],"
                          f" got {r_max!r}")
    for name in ("plans", "darling_plans"):
        if not BuiltWhenRead.built(context, name):  # the context's own planner's, if read
            continue
        table = getattr(context, name)
        if table is not None and table.enumerated:  # as the learner's Plans group
            group = Plans(np.ascontiguousarray(table.first_actions), table.plan_ptr,
                          table.pair_ptr, table.pair_state, table.pair_action)
            check_arrays(f"TaskContext.{name}", group, TABLES["plans"],
                         _sizes(*size, group))
        elif table is not None:  # plans enumerated when read: their first actions now
            check_arrays(f"TaskContext.{name}", table,
                         {"first_actions": TABLES["plans"]["opt_r"]}, _sizes(*size, None))
    columns = getattr(context, "columns", None)
    if columns is not None:
        live = columns >= 0 if isinstance(columns, np.ndarray) else None
        if live is None or columns.dtype != I8 or columns.shape != size or \
                not live[:, 0].all() or (live[:, 1:] & ~live[:, :-1]).any():
            raise ConfigError(f"TaskContext.columns must be an int64 array of shape "
                              f"{size}, each row its actions (at least one) then -1 padding")
    if context.prior is not None:
        check_arrays("TaskContext.prior", context.prior,
                     {"next_state": TABLES["prior"]["next_state"]}, _sizes(*size, None))
        dead = getattr(context.prior, "dead", None)
        if dead is not None:
            if not isinstance(dead, np.ndarray) or dead.dtype != F8 or dead.shape != size:
                raise ConfigError(f"TaskContext.prior.dead must be a float64 array of shape "
                                  f"{size}")
            _check_chances("TaskContext.prior.dead", dead)
    reward = getattr(context, "prior_reward", None)
    if reward is not None:
        if not getattr(context, "own_scale", False):
            raise ConfigError("TaskContext.prior_reward is the file's rewards of a problem on "
                              "its own reward scale: give it only with own_scale=True")
        if not isinstance(reward, np.ndarray) or reward.dtype != F8 or reward.shape != size:
            raise ConfigError(f"TaskContext.prior_reward must be a float64 array of shape "
                              f"{size}")
        _check_rewards("TaskContext.prior_reward", reward)


def _check_chances(where: str, chance: np.ndarray) -> None:
    """Chances of dead ends the prior reads: each in [0, 1]."""
    if chance.size and not ((chance >= 0.0) & (chance <= 1.0)).all():
        raise ConfigError(f"{where} must hold probabilities, each in [0, 1]")


def _check_rewards(where: str, reward: np.ndarray) -> None:
    """Rewards the prior charges: finite, at most MAX_NUMBER in size."""
    if reward.size and not (np.isfinite(reward).all() and np.abs(reward).max() <= MAX_NUMBER):
        raise ConfigError(f"{where} must be finite, at most {MAX_NUMBER:g} in size")


def check_dynamics(model: object, start: int, doors: np.ndarray, n_states: int,
                   n_actions: int, columns: np.ndarray | None = None) -> int:
    """The env's compiled dynamics (:class:`~gdq_pddl.envs.step.ModelArrays`, from full
    state ``start``, or :class:`~gdq_pddl.envs.compact.CompactModel`, from position
    ``start`` with the open-door array ``doors``) as :data:`DYNAMICS` says, for a learner
    of ``n_states x n_actions`` columns (``columns``: their actions, None: every action);
    returns the most areas."""
    where = "the env's dynamics"
    acts = getattr(model, "acts", np.zeros((0, 0), dtype=np.int64))
    if (columns is None) != (acts.shape[0] == 0) or columns is not None and (
            columns.shape != acts.shape or not np.array_equal(columns, acts)):
        raise ConfigError("the learner's columns (the actions each state offers) are not the "
                          "env's: build the learner from this env's task context")
    if acts.size and (acts.dtype != I8 or acts.min() < -1 or acts.max() >= model.n_actions
                      or acts.shape[0] != len(model.obs_of)):
        raise ConfigError(f"{where}: acts must be int64 rows of actions in [-1, "
                          f"{model.n_actions}), one per full state")
    width = width_of(model)
    if width != n_actions:
        raise ConfigError(f"the learner has {n_actions} actions, the env's dynamics "
                          f"{width}: build the learner from this env's task context")
    compact = isinstance(model, CompactModel)
    n_pos = len(model.area_of_pos)
    n_full = len(model.pos_of_state) if compact else len(model.obs_of)
    sizes = {"*": -1, "2": 2, "A": model.n_actions, "O": len(model.prob), "X": n_pos,
             "F": n_full, "PA+1": n_full * width + 1, "D": model.n_doors,
             "S": min(n_states, n_full) if compact else n_states}
    skip = _FULL_ONLY if compact else _COMPACT_ONLY
    check_arrays(where, model, {k: v for k, v in DYNAMICS.items() if k not in skip}, sizes)
    if compact:
        check_arrays(where, type("Doors", (), {"doors": doors}),
                     {"doors": (np.dtype(np.uint8), "*", None)}, sizes)
        if len(doors) < max(1, model.n_doors):
            raise ConfigError(f"{where}: the open-door array has {len(doors)} entries for "
                              f"{model.n_doors} doors (at least 1)")
    check_state(f"the env's start {'position' if compact else 'state'}", start,
                n_pos if compact else n_full)
    return int(model.area_of_pos.max()) if n_pos else 0


# --- the per-step API and the env ---------------------------------------------------------

def check_generator(rng: object, name: str = "rng") -> None:
    """``rng`` must be a ``numpy.random.Generator`` (the only source of randomness)."""
    if not isinstance(rng, np.random.Generator):
        raise ConfigError(f"{name} must be a numpy.random.Generator (e.g. "
                          f"numpy.random.default_rng(0)), got {type(rng).__name__}")


def check_state(name: str, value: object, n: int, what: str = "a state") -> int:
    """``value`` as a learner state (or ``what``) index in ``[0, n)``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or \
            not 0 <= value < n:
        raise ConfigError(f"{name} must be {what} of the learner, an integer in "
                          f"[0, {n - 1}], got {value!r}")
    return int(value)


def check_action(name: str, value: object, n_actions: int) -> int:
    """``value`` as a learner action index in ``[0, n_actions)``."""
    return check_state(name, value, n_actions, "an action")


def check_reward(value: object) -> float:
    """``value`` as a finite reward within :data:`~gdq_pddl.limits.MAX_NUMBER`."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or \
            not math.isfinite(value) or abs(value) > MAX_NUMBER:
        raise ConfigError(f"r must be a finite reward of magnitude at most {MAX_NUMBER:g}, "
                          f"got {value!r}")
    return float(value)


def check_env(n_states: int, n_actions: int, env: object) -> None:
    """The env's observations and actions (what its outermost wrapper shows) must be the
    learner's states and actions (its spaces, when they are ``Discrete``)."""
    for space, n, what in (("observation_space", n_states, "states"),
                           ("action_space", n_actions, "actions")):
        size = getattr(getattr(env, space, None), "n", None)
        if size is not None and int(size) != n:
            raise ConfigError(f"the learner was built for {n_states} states x {n_actions} "
                              f"actions, the env has {int(size)} {what} (its {space}): build "
                              "the learner from this env's task context")
