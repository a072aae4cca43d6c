"""The learners side by side: equivalences, determinism and fast path == Python path,
runs without any plan, task switches, make_learner's checks, the numba cache, and
tables refused past the machine's memory. OptInit, the learned model and DARLING
have modules of their own."""

from __future__ import annotations

import pickle
from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import (
    GDQ,
    Darling,
    DarlingConfig,
    DynaQ,
    DynaQConfig,
    GDQConfig,
    QLearning,
    empty_plan_table,
    make_learner,
    office_task_context,
)
from gdq_pddl.world_types import Task
from tests.helpers import Recording, run
from tests.learners.learning import DET, WORLD, expected_backup

ALL = [("qlearning", {}), ("dynaq", {}), ("darling", {}), ("darling", {"variant": "code"}),
       ("gdq", {}), ("gdq", {"variant": "literal"}), ("gdq", {"variant": "code"})]


# --- equivalences and determinism ---------------------------------------------------------

def test_dynaq_without_backups_acts_exactly_like_qlearning(ctx_c):
    env = OfficeEnv(task="C")
    a = Recording(DynaQ(ctx_c, DynaQConfig(n_backups=0)))
    b = Recording(QLearning(ctx_c))
    run(a, env, 60, 11, fast=False)
    run(b, env, 60, 11, fast=False)
    assert a.actions == b.actions
    assert np.array_equal(a.q, b.q)


@pytest.mark.parametrize(("method", "kw"), ALL)
def test_same_seed_same_results_bit_for_bit(ctx_c, method, kw):
    env = OfficeEnv(task="C")
    out = []
    for _ in range(2):
        learner = make_learner(method, ctx_c, **kw)
        rec = run(learner, env, 80, 5)
        out.append((rec, learner.q.copy()))
    (r1, q1), (r2, q2) = out
    for f in ("returns", "steps", "success", "area_visits"):
        assert np.array_equal(getattr(r1, f), getattr(r2, f))
    assert np.array_equal(q1, q2)


@pytest.mark.parametrize(("method", "kw"), ALL)
def test_fast_path_equals_python_path(ctx_c, method, kw):
    env = OfficeEnv(task="C")
    fast, slow = make_learner(method, ctx_c, **kw), make_learner(method, ctx_c, **kw)
    rf = run(fast, env, 40, 7, fast=True)
    rs = run(slow, env, 40, 7, fast=False)
    for f in ("returns", "steps", "success", "area_visits"):
        assert np.array_equal(getattr(rf, f), getattr(rs, f)), f
    assert np.array_equal(fast.q, slow.q)
    assert np.array_equal(fast.tables.model.slots, slow.tables.model.slots)  # the same slots, too
    assert np.array_equal(fast.counts, slow.counts)
    assert rf.area_visits.sum() == rf.steps.sum()  # every office position has an area
    assert rf.area_visits.shape == (40, 7)


def test_runner_works_through_gymnasium_make(ctx_c):
    import gymnasium

    env = gymnasium.make("gdq_pddl/Office-v0", task="C")
    learner = QLearning(ctx_c)
    rec_fast = run(learner, env, 20, 1)
    learner2 = QLearning(ctx_c)
    rec_slow = run(learner2, env, 20, 1, fast=False)
    assert np.array_equal(rec_fast.returns, rec_slow.returns)


# --- no plans, task switch ----------------------------------------------------------------

@pytest.mark.parametrize("variant", ["literal", "code"])
def test_gdq_without_any_plan_runs_and_learns(variant):
    """The plan-based variants with an empty H: Dyna-Q with extra steps, still learning.
    (The default variant plans on its prior model, not on H: tests/learners/test_gdq_model.py.)"""
    task = Task("near", "p0", "p2")
    ctx = office_task_context(DET, task)
    empty = empty_plan_table(ctx.n_states, ctx.n_actions)
    ctx = replace(ctx, plans=empty, darling_plans=empty)
    learner = GDQ(ctx, GDQConfig(variant=variant))
    assert not learner.optimistic_pairs.any()
    env = OfficeEnv(start="p0", goal="p2", world=DET)
    rec = run(learner, env, 150, 2)
    assert rec.success[-50:].mean() > 0.8
    assert rec.success[-50:].mean() > rec.success[:50].mean()
    assert learner.visits.sum() == rec.steps.sum()


