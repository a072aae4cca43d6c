"""GDQ's OptInit: the greedy policy follows a shortest plan, the code variant's plan
tolerance and its sample backups, the optimistic values of the literal variant and of
terminal optimism, and a task switch that keeps the model and reseeds Q."""

from __future__ import annotations

import numpy as np
import pytest

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import (
    GDQ,
    GDQConfig,
    learned_model,
    office_task_context,
    run_episodes,
    tables,
)
from gdq_pddl.spaces import LearnerSpaces
from tests.learners.learning import DET, WORLD, expected_backup

LITERAL = GDQConfig(variant="literal")


# --- OptInit ------------------------------------------------------------------------------

def greedy_walk(learner, world, task: str, limit: int) -> tuple[list[tuple[int, int]], str]:
    """The (state, action) pairs of the greedy policy from the start, and how it ended."""
    policy = learner.greedy_policy()
    env = OfficeEnv(task=task, world=world)
    s, _ = env.reset(seed=0)
    taken, info = [], {"cause": ""}
    for _ in range(limit):
        a = int(policy[s])
        taken.append((s, a))
        s, _, terminated, truncated, info = env.step(a)
        if terminated or truncated:
            break
    return taken, info["cause"]


@pytest.mark.parametrize("config", [GDQConfig(variant="literal"),
                                    GDQConfig(variant="code", plan_tolerance=0.0)])
def test_optinit_greedy_policy_follows_a_shortest_plan(config):
    ctx = office_task_context(DET, "C")
    learner = GDQ(ctx, config)
    plans = ctx.plans.plans_from(ctx.s0)
    shortest = int(ctx.plans.length[ctx.s0])
    assert shortest == 8 and plans
    taken, cause = greedy_walk(learner, DET, "C", shortest)
    assert cause == "goal"
    assert taken in plans, "the greedy path must be one of the planner's shortest plans"


def test_code_variant_plans_within_the_authors_tolerance():
    """GDQ-code's H holds plans up to 1.3 x the shortest: the 9-step easy-door route too."""
    ctx = office_task_context(DET, "C")
    code, literal = GDQ(ctx, GDQConfig(variant="code")), GDQ(ctx, LITERAL)
    assert code.config.plan_tolerance == pytest.approx(0.3)
    assert literal.config.plan_tolerance == 0.0
    sp = LearnerSpaces(DET)
    p8_to_p5 = (sp.state("p8"), sp.action("goto", "p5"))  # only on the 1->3->2->6 route
    assert code.optimistic_pairs[p8_to_p5] and not literal.optimistic_pairs[p8_to_p5]
    # every pair the greedy policy takes is on some plan (ties between plans may cycle
    # in a memoryless policy: only real experience breaks them)
    taken, _ = greedy_walk(code, DET, "C", 10)
    assert all(code.optimistic_pairs[s, a] for s, a in taken)
    firsts = {plan[0][1] for plan in ctx.darling_plans.plans_from(ctx.s0)}
    assert taken[0][1] in firsts
    with pytest.raises(ValueError, match="plan_tolerance 0.5"):
        GDQ(ctx, GDQConfig(variant="code", plan_tolerance=0.5))


def test_optinit_policy_iteration_values_of_the_optimistic_model(ctx_c):
    learner = GDQ(ctx_c, LITERAL)
    r_max, gamma = ctx_c.r_max, learner.config.gamma
    top = r_max / (1 - gamma)  # optimistic pairs loop back to s0 without ending
    opt = learner.optimistic_pairs
    assert opt.any()
    not_goal = ~ctx_c.goal
    assert np.allclose(learner.q[opt], top, atol=1e-6)
    rest = ~opt & not_goal[:, None]
    assert np.allclose(learner.q[rest], gamma * top, atol=1e-6)
    assert np.all(learner.q[ctx_c.goal] == 0.0)


def test_code_variant_sets_r_max_on_plan_pairs_only(ctx_c):
    learner = GDQ(ctx_c, GDQConfig(variant="code"))
    opt = learner.optimistic_pairs
    assert np.all(learner.q[opt] == ctx_c.r_max)
    assert np.all(learner.q[~opt] == 0.0)
    assert learner.params.backup == tables.BACKUP_SAMPLE


def test_code_variant_backups_replay_experience_and_skip_untried_pairs(ctx_c):
    learner = GDQ(ctx_c, GDQConfig(variant="code", n_backups=0))
    t, p = learner.tables, learner.params
    rng = np.random.default_rng(0)
    s, a = (int(x[0]) for x in np.nonzero(learner.optimistic_pairs))
    t.table.q[:, :] = 50.0  # a backup through the optimistic model would move Q(s, a)
    tables.recompute_all_v(t.table)
    learned_model.model_backup(t.table, t.model, t.plans.opt_r, p, s, a, rng)
    assert t.table.q[s, a] == 50.0  # never tried: left alone
    s2 = int(np.flatnonzero(~ctx_c.goal & (np.arange(ctx_c.n_states) != s))[0])
    # one ordinary step to s2 at cost 2
    learned_model.record(t.model, t.table.goal, p, s, a, -2.0, s2, False, False)
    assert learner.successors(s, a) == {s2: 1} and t.model.visits[s, a] == 1
    t.table.q[s2, :] = 10.0
    tables.recompute_all_v(t.table)
    learned_model.model_backup(t.table, t.model, t.plans.opt_r, p, s, a, rng)
    target = -2.0 + p.gamma * 10.0
    assert t.table.q[s, a] == pytest.approx(50.0 + p.alpha * (target - 50.0))


def test_code_variant_task_switch_keeps_the_model_and_reseeds_q(ctx_c):
    learner = GDQ(ctx_c, GDQConfig(variant="code"))
    env = OfficeEnv(task="C")
    env.reset(seed=0)
    run_episodes(learner, env, 200, np.random.default_rng(0))
    visits = learner.visits.copy()
    learner.start_task(office_task_context(WORLD, "D"))
    assert np.array_equal(learner.visits, visits) and visits.sum() > 0
    opt = learner.optimistic_pairs
    assert np.all(learner.q[opt] == ctx_c.r_max) and np.all(learner.q[~opt] == 0.0)


def test_terminal_optimism_bounds_optinit_values_by_r_max(ctx_c):
    learner = GDQ(ctx_c, GDQConfig(variant="literal", optimistic_successor="terminal"))
    opt = learner.optimistic_pairs
    assert np.allclose(learner.q[opt], ctx_c.r_max)
    assert np.all(learner.q[~opt] == 0.0)
    t, p = learner.tables, learner.params
    s, a = (int(x[0]) for x in np.nonzero(opt))
    high = np.full(ctx_c.n_states, 100.0)
    assert expected_backup(t, p, s, a, high) == ctx_c.r_max  # no continuation
