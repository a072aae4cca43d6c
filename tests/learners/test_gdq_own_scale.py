"""GDQ on a problem's own reward scale (an IPPC file's rewards): the learned model pays
ending steps as the env does, the prior pays the file's rewards besides a capped flat
step cost, and a goal-scale learner keeps the flat prior."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import GDQ, gdq, warm_start


@pytest.mark.parametrize("own", [False, True])
def test_the_learned_model_pays_ending_steps_as_the_env_does(own):
    """On the problem's own scale (IPPC rewards) a stuck end pays the step's cost and no
    -r_max, and the goal step its cost besides r_max; on the goal scale -r_max and r_max."""
    from gdq_pddl.learners.learned_model import (
        learned_value,
        new_model,
        record,
        sample_outcome,
    )
    from gdq_pddl.learners.tables import Params

    p = Params(kind=4, alpha=0.1, gamma=1.0, epsilon=0.1, r_max=20.0, n_backups=0, m=0,
               backup=0, s0=0, own_scale=float(own))
    goal = np.array([False, False, True])
    model = new_model(3, 1, 3)
    assert record(model, goal, p, 0, 0, -3.0, 1, False, False)  # an ordinary step, cost 3
    assert record(model, goal, p, 0, 0, -3.0, 0, True, False)  # stuck
    assert record(model, goal, p, 0, 0, 17.0, 2, True, False)  # the goal
    v = np.array([0.0, 5.0, 0.0])
    value = learned_value(model.slots, model.stuck, model.visits, model.cost_sum,
                          model.cost_n, model.cost_all, goal, v, p, 0, 0)
    stuck, reached = (-3.0, 20.0 - 3.0) if own else (-20.0, 20.0)
    assert value == pytest.approx((stuck + (5.0 - 3.0) + reached) / 3)
    rng = np.random.default_rng(0)
    seen = {sample_outcome(model, goal, p, 0, 0, rng) for _ in range(60)}
    assert seen == {(stuck, 0, True), (-3.0, 1, False), (reached, 2, True)}


def test_the_learned_model_keeps_what_an_ending_step_itself_pays_on_own_scale():
    """An ending step's own reward is learned from the ending steps themselves: a goal step
    that pays 25 besides the goal reward (the courier's on-time delivery) is worth 45, a
    stuck step that cost 7 is worth -7, whatever the pair's or other pairs' ordinary steps
    cost."""
    from gdq_pddl.learners.learned_model import learned_value, new_model, record
    from gdq_pddl.learners.tables import Params

    p = Params(kind=4, alpha=0.1, gamma=1.0, epsilon=0.1, r_max=20.0, n_backups=0, m=0,
               backup=0, s0=0, own_scale=1.0)
    goal = np.array([False, False, True])
    model = new_model(3, 2, 3)
    assert record(model, goal, p, 1, 0, -1.0, 0, False, False)  # an ordinary step elsewhere
    assert record(model, goal, p, 0, 0, 45.0, 2, True, False)  # the goal, 25 over r_max
    assert record(model, goal, p, 0, 1, -7.0, 0, True, False)  # stuck after paying 7
    v = np.zeros(3)
    args = (model.slots, model.stuck, model.visits, model.cost_sum, model.cost_n,
            model.cost_all, goal, v, p, 0)
    assert learned_value(*args, 0) == pytest.approx(45.0)
    assert learned_value(*args, 1) == pytest.approx(-7.0)


def test_a_problem_on_its_own_scale_tells_the_learners():
    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.learners import make_learner, pddl_task_context

    for problem, own in (("courier-1", True), ("lift-1", False)):
        ctx = pddl_task_context(load_instance(problem.split("-")[0], problem))
        assert ctx.own_scale is own
        assert make_learner("GDQ", ctx).params.own_scale == float(own)


def test_the_prior_step_cost_keeps_every_plan_within_the_limit_worth_doing_on_own_scale():
    """On a problem's own scale a step may cost nothing: the prior's step cost is capped
    at r_max / step_limit there (unchanged on the goal scale), with or without the file's
    rewards."""
    from dataclasses import replace

    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.learners import make_learner, pddl_task_context
    from gdq_pddl.learners.gdq_learner import prior_step_cost

    ctx = pddl_task_context(load_instance("courier", "courier-2"))
    assert ctx.own_scale and ctx.step_limit == 20 and ctx.r_max == 20.0
    assert prior_step_cost(1.0, ctx) == 1.0
    assert prior_step_cost(1.0, replace(ctx, prior_reward=None)) == 1.0
    small = replace(ctx, r_max=1.0)  # an IPPC goal reward of 1
    assert prior_step_cost(1.0, small) == pytest.approx(1.0 / 20)
    assert make_learner("GDQ", small).params.prior_cost == pytest.approx(1.0 / 20)
    goal_scale = pddl_task_context(load_instance("lift", "lift-2"))
    assert prior_step_cost(1.0, replace(goal_scale, r_max=1.0)) == 1.0


TOLL = """(define (domain toll) (:requirements :typing :rewards :probabilistic-effects)
  (:types site)
  (:predicates (at ?s - site) (link ?x ?y - site) (bus ?x ?y - site) (dash ?x ?y - site))
  (:functions (fee ?x ?y - site) (bonus ?x ?y - site))
  (:action go :parameters (?x ?y - site) :precondition (and (at ?x) (link ?x ?y))
    :effect (and (decrease (reward) (fee ?x ?y))
                 (probabilistic 1/2 (and (at ?y) (not (at ?x))))))
  (:action dash :parameters (?x ?y - site) :precondition (and (at ?x) (dash ?x ?y))
    :effect (probabilistic 1/2 (and (at ?y) (not (at ?x)) (decrease (reward) 5))
                           1/2 (increase (reward) 2)))
  (:action ride :parameters (?x ?y - site) :precondition (and (at ?x) (bus ?x ?y))
    :effect (and (at ?y) (not (at ?x)) (increase (reward) (bonus ?x ?y)))))
"""


def _toll(tmp_path, back: int | None):
    """A toll problem: from a, walk to the goal g for 3 (half the time nothing happens),
    or ride to b, paid 4, then walk for 1, or dash (reaching g costs 5, failing pays 2);
    ``back``: a bus from b to a paying that."""
    from gdq_pddl.envs.pddl_env import PDDLInstance
    from gdq_pddl.learners import pddl_task_context

    extra = "" if back is None else f"(bus b a) (= (bonus b a) {back})"
    (tmp_path / "toll.pddl").write_text(TOLL)
    (tmp_path / "p.pddl").write_text(f"""(define (problem p) (:domain toll)
      (:objects a b g - site)
      (:init (at a) (link a g) (bus a b) (link b g) (dash b g) {extra}
             (= (fee a g) 3) (= (fee b g) 1) (= (bonus a b) 4))
      (:goal (at g)) (:goal-reward 10) (:metric maximize (reward)))""")
    inst = PDDLInstance.from_files(tmp_path / "toll.pddl", tmp_path / "p.pddl")
    ctx = pddl_task_context(inst)
    at = {x: s for s in range(ctx.n_states) for x in "abg" if f"at {x}" in inst.state_name(s)}
    return ctx, at


@pytest.mark.parametrize("back", [None, 1])
def test_the_prior_on_the_own_scale_pays_the_files_rewards(tmp_path, back):
    """Hand-derived (gamma 0.95, goal reward 10, the flat cost c = min(1, 10 / step
    limit) besides): the prior pays each pair the most any of its outcomes pays, and
    reaches the successor closest to the goal. From b: walk -1, dash 2 (its outcome that
    reaches g pays -5: the prior is optimistic in both), so V(b) = 2 - c + 10; from a:
    V(a) = max(-3 - c + 10, 4 - c + 0.95 V(b)) (the flat cost alone would prefer
    walking). A bus back paying 1 makes a loop that pays more: with x = 4 - c and
    y = 1 - c, V(a) = (x + 0.95 y) / (1 - 0.95**2), V(b) = max(12 - c, y + 0.95 V(a)).
    OptInit starts from them (one sweep)."""
    ctx, at = _toll(tmp_path, back)
    assert ctx.own_scale and ctx.prior_reward is not None
    learner = GDQ(ctx)
    t, p = learner.tables, learner.params
    c = min(1.0, 10.0 / ctx.step_limit)
    assert p.prior_cost == c and t.prior.reward.shape == (ctx.n_states, ctx.n_actions)
    a, b = at["a"], at["b"]
    assert sorted(t.prior.reward[a][ctx.live[a]]) == [-3.0, 4.0]
    assert sorted(t.prior.reward[b][ctx.live[b]]) == ([-1.0, 2.0] if back is None
                                                      else [-1.0, 1.0, 2.0])
    if back is None:
        want_b = 12 - c
        want_a = max(7 - c, 4 - c + 0.95 * want_b)
    else:
        x, y = 4 - c, 1 - c
        want_a = (x + 0.95 * y) / (1 - 0.95 ** 2)
        want_b = y + 0.95 * want_a
        assert want_b > 12 - c
    assert learner.v[a] == pytest.approx(want_a, abs=1e-9)
    assert learner.v[b] == pytest.approx(want_b, abs=1e-9)
    init = warm_start.prior_values(t.table, t.prior, p)
    assert init[a] == pytest.approx(want_a, abs=1e-9) and init[at["g"]] == 0.0
    assert gdq.value_iteration(t.table, t.model, t.prior, t.queue, p, 1e-9, 1000) == 1
    walk = int(np.flatnonzero(t.prior.reward[a] == -3.0)[0])
    assert learner.q[a, walk] == pytest.approx(7.0 - c)  # -3 - c + 10: the goal pays besides


def test_a_goal_scale_learner_keeps_the_flat_prior():
    """Without the file's rewards the prior is the flat cost's: no reward array, and
    OptInit's values the closed form by goal distance, R_max at one step."""
    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.learners import pddl_task_context

    inst = load_instance("lift", "lift-1")
    ctx = pddl_task_context(inst)
    assert not ctx.own_scale and ctx.prior_reward is None
    learner = GDQ(ctx)
    t, p = learner.tables, learner.params
    assert t.prior.reward.shape == (0, 0) and p.prior_cost == 1.0
    d = inst.graph.distances
    want = np.where(d == 0, 0.0, np.where(d < 0, -1.0 / (1 - p.gamma), 0.0))
    for s in np.flatnonzero(d > 0):
        x = p.r_max
        for _ in range(d[s] - 1):
            x = -1.0 + p.gamma * x
        want[s] = x
    assert np.array_equal(learner.v, want)


def test_a_context_refuses_file_rewards_off_the_own_scale(ctx_c):
    with pytest.raises(ConfigError, match="own_scale"):
        GDQ(replace(ctx_c, prior_reward=np.zeros((ctx_c.n_states, ctx_c.n_actions))))
