"""Checks at the entry of the compiled code: nothing given to a public function of the
learners can make a compiled rule read or write outside an array.

Compiled code has no bounds checks, so every index it reads must be in range before it
runs. The public entry points check what they are given and raise
:class:`~gdq_pddl.errors.ConfigError` (a ValueError) naming the argument and the range:

- a learner's construction and ``start_task`` check the task context
  (:func:`check_context`) and then every array and setting the compiled rules index with
  (:func:`check_tables`): shapes, dtypes, layout, and the ranges of the index arrays (plans,
  prior, counters);
- ``act`` and ``observe`` check the states, the action and the generator
  (:func:`check_state`, :func:`check_action`, :func:`check_generator`);
- :func:`gdq_pddl.learners.episodes.run_episodes` checks the generator, that the
  learner's states and actions are the env's (:func:`check_env`), and, before the compiled
  loop, the learner's tables again and the env's compiled dynamics
  (:func:`check_dynamics`, :func:`check_compact_dynamics`).

What is not checked: the *contents* the compiled rules write themselves (the learned
model's slots, the reverse index, the queue), which are in range by construction as long
as every index that reaches them was; replacing them by hand is not supported.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from gdq_pddl.errors import ConfigError
from gdq_pddl.learners.tables import (
    BACKUP_EXPECTED,
    BACKUP_SAMPLE,
    KIND_GDQ,
    KIND_NAMES,
    Params,
    Tables,
)
from gdq_pddl.limits import MAX_NUMBER


def check_generator(rng: object, name: str = "rng") -> None:
    """``rng`` must be a ``numpy.random.Generator`` (the only source of randomness)."""
    if not isinstance(rng, np.random.Generator):
        raise ConfigError(f"{name} must be a numpy.random.Generator (e.g. "
                          f"numpy.random.default_rng(0)), got {type(rng).__name__}")


def _check_index(name: str, value: object, n: int, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or \
            not 0 <= value < n:
        raise ConfigError(f"{name} must be {what} of the learner, an integer in "
                          f"[0, {n - 1}], got {value!r}")
    return int(value)


def check_state(name: str, value: object, n_states: int) -> int:
    """``value`` as a learner state index in ``[0, n_states)``."""
    return _check_index(name, value, n_states, "a state")


def check_action(name: str, value: object, n_actions: int) -> int:
    """``value`` as a learner action index in ``[0, n_actions)``."""
    return _check_index(name, value, n_actions, "an action")


def check_reward(value: object) -> float:
    """``value`` as a finite reward within :data:`~gdq_pddl.limits.MAX_NUMBER`."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or \
            not math.isfinite(value) or abs(value) > MAX_NUMBER:
        raise ConfigError(f"r must be a finite reward of magnitude at most {MAX_NUMBER:g}, "
                          f"got {value!r}")
    return float(value)


def _array(where: str, name: str, x: object, dtype: type, shape: tuple[int, ...]) -> None:
    """``x`` must be a C-contiguous ndarray of ``dtype`` and ``shape`` (-1: any size)."""
    if not isinstance(x, np.ndarray) or x.dtype != dtype or x.ndim != len(shape) or any(
            want >= 0 and have != want for have, want in zip(x.shape, shape, strict=True)) \
            or not x.flags.c_contiguous:
        got = (f"{x.dtype}{list(x.shape)}" if isinstance(x, np.ndarray)
               else type(x).__name__)
        want = ", ".join("any" if n < 0 else str(n) for n in shape)
        raise ConfigError(f"{where}: {name} must be a contiguous {np.dtype(dtype)} array of "
                          f"shape ({want}), got {got}")


def _in_range(where: str, name: str, x: np.ndarray, low: int, high: int) -> None:
    """Every entry of ``x`` in ``[low, high)``."""
    if x.size and (x.min() < low or x.max() >= high):
        bad = x[(x < low) | (x >= high)][0]
        raise ConfigError(f"{where}: {name} must hold values in [{low}, {high - 1}], "
                          f"holds {bad}")


