"""Experiments where the PDDL knowledge disagrees with the world (gdq-pddl knowledge)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from gdq_pddl.cli import main
from gdq_pddl.envs.evaluate import policy_value
from gdq_pddl.envs.model import compile_model, full_state
from gdq_pddl.envs.solve import solve_task
from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.knowledge import (
    CASES,
    PASSAGE,
    derived_world,
    knowledge_experiments,
    knowledge_instance,
    knowledge_world,
    problem_truth,
    route_check,
)
from gdq_pddl.experiments.protocol import Experiment, Unit
from gdq_pddl.experiments.work import (
    context_of,
    load_pddl_instance,
    load_world_named,
    make_learner,
    run_unit,
)
from gdq_pddl.learners import office_task_context, registry
from gdq_pddl.spaces import LearnerSpaces


def _plan_pairs(table, spaces):
    return {(spaces.state_name(int(s)), spaces.action_name(int(a)))
            for s, a in zip(table.pair_state, table.pair_action, strict=True)}


def test_locked_door_is_believed_usable_but_locked_in_reality(office):
    real = load_world_named("office:locked-d3")
    assert LearnerSpaces(real).states == LearnerSpaces(office).states
    spaces = LearnerSpaces(office)
    wrong = office_task_context(knowledge_world(real, "office"), "C")
    pairs = _plan_pairs(wrong.plans, spaces) | _plan_pairs(wrong.darling_plans, spaces)
    assert ("p6 (door open)", "gothrough p7") in pairs  # the knowledge plans through d3
    # reality: d3 never opens (success 0) and never traps the robot
    d3 = {d.name: d for d in real.doors}["d3"]
    assert (d3.success, d3.stuck) == (0.0, 0.0)
    model = compile_model(real)
    fs = full_state(real, "p6")
    i = fs * model.n_actions + spaces.action("opendoor", "p6")
    assert list(model.next[model.ptr[i]:model.ptr[i + 1]]) == [fs]
    assert not model.stuck[model.ptr[i]:model.ptr[i + 1]].any()
    # accurate knowledge (built from the real world) knows the door is a wall
    accurate = office_task_context(real, "C")
    acc_pairs = _plan_pairs(accurate.plans, spaces) | _plan_pairs(accurate.darling_plans, spaces)
    assert not any(a in ("gothrough p7", "gothrough p6") for _, a in acc_pairs)


def test_passage_exists_in_reality_but_in_no_plan(office):
    real = load_world_named("office:passage")
    a, b = PASSAGE
    assert b in real.walk_neighbours[a] and b not in office.walk_neighbours[a]
    spaces = LearnerSpaces(real)
    goto = spaces.action("goto", b)
    model = compile_model(real)
    i = full_state(real, a) * model.n_actions + goto
    outcomes = dict(zip(model.pos_of[model.next[model.ptr[i]:model.ptr[i + 1]]].tolist(),
                        model.prob[model.ptr[i]:model.ptr[i + 1]].tolist(), strict=True))
    assert outcomes[real.index[b]] >= real.navigation_success
    wrong = office_task_context(knowledge_world(real, "office"), "C")
    s = spaces.state(a)
    for table in (wrong.plans, wrong.darling_plans):
        assert not table.first_actions[:, goto][s]
        assert not np.any((table.pair_state == s) & (table.pair_action == goto))
    # DARLING's allowed set at p8 therefore excludes the optimal action
    steps = route_check(real, office, real.task("C"))
    assert [s.state for s in steps if not s.darling_allowed] == [a]
    assert all(s.darling_allowed for s in route_check(real, real, real.task("C")))


def test_spurious_passage_is_planned_on_but_missing_in_reality(office):
    """The spurious effect: the knowledge believes goto p17 at p8 leads to p17 (its
    shortest plans take it); in reality that action does not exist as a move (the robot
    stays at p8)."""
    case = next(c for c in CASES if c.name == "spurious-passage")
    real = load_world_named(case.real)
    a, b = PASSAGE
    assert b not in real.walk_neighbours[a]
    knowledge = knowledge_world(real, case.knowledge)
    assert b in knowledge.walk_neighbours[a]
    spaces = LearnerSpaces(real)
    goto, s = spaces.action("goto", b), spaces.state(a)
    model = compile_model(real)
    i = full_state(real, a) * model.n_actions + goto
    assert set(model.pos_of[model.next[model.ptr[i]:model.ptr[i + 1]]].tolist()) == \
        {real.index[a]}  # in reality goto p17 leaves the robot where it is
    wrong = office_task_context(knowledge, "C")
    assert wrong.plans.first_actions[s, goto]  # the knowledge's shortest plan takes it
    accurate = office_task_context(real, "C")
    assert not accurate.plans.first_actions[s, goto]
    assert not accurate.darling_plans.first_actions[s, goto]


def test_control_knowledge_is_the_accurate_knowledge(office):
    det = derived_world("office:deterministic")
    a, b = office_task_context(office, "C"), office_task_context(det, "C")
    for x, y in ((a.plans, b.plans), (a.darling_plans, b.darling_plans)):
        assert np.array_equal(x.pair_state, y.pair_state)
        assert np.array_equal(x.pair_action, y.pair_action)


def test_knowledge_world_must_have_the_same_spaces(office):
    with pytest.raises(GdqError, match="learner spaces differ"):
        knowledge_world(office, "office_robot")
    with pytest.raises(GdqError, match="unknown derived world"):
        load_world_named("office:nowhere")


def test_experiments_pair_each_case_with_accurate_knowledge():
    exps = knowledge_experiments(episodes=10, runs=2)
    assert len(exps) == 2 * len(CASES)
    for c, (acc, wrong) in zip(CASES, zip(exps[::2], exps[1::2], strict=True), strict=True):
        if c.pddl is None:
            assert acc.world == wrong.world == c.real
        else:  # a PDDL case: reality is its files, the knowledge another domain file
            assert acc.pddl == wrong.pddl == c.pddl and c.pddl.domain == c.real
        assert acc.knowledge is None and wrong.knowledge == c.knowledge


def test_every_guided_method_runs_each_case_by_default():
    guided = [e.name for e in registry.BUILT_IN if e.knowledge != "none"]
    assert {"GDQ", "GDQ-literal", "GDQ-code", "DARLING", "Q-shaping", "Dyna-Q-shaping",
            "Plan-shaping", "R-max-shaping", "FF-Replan"} <= set(guided)
    for exp in knowledge_experiments(episodes=10, runs=1):
        if exp.pddl is None:
            assert list(exp.methods) == guided
        else:  # FF-Replan told the case's determinisation (it refuses another)
            assert [m.split(":")[0] for m in exp.methods] == guided
            assert "FF-Replan:determinisation=most-likely" in exp.methods
            for unit in exp.units():  # every guided method runs on it
                run_unit(replace(unit, experiment=replace(exp, schedule=((exp.schedule[0][0],
                                                                            2),))))


def test_wrong_probabilities_differ_from_reality_exactly_as_documented():
    case = next(c for c in CASES if c.name == "wrong-probabilities")
    real = load_pddl_instance(case.pddl)
    known = knowledge_instance(real, case.pddl, case.knowledge)
    # the same states and actions, so the learners' tables agree ...
    assert known.graph.states == real.graph.states
    assert np.array_equal(known.columns, real.columns)
    # ... and every pair's outcomes are the same, with other probabilities only at the
    # locks: unlock (sound, blue) 0.9 -> 0.3 opens; unlock-stiff (red) 0.5 / 0.3 -> 0.9 /
    # 0.05 (open / jammed)
    r, k = real.model, known.model
    assert np.array_equal(r.ptr, k.ptr) and np.array_equal(r.next, k.next)
    changed = {}
    for s in range(real.n_states):
        for j, a in enumerate(real.columns[s]):
            if a < 0:
                continue
            i = s * real.columns.shape[1] + j
            lo, hi = r.ptr[i], r.ptr[i + 1]
            if not np.allclose(r.prob[lo:hi], k.prob[lo:hi]):
                name = real.action_name(int(a)).strip("()").split()[0]
                changed.setdefault(name, set()).add(
                    (tuple(np.round(r.prob[lo:hi], 6)), tuple(np.round(k.prob[lo:hi], 6))))
    assert set(changed) == {"unlock", "unlock-stiff"}
    assert all(sorted(real_p) == sorted((0.1, 0.9)) and sorted(known_p) == sorted((0.3, 0.7))
               for real_p, known_p in changed["unlock"])
    assert all(sorted(real_p) == sorted((0.2, 0.3, 0.5)) and
               sorted(known_p) == sorted((0.05, 0.05, 0.9))
               for real_p, known_p in changed["unlock-stiff"])
    # the knowledge's plans (most-likely outcomes) take the red door only, reality's both
    truth = problem_truth({"pddl": case.pddl, "knowledge": case.knowledge})
    assert truth.first_actions["accurate"] == ("(move c11 c12)", "(move c11 c21)")
    assert truth.first_actions["wrong"] == ("(move c11 c12)",)
    assert truth.believed_v_star < truth.v_star


def test_a_knowledge_domain_with_other_outcomes_is_refused(tmp_path):
    """Moves that always work: the same states, but no 'nothing happens' outcome."""
    case = next(c for c in CASES if c.name == "wrong-probabilities")
    real = load_pddl_instance(case.pddl)
    text = Path(case.pddl.domain).read_text()
    assert "(probabilistic 0.95 (and (at ?to)" in text
    other = tmp_path / "keys-ppddl.pddl"
    other.write_text(text.replace("(probabilistic 0.95 (and (at ?to)",
                                  "(probabilistic 1.0 (and (at ?to)"))
    with pytest.raises(GdqError, match="does not give the reachable states"):
        knowledge_instance(real, case.pddl, str(other))


def test_a_pddl_experiment_plans_on_the_knowledge_domain():
    case = next(c for c in CASES if c.name == "wrong-probabilities")
    acc, wrong = (e for e in knowledge_experiments(episodes=5, runs=1, methods=("GDQ-code",))
                  if e.name.startswith(case.name))
    real = load_pddl_instance(case.pddl)
    s = real.learner_start
    a, w = context_of(acc, real), context_of(wrong, real)
    assert a.plans.first_actions[s].sum() == 2 and w.plans.first_actions[s].sum() == 1
    # the env stays reality's: a run with the wrong knowledge differs from the accurate one
    got = run_unit(Unit(wrong, "GDQ-code", 0))
    assert len(got["returns"]) == 5


def test_knowledge_none_is_bit_identical_to_before(office):
    """knowledge=None changes nothing: same keys, seeds and results as the loop the runner
    had before the field existed."""
    from gdq_pddl.envs.office import OfficeEnv
    from gdq_pddl.learners.episodes import run_episodes

    exp = Experiment("tasks", (("C", 40),), methods=("GDQ-code", "DARLING"), runs=1)
    for method in exp.methods:
        unit = Unit(exp, method, 0)
        assert unit.key == "tasks__C__" + method + "__run0"
        got = run_unit(unit)
        rng, env_seed = unit.seeds()
        task = office.task("C")
        learner = make_learner(method, office_task_context(office, task), exp.hyper)
        env = OfficeEnv(world=office, start=task.start, goal=task.goal)
        env.reset(seed=env_seed)
        ref = run_episodes(learner, env, 40, rng)
        assert np.array_equal(got["returns"], ref.returns)
        assert np.array_equal(got["policy"], learner.greedy_policy())
        # naming the real world as the knowledge is the same experiment
        same = run_unit(Unit(replace(exp, knowledge="office"), method, 0))
        assert np.array_equal(same["returns"], got["returns"])
        assert Unit(replace(exp, knowledge="office"), method, 0).key == unit.key


def test_policy_value_of_the_optimal_first_step_policy_is_v_star(office):
    task = office.task("C")
    model = compile_model(office)
    sol, s0 = solve_task(office, task, model)
    pi: dict[int, int] = {}
    for fs in range(len(model.obs_of)):
        pi.setdefault(int(model.obs_of[fs]), int(sol.policy[0, fs]))
    assert policy_value(office, task, pi, model) == pytest.approx(sol.V[0, s0], abs=1e-3)


def test_knowledge_command_end_to_end(tmp_path):
    out = tmp_path / "k"
    assert main(["knowledge", "--episodes", "30", "--runs", "1", "--jobs", "1",
                 "--method", "GDQ-code", "DARLING", "--out", str(out)]) == 0
    report = (out / "REPORT.md").read_text()
    for c in CASES:
        assert f"## {c.name}" in report
    assert "DARLING allows an optimal action" in report
    assert "no, not at p8 (goto p17)" in report  # the passage case, measured
    assert "corridor p8-p17 that reality lacks" in report  # the spurious effect's case
    assert "V* the knowledge believes (its own probabilities) = 10.803" in report
    assert "wrong knowledge (move c11 c12)\n" in report  # the wrong probabilities' plans
    for stem in ("knowledge_curves", "knowledge_convergence"):
        assert (out / f"{stem}.png").stat().st_size > 0


def test_run_takes_a_ppddl_knowledge_domain(tmp_path, capsys):
    """gdq-pddl run --knowledge-domain: the learners plan on that file, the env simulates
    --domain; recorded in config.json; one with other outcomes, or online, is refused."""
    case = next(c for c in CASES if c.name == "wrong-probabilities")
    out = tmp_path / "r"
    common = ["run", "--problem", "keys-ppddl-1", "--determinisation", "most-likely",
              "--episodes", "3", "--runs", "1", "--jobs", "1", "--method", "GDQ-code"]
    assert main([*common, "--knowledge-domain", case.knowledge, "--out", str(out)]) == 0
    exp = json.loads((out / "config.json").read_text())["experiments"][0]
    assert exp["knowledge"] == case.knowledge and exp["pddl"]["domain"].endswith("keys-ppddl.pddl")
    other = tmp_path / "keys-ppddl.pddl"
    other.write_text(Path(case.pddl.domain).read_text().replace(
        "(probabilistic 0.95 (and (at ?to)", "(probabilistic 1.0 (and (at ?to)"))
    capsys.readouterr()
    assert main([*common, "--knowledge-domain", str(other), "--out", str(tmp_path / "x")]) == 2
    assert "does not give the reachable states" in capsys.readouterr().err
    assert main([*common, "--explore", "online", "--knowledge-domain", case.knowledge,
                 "--out", str(tmp_path / "y")]) == 2
    assert main(["run", "--task", "C", "--knowledge-domain", case.knowledge, "--episodes",
                 "2", "--out", str(tmp_path / "z")]) == 2
