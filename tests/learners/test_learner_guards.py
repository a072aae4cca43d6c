"""Nothing given to the learners' public API makes compiled code leave its arrays (issue
19): sizes, dtypes and ranges are checked at the entry of every compiled loop, and bad
arguments are refused with a ConfigError naming them. One test runs the compiled code
with numba's bounds checking on."""

from __future__ import annotations

import os
import sys
from dataclasses import replace
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import gdq_pddl  # noqa: F401  (registers the envs)
from gdq_pddl.abstraction.prior import PriorModel
from gdq_pddl.envs.office import CompactEnv, OfficeEnv
from gdq_pddl.errors import ConfigError
from gdq_pddl.experiments.protocol import METHODS as CLI_METHODS
from gdq_pddl.learners import (
    GDQ,
    METHODS,
    Darling,
    DarlingConfig,
    DynaQ,
    DynaQConfig,
    GDQConfig,
    PaperGDQ,
    QLearning,
    QLearningConfig,
    make_learner,
    office_task_context,
    run_compact,
    run_episodes,
)
from gdq_pddl.learners.episodes import run_compiled
from gdq_pddl.learners.replan import FFReplan
from gdq_pddl.learners.rmax import RMax, RMaxShaping
from gdq_pddl.learners.shaping import DynaQShaping, PlanShaping, QShaping
from gdq_pddl.limits import MAX_NUMBER
from gdq_pddl.world import load_world
from tests.helpers import BACKGROUND

WORLD = load_world()


@pytest.fixture(scope="module")
def ctx():
    return office_task_context(WORLD, "C")


@pytest.fixture(scope="module")
def delivery():
    return gymnasium.make("gdq_pddl/PDDL-v0", domain="delivery", problem="delivery-2")


# --- a learner in an env it was not built for ---------------------------------------------

@pytest.mark.parametrize("fast", [None, False])
@pytest.mark.parametrize("method", ["Q-learning", "GDQ"])
def test_a_learner_run_in_another_env_is_refused(ctx, delivery, method, fast):
    learner = make_learner(method, ctx)
    q = learner.q.copy()
    delivery.reset(seed=0)
    with pytest.raises(ConfigError, match="31 states x 95 actions, the env has"):
        run_episodes(learner, delivery, 3, np.random.default_rng(0), fast=fast)
    assert np.array_equal(learner.q, q)  # nothing ran


def test_the_compiled_loop_checks_the_dynamics_it_is_given(ctx):
    """``run_compiled`` (what ``run_compact`` and the fast path call) checks the learner's
    sizes against the dynamics themselves, not only against the env's spaces."""
    from gdq_pddl.buildings import building_world

    big = CompactEnv(task="A", world=building_world(100, seed=1))
    big.reset(seed=0)
    env = big.unwrapped
    learner = QLearning(ctx)
    with pytest.raises(ConfigError, match="learner states|actions"):
        run_compiled(env.model, env.instance.start_pos, env.instance.goal_pos, env.doors, learner,
                     env.np_random, 2, np.random.default_rng(0), 8)
    with pytest.raises(ConfigError, match="states x 95 actions, the env has"):
        run_compact(learner, big, 2, np.random.default_rng(0))
    office = OfficeEnv(task="C")
    office.reset(seed=0)
    with pytest.raises(ConfigError, match="start state"):
        run_compiled(office.model, 10**9, office.instance.goal_pos, np.zeros(1, np.uint8), learner,
                     office.np_random, 2, np.random.default_rng(0), 7)
    with pytest.raises(ConfigError, match="n_areas"):
        run_compiled(office.model, office.instance.start_state, office.instance.goal_pos,
                     np.zeros(1, np.uint8), learner, office.np_random, 2,
                     np.random.default_rng(0), 3)


def test_tables_replaced_by_hand_are_checked_before_the_compiled_loop(ctx):
    env = OfficeEnv(task="C")
    env.reset(seed=0)
    learner = DynaQ(ctx)
    t = learner.tables
    learner.tables = t._replace(table=t.table._replace(v=np.zeros(3)))
    with pytest.raises(ConfigError, match="v must be a contiguous float64 array of shape"):
        run_episodes(learner, env, 2, np.random.default_rng(0))
    learner = GDQ(ctx)
    t = learner.tables
    learner.tables = t._replace(prior=t.prior._replace(pp_pair=t.prior.pp_pair + 10**6))
    with pytest.raises(ConfigError, match="pp_pair must hold values in"):
        run_episodes(learner, env, 2, np.random.default_rng(0))


# --- the per-step API -----------------------------------------------------------------------