def _pointers(where: str, name: str, ptr: np.ndarray, end: int, nonempty: bool = False) -> None:
    """A CSR pointer array: starts at 0, never decreases (increases, if ``nonempty``),
    ends within ``end`` entries."""
    steps = np.diff(ptr)
    if len(ptr) == 0 or ptr[0] != 0 or (steps < (1 if nonempty else 0)).any() or \
            ptr[-1] > end:
        order = "increase" if nonempty else "never decrease"
        raise ConfigError(f"{where}: {name} must start at 0, {order}, and end at most at "
                          f"{end}")


def check_plan_table(where: str, plans: object, n_states: int, n_actions: int) -> None:
    """A :class:`~gdq_pddl.abstraction.PlanTable` over ``n_states x n_actions``: pointers
    that stay in their arrays, plans of at least one pair, pairs within the spaces."""
    for name in ("plan_ptr", "pair_ptr", "pair_state", "pair_action", "first_actions",
                 "length"):
        if not hasattr(plans, name):
            raise ConfigError(f"{where} must be a PlanTable, got {type(plans).__name__}")
    _array(where, "plan_ptr", plans.plan_ptr, np.int64, (n_states + 1,))
    _array(where, "pair_ptr", plans.pair_ptr, np.int64, (-1,))
    _array(where, "pair_state", plans.pair_state, np.int64, (-1,))
    _array(where, "pair_action", plans.pair_action, np.int64, (len(plans.pair_state),))
    _array(where, "first_actions", np.ascontiguousarray(plans.first_actions), np.bool_,
           (n_states, n_actions))
    _pointers(where, "plan_ptr", plans.plan_ptr, len(plans.pair_ptr) - 1)
    _pointers(where, "pair_ptr", plans.pair_ptr, len(plans.pair_state), nonempty=True)
    _in_range(where, "pair_state", plans.pair_state, 0, n_states)
    _in_range(where, "pair_action", plans.pair_action, 0, n_actions)


def check_context(context: object, n_states: int | None = None,
                  n_actions: int | None = None) -> None:
    """A task context a learner can use (of ``n_states x n_actions`` when given: a task
    switch keeps the learner's size)."""
    for name in ("s0", "goal", "plans", "r_max", "darling_plans", "prior"):
        if not hasattr(context, name):
            raise ConfigError(f"the context must be a TaskContext (office_task_context, "
                              f"pddl_task_context), got {type(context).__name__}")
    goal = context.goal
    if not isinstance(goal, np.ndarray) or goal.ndim != 1 or len(goal) == 0 or \
            goal.dtype != np.bool_:
        raise ConfigError("TaskContext.goal must be a non-empty 1-D bool array")
    size = (len(goal), int(getattr(context.plans.first_actions, "shape", (0, 0))[1]))
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
    check_plan_table("TaskContext.plans", context.plans, *size)
    if context.darling_plans is not None:
        check_plan_table("TaskContext.darling_plans", context.darling_plans, *size)
    if context.prior is not None:
        nxt = getattr(context.prior, "next_state", None)
        _array("TaskContext.prior", "next_state", nxt, np.int64, size)
        _in_range("TaskContext.prior", "next_state", nxt, -1, size[0])