def test_task_switch_keeps_the_model_and_reruns_optinit(ctx_c):
    learner = GDQ(ctx_c)
    env = OfficeEnv(task="C")
    run(learner, env, 30, 4)
    counts, visits = learner.counts.copy(), learner.visits.copy()
    assert visits.sum() > 0
    ctx_e = office_task_context(WORLD, "E")
    learner.start_task(ctx_e)
    assert np.array_equal(learner.counts, counts)
    assert np.array_equal(learner.visits, visits)
    assert learner.params.s0 == ctx_e.s0
    assert np.array_equal(learner.tables.table.goal, ctx_e.goal)
    # OptInit for E: the plan pairs from E's start are the optimistic ones, and the
    # greedy action at E's start begins one of its plans (unknown pairs dominate there)
    firsts = {p[0][1] for p in ctx_e.plans.plans_from(ctx_e.s0)}
    assert learner.greedy_policy()[ctx_e.s0] in firsts
    # the learned model is what the known pairs' backups use after the switch
    known = np.argwhere(visits > learner.params.m)
    assert len(known)
    s, a = map(int, known[0])
    assert expected_backup(learner.tables, learner.params, s, a, learner.v) == \
        pytest.approx(learner.q[s, a], abs=1e-6)
    run(learner, OfficeEnv(task="E"), 10, 5)  # keeps learning on the new task
    assert learner.visits.sum() > visits.sum()


def test_dynaq_task_switch_keeps_model_and_q(ctx_c):
    learner = DynaQ(ctx_c)
    run(learner, OfficeEnv(task="C"), 20, 4)
    q, counts = learner.q.copy(), learner.counts.copy()
    learner.start_task(office_task_context(WORLD, "D"))
    assert np.array_equal(learner.q, q) and np.array_equal(learner.counts, counts)


def test_make_learner_rejects_unknown_methods_and_bad_configs(ctx_c):
    with pytest.raises(ValueError):
        make_learner("sarsa", ctx_c)
    with pytest.raises(ValueError):
        GDQConfig(variant="other")  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        Darling(ctx_c, DarlingConfig(tolerance=0.5))


def test_numba_cache_is_dropped_when_a_compiled_module_changes(tmp_path):
    """The fast loop's cache bakes in the rules it calls from other files; an edit of
    any of them must drop the whole cache (gdq_pddl/_jit_cache.py)."""
    from gdq_pddl import _jit_cache

    for folder in _jit_cache.JIT_FOLDERS:
        (tmp_path / folder / "__pycache__").mkdir(parents=True)
        (tmp_path / folder / "mod.py").write_text("x = 1\n")
    cached = tmp_path / "learners" / "__pycache__" / "runner._episodes-1.py311.nbi"
    cached.write_text("stale")
    assert _jit_cache.refresh(tmp_path)  # no stamp yet: dropped, stamp written
    assert not cached.exists()
    # a whole .nbi file is two pickles (the index); a damaged one is dropped on its own
    cached.write_bytes(pickle.dumps("index") + pickle.dumps("entries"))
    assert not _jit_cache.refresh(tmp_path) and cached.exists()  # nothing changed
    (tmp_path / "learners" / "mod.py").write_text("x = 2\n")  # a callee changes
    assert _jit_cache.refresh(tmp_path) and not cached.exists()


def test_learner_tables_are_refused_past_the_machines_memory(monkeypatch):
    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.errors import PlanningError
    from gdq_pddl.learners import context
    from gdq_pddl.learners.tables import table_bytes

    inst = load_instance("courier", "courier-1")
    need = table_bytes(inst.n_states, inst.columns.shape[1], inst.max_successors)
    assert context.MAX_TABLE_BYTES is None  # the default: what the machine has
    monkeypatch.setenv("GDQ_PDDL_MEMORY", str(need))
    assert context.task_context(inst).columns is inst.columns  # fits exactly
    monkeypatch.setenv("GDQ_PDDL_MEMORY", str(need - 1))
    with pytest.raises(PlanningError, match=r"courier-1.pddl: .*learners' tables would need "
                       r".*this machine's memory, or .*MAX_TABLE_BYTES"):
        context.task_context(inst)
    monkeypatch.setattr(context, "MAX_TABLE_BYTES", need)  # a figure of one's own wins
    assert context.task_context(inst).columns is inst.columns