def test_act_and_observe_refuse_what_is_not_a_state_action_or_reward(ctx):
    learner = DynaQ(ctx)
    rng = np.random.default_rng(0)
    for bad in (31, -1, 2.0, True, "3"):
        with pytest.raises(ConfigError, match="state must be a state of the learner"):
            learner.act(bad, rng)
    with pytest.raises(ConfigError, match=r"s2 must be a state .* \[0, 30\], got 10000"):
        learner.observe(0, 0, -1.0, 10_000, False, False, rng)
    with pytest.raises(ConfigError, match=r"a must be an action .* \[0, 94\], got 95"):
        learner.observe(0, 95, -1.0, 1, False, False, rng)
    with pytest.raises(ConfigError, match="r must be a finite reward"):
        learner.observe(0, 1, float("nan"), 1, False, False, rng)
    with pytest.raises(ConfigError, match="s must be a state"):
        learner.successors(-5, 0)
    assert learner.visits.sum() == 0  # nothing was recorded


def test_an_rng_that_is_not_a_generator_is_refused(ctx):
    env = OfficeEnv(task="C")
    env.reset(seed=0)
    learner = QLearning(ctx)
    for bad in (None, 0, np.random.RandomState(0)):
        with pytest.raises(ConfigError, match="rng must be a numpy.random.Generator"):
            run_episodes(learner, env, 2, bad)  # type: ignore[arg-type]
        with pytest.raises(ConfigError, match="rng must be a numpy.random.Generator"):
            learner.act(0, bad)  # type: ignore[arg-type]


# --- configs and contexts -------------------------------------------------------------------

@pytest.mark.parametrize(("cls", "config", "expected"), [
    (GDQ, DynaQConfig(), "GDQConfig"), (QLearning, GDQConfig(), "QLearningConfig"),
    (DynaQ, QLearningConfig(), "DynaQConfig"), (Darling, {"alpha": 0.1}, "DarlingConfig")])
def test_a_config_of_another_learner_is_refused_naming_the_expected_type(ctx, cls, config,
                                                                         expected):
    with pytest.raises(ConfigError, match=f"{cls.__name__} takes a {expected}, got"):
        cls(ctx, config)


@pytest.mark.parametrize("name", ["prior_cost", "prior_weight", "sweep_threshold"])
def test_a_config_float_that_could_overflow_the_q_table_is_refused(name):
    with pytest.raises(ConfigError, match=rf"{name} must be a finite number in \[0, 1e\+15\]"):
        GDQConfig(**{name: 1e308})


def test_the_largest_settings_accepted_keep_the_q_table_finite(ctx):
    config = GDQConfig(prior_cost=MAX_NUMBER, prior_weight=MAX_NUMBER, gamma=1 - 1e-12)
    learner = GDQ(replace(ctx, r_max=MAX_NUMBER), config)
    env = OfficeEnv(task="C")
    env.reset(seed=0)
    run_episodes(learner, env, 5, np.random.default_rng(0))
    assert np.isfinite(learner.q).all()
    with pytest.raises(ConfigError, match="r_max must be a finite number"):
        GDQ(replace(ctx, r_max=1e308))


def test_a_context_whose_arrays_leave_the_spaces_is_refused(ctx):
    plans = ctx.plans
    arrays = (plans.plan_ptr, plans.pair_ptr, plans.pair_state, plans.pair_action, False)
    bad_state = replace(plans, plans=(*arrays[:2], arrays[2] + 1000, *arrays[3:]))
    with pytest.raises(ConfigError, match="TaskContext.plans: pair_state must hold values"):
        DynaQ(replace(ctx, plans=bad_state))
    cut = replace(plans, plans=(arrays[0], arrays[1][:-1], *arrays[2:]))
    with pytest.raises(ConfigError, match="TaskContext.plans: plan_ptr must"):
        GDQ(replace(ctx, plans=cut), GDQConfig(variant="literal"))
    far = PriorModel(np.full((ctx.n_states, ctx.n_actions), 500, dtype=np.int64))
    with pytest.raises(ConfigError, match="TaskContext.prior: next_state must hold values"):
        GDQ(replace(ctx, prior=far))
    with pytest.raises(ConfigError, match=r"TaskContext.s0 must be a state .*got 31"):
        QLearning(replace(ctx, s0=31))
    other = office_task_context(WORLD, "D")
    learner = QLearning(ctx)
    learner.start_task(other)  # same spaces: fine
    small = replace(other, goal=other.goal[:5])
    with pytest.raises(ConfigError, match="the task has 5 states x 95 actions, the learner"):
        learner.start_task(small)


# --- one make_learner for every name the command line takes -----------------------------------