def check_tables(t: Tables, p: Params) -> None:
    """Everything the compiled rules index with: every array's dtype and shape agree with
    the Q table's ``S x A``, the index arrays (plans, prior, counters) are in range, and
    the settings are what the rules expect."""
    where = "learner tables"
    if not isinstance(t, Tables) or not isinstance(p, Params):
        raise ConfigError("a learner's tables and params must be gdq_pddl.learners.tables."
                          "Tables and Params")
    _array(where, "q", t.q, np.float64, (-1, -1))
    n_s, n_a = t.q.shape
    if n_s < 1 or n_a < 1:
        raise ConfigError(f"{where}: q must have at least one state and action, has "
                          f"{n_s} x {n_a}")
    pair, state = (n_s, n_a), (n_s,)
    for name, dtype, shape in (
            ("v", np.float64, state), ("allowed", np.bool_, pair),
            ("guide", np.bool_, pair), ("n_guide", np.int64, state),
            ("goal", np.bool_, state), ("opt_r", np.bool_, pair),
            ("slots", np.int64, (n_s, n_a, -1)), ("stuck", np.int64, pair),
            ("visits", np.int64, pair), ("cost_sum", np.float64, pair),
            ("cost_n", np.int64, pair), ("cost_all", np.float64, (2,)),
            ("known", np.int64, (n_s * n_a,)), ("n_known", np.int64, (1,))):
        _array(where, name, getattr(t, name), dtype, shape)
    if not np.array_equal(t.n_guide, t.guide.sum(axis=1)) or (t.n_guide < 1).any():
        raise ConfigError(f"{where}: every state must let exploration draw some action "
                          "(guide), and n_guide count them")
    _in_range(where, "n_known", t.n_known, 0, n_s * n_a + 1)
    plans = type("Plans", (), {"plan_ptr": t.plan_ptr, "pair_ptr": t.pair_ptr,
                               "pair_state": t.pair_state, "pair_action": t.pair_action,
                               "first_actions": t.opt_r, "length": t.v})
    check_plan_table(where, plans, n_s, n_a)
    if p.kind == KIND_GDQ:
        for name, dtype, shape in (
                ("prior_next", np.int64, pair), ("pp_ptr", np.int64, (n_s + 1,)),
                ("pp_pair", np.int64, (-1,)), ("rev_head", np.int64, state),
                ("rev_next", np.int64, (-1,)), ("rev_pair", np.int64, (len(t.rev_next),)),
                ("rev_n", np.int64, (1,)), ("heap", np.int64, state),
                ("heap_pos", np.int64, state), ("heap_prio", np.float64, state),
                ("heap_n", np.int64, (1,))):
            _array(where, name, getattr(t, name), dtype, shape)
        _in_range(where, "prior_next", t.prior_next, -1, n_s)
        _pointers(where, "pp_ptr", t.pp_ptr, len(t.pp_pair))
        _in_range(where, "pp_pair", t.pp_pair, 0, n_s * n_a)
        _in_range(where, "rev_n", t.rev_n, 0, len(t.rev_pair) + 1)
        _in_range(where, "rev_head", t.rev_head, -1, max(1, len(t.rev_pair)))
        _in_range(where, "heap_n", t.heap_n, 0, n_s + 1)
    _check_params(p, n_s)


def _check_params(p: Params, n_states: int) -> None:
    where = "learner params"
    if not 0 <= p.kind < len(KIND_NAMES):
        raise ConfigError(f"{where}: kind must be in [0, {len(KIND_NAMES) - 1}], got {p.kind}")
    if p.backup not in (BACKUP_EXPECTED, BACKUP_SAMPLE):
        raise ConfigError(f"{where}: backup must be {BACKUP_EXPECTED} or {BACKUP_SAMPLE}, "
                          f"got {p.backup}")
    check_state("s0", p.s0, n_states)
    if p.n_backups < 0 or p.m < 0:
        raise ConfigError(f"{where}: n_backups and m must be at least 0")
    for name in ("alpha", "gamma", "epsilon", "r_max", "opt_continue", "explore_all",
                 "explore_all_last", "prior_cost", "sweep_threshold", "prior_weight"):
        x = getattr(p, name)
        if not math.isfinite(x) or abs(x) > MAX_NUMBER:
            raise ConfigError(f"{where}: {name} must be finite, at most {MAX_NUMBER:g} in "
                              f"size, got {x!r}")