def test_make_learner_takes_every_name_the_command_line_takes(ctx):
    assert tuple(METHODS) == CLI_METHODS
    expected = {"GDQ": (GDQ, "prior"), "GDQ-literal": (PaperGDQ, "literal"),
                "GDQ-code": (PaperGDQ, "code"), "DARLING": (Darling, "paper"),
                "DARLING-code": (Darling, "code"), "Dyna-Q": (DynaQ, None),
                "Q-learning": (QLearning, None), "Q-shaping": (QShaping, None),
                "Dyna-Q-shaping": (DynaQShaping, None), "Plan-shaping": (PlanShaping, None),
                "R-max": (RMax, None), "R-max-shaping": (RMaxShaping, None),
                "FF-Replan": (FFReplan, None)}
    for name in CLI_METHODS:
        learner = make_learner(name, ctx, alpha=0.2)
        cls, variant = expected[name]
        assert type(learner) is cls and learner.config.alpha == 0.2
        assert getattr(learner.config, "variant", None) == variant
    assert make_learner("gdq", ctx, variant="code").config.variant == "code"
    assert type(make_learner("q_learning", ctx)) is QLearning
    with pytest.raises(ConfigError, match="sets variant='code', and the overrides"):
        make_learner("GDQ-code", ctx, variant="literal")
    with pytest.raises(ConfigError, match="unknown method 'sarsa'"):
        make_learner("sarsa", ctx)
    with pytest.raises(ConfigError, match="unexpected keyword argument 'prior_cost'"):
        make_learner("Dyna-Q", ctx, prior_cost=2.0)
    with pytest.raises(ConfigError, match="variant must be one of 'prior', 'literal', 'code'"):
        GDQConfig(variant="model")  # type: ignore[arg-type]  # the default's former name
    with pytest.raises(ConfigError):
        DarlingConfig(variant="literal")  # type: ignore[arg-type]


# --- the compiled code under numba's bounds checking --------------------------------------------

BOUNDS_CHECKED = '''
import atexit, os, shutil, tempfile
os.environ["NUMBA_CACHE_DIR"] = cache = tempfile.mkdtemp(prefix="gdq-bounds-")
os.chdir(cache)
atexit.register(shutil.rmtree, cache, True)  # compiled afresh, and nothing left behind
import numba, numpy as np
from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import METHODS, make_learner, office_task_context, run_episodes


@numba.njit
def past_the_end(x):
    return x[len(x)]


try:
    past_the_end(np.zeros(2))
    raise SystemExit("numba's bounds checking is off")
except IndexError:
    pass
env = OfficeEnv(task="C")
ctx = office_task_context(env.world, "C")
rng = np.random.default_rng(0)
for name in METHODS:
    learner = make_learner(name, ctx)  # OptInit
    env.reset(seed=0)
    # Q-learning in the compiled loop (its own indexing, the env's step inlined), every
    # other learner's compiled act and observe from the Python loop (the env's step
    # compiled once, env_act), not a copy of the loop per rules class
    run_episodes(learner, env, 3, rng, fast=name == "Q-learning")
    learner.start_task(ctx)
    learner.greedy_policy()
print("bounds-checked")
'''


def start_bounds_checked(item=None):
    env = {**os.environ, "NUMBA_BOUNDSCHECK": "1", "NUMBA_OPT": "0",
           "PYTHONPATH": os.pathsep.join(
               [str(Path(gdq_pddl.__file__).resolve().parents[1]),
                os.environ.get("PYTHONPATH", "")])}
    return BACKGROUND.run("bounds-checked", [sys.executable, "-W", "ignore", "-c",
                                             BOUNDS_CHECKED], env=env, timeout=1200)


@pytest.mark.background.with_args(start_bounds_checked, first=True)
def test_compiled_code_runs_with_numba_bounds_checking():
    """Every learner's compiled rules (act, observe) and OptInit, the episode loop and
    the env's step, compiled afresh with bounds checking: any index out of range raises
    IndexError there. One process for every learner (numba cannot cache bounds-checked
    code: it compiles all of it each time), 3 episodes each on the office (the compact
    loop compiles the same rules); the loop itself once, with Q-learning's rules, the
    other learners' rules called from the Python loop (the same compiled functions the
    loop calls: a copy of the loop per rules class cost 24 s more CPU, 76 -> 52 s), and
    LLVM's optimisations off (``NUMBA_OPT=0``): the bounds checks are placed before
    them. The process starts when collection ends and compiles on
    the second core while the tests before this one run (``tests.helpers.Background``).
    (A learner run in another env is refused before any compiled code runs:
    ``test_a_learner_run_in_another_env_is_refused``.)"""
    done = start_bounds_checked().result()
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip() == "bounds-checked"