def check_env(n_states: int, n_actions: int, env: object) -> None:
    """The env's observations and actions must be the learner's states and actions (its
    spaces, when they are ``Discrete``)."""
    inner = getattr(env, "unwrapped", env)
    for space, n, what in (("observation_space", n_states, "states"),
                           ("action_space", n_actions, "actions")):
        size = getattr(getattr(inner, space, None), "n", None)
        if size is not None and int(size) != n:
            raise ConfigError(f"the learner was built for {n_states} states x {n_actions} "
                              f"actions, the env has {int(size)} {what} (its {space}): build "
                              "the learner from this env's task context")


def check_dynamics(model: object, start: int, n_states: int, n_actions: int) -> int:
    """A :class:`~gdq_pddl.envs.model.ModelArrays` the compiled loop can step a learner of
    ``n_states x n_actions`` through from full state ``start``; returns the most areas."""
    where = "the env's dynamics"
    n_full = len(model.obs_of)
    _sizes(where, model, n_actions, n_full * n_actions)
    _array(where, "next", model.next, np.int64, (len(model.prob),))
    _array(where, "obs_of", model.obs_of, np.int64, (n_full,))
    _array(where, "pos_of", model.pos_of, np.int64, (n_full,))
    _in_range(where, "next", model.next, 0, n_full)
    _in_range(where, "obs_of (learner states)", model.obs_of, 0, n_states)
    _in_range(where, "pos_of", model.pos_of, 0, len(model.area_of_pos))
    check_state("the env's start state", start, n_full)
    return _areas(where, model)


def check_compact_dynamics(model: object, start: int, doors: np.ndarray, n_states: int,
                           n_actions: int) -> int:
    """A :class:`~gdq_pddl.envs.compact.CompactModel` the compiled loop can step a learner
    of ``n_states x n_actions`` through from position ``start`` with the open-door array
    ``doors``; returns the most areas."""
    where = "the env's dynamics"
    n_pos = len(model.area_of_pos)
    n_model_states = len(model.pos_of_state)
    _sizes(where, model, n_actions, n_model_states * n_actions)
    _array(where, "next_pos", model.next_pos, np.int64, (len(model.prob),))
    _array(where, "opens", model.opens, np.bool_, (len(model.prob),))
    _array(where, "door_of_pos", model.door_of_pos, np.int64, (n_pos,))
    _array(where, "state_of", model.state_of, np.int64, (n_pos, 2))
    _in_range(where, "next_pos", model.next_pos, 0, n_pos)
    _in_range(where, "door_of_pos", model.door_of_pos, -1, model.n_doors)
    _in_range(where, "state_of (learner states)", model.state_of, 0,
              min(n_states, n_model_states))
    _array(where, "doors", doors, np.uint8, (-1,))
    if len(doors) < max(1, model.n_doors):
        raise ConfigError(f"{where}: the open-door array has {len(doors)} entries for "
                          f"{model.n_doors} doors (at least 1)")
    check_state("the env's start position", start, n_pos)
    return _areas(where, model)


def _sizes(where: str, model: object, n_actions: int, n_pairs: int) -> None:
    """The outcome arrays shared by both kinds of compiled dynamics."""
    if model.n_actions != n_actions:
        raise ConfigError(f"the learner has {n_actions} actions, the env's dynamics "
                          f"{model.n_actions}: build the learner from this env's task context")
    _array(where, "ptr", model.ptr, np.int64, (n_pairs + 1,))
    _array(where, "prob", model.prob, np.float64, (-1,))
    _array(where, "stuck", model.stuck, np.bool_, (len(model.prob),))
    _pointers(where, "ptr", model.ptr, len(model.prob))
    for name in ("cost_kind", "cost_a", "cost_b"):
        if len(getattr(model, name)) < n_actions:
            raise ConfigError(f"{where}: {name} must have an entry per action")
    _array(where, "area_of_pos", model.area_of_pos, np.int64, (-1,))


def _areas(where: str, model: object) -> int:
    areas = model.area_of_pos
    if areas.size and areas.min() < 0:
        raise ConfigError(f"{where}: area_of_pos must hold area numbers >= 0")
    return int(areas.max()) if areas.size else 0
