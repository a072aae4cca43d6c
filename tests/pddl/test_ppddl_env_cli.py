"""PPDDL end to end: the env on a PPDDL domain, learners on it, gymnasium.make, step
limits, and the command line on a PPDDL domain written here (run, plan, errors that
say why); runs that do not depend on the hash seed."""

from __future__ import annotations

import json
import os
import sys

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from gdq_pddl.cli import main
from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLEnv, PDDLInstance
from gdq_pddl.envs.solve import expected_costs, solve
from gdq_pddl.errors import PlanningError, WorldError
from gdq_pddl.learners import make_learner, pddl_task_context, run_episodes
from tests.helpers import BACKGROUND
from tests.helpers import REPO_ROOT as ROOT
from tests.pddl.hike import HIKE_DOMAIN, HIKE_PROBLEM, hike, hike_files

# --- the env, the learners, the command line ----------------------------------------

def test_the_env_passes_the_checker_and_learners_run_on_it():
    inst = hike()
    env = PDDLEnv(instance=inst)
    check_env(env, skip_render_check=True)
    ctx = pddl_task_context(inst)
    assert ctx.plans.length[0] == 3
    out = []
    for fast in (True, False):
        env.reset(seed=1)
        learner = make_learner("gdq", ctx, variant="code")
        out.append(run_episodes(learner, env, 30, np.random.default_rng(2), fast=fast))
    np.testing.assert_array_equal(out[0].returns, out[1].returns)


def test_the_env_takes_a_ppddl_domain_file_alone():
    env = PDDLEnv(ROOT / "domains" / "keys-ppddl.pddl", ROOT / "problems" / "keys-ppddl-2.pddl")
    check_env(env, skip_render_check=True)
    assert env.instance.dynamics.step_limit == 20  # no overlay: max(20, ceil(2.5 x 7))


@pytest.mark.parametrize("determinisation", ["all-outcomes", "most-likely"])
def test_gymnasium_make_takes_the_determinisation(tmp_path, determinisation):
    import gymnasium

    d, p = hike_files(tmp_path)
    env = gymnasium.make("gdq_pddl/PDDL-v0", domain=str(d), problem=str(p),
                         determinisation=determinisation).unwrapped
    check_env(env, skip_render_check=True)
    assert env.instance.determinisation == determinisation
    want = hike(determinisation).graph  # the planner's knowledge: the graph's edges
    np.testing.assert_array_equal(env.instance.graph.edge_next, want.edge_next)
    assert gymnasium.make("gdq_pddl/PDDL-v0", domain=str(d),
                          problem=str(p)).unwrapped.instance.determinisation == "all-outcomes"
    with pytest.raises(PlanningError, match="unknown determinisation 'best'"):
        gymnasium.make("gdq_pddl/PDDL-v0", domain=str(d), problem=str(p),
                       determinisation="best")


def test_a_step_limit_below_the_way_reality_reaches_the_goal_is_refused(tmp_path):
    """Most-likely knows no way to e1 (wading mostly does nothing), so no plan is longer
    than the step limit; reality's fewest actions (walk, wade, walk) are."""
    domain = HIKE_DOMAIN.replace("0.5 (and (at ?b)", "0.2 (and (at ?b)")
    problem = HIKE_PROBLEM.replace("(trail w4 e4) (trail e4 w4)", "")
    short = PDDLInstance.from_texts(domain, problem, "[dynamics]\nstep_limit = 2\n",
                                    determinisation="most-likely")
    with pytest.raises(WorldError, match=r"<string>: dynamics.step_limit: 2 is less than the "
                       r"fewest actions .* in reality \(3 actions; the knowledge has no plan"):
        short.model  # noqa: B018
    assert PDDLInstance.from_texts(domain, problem, "[dynamics]\nstep_limit = 3\n",
                                   determinisation="most-likely").model.step_limit == 3


@pytest.mark.parametrize(("which", "old", "new", "names"), [
    (0, "(probabilistic 0.9 (and", "(probabilistic 0 (and", [
        "hike.pddl", "(at e1) can never hold (no outcome of positive probability of"]),
    (1, "(:goal (at e1))", "(:goal (and (at e1) (not (at e1))))", [
        "hike-4.pddl", "(at e1) and (not (at e1)), which can never both hold"]),
])
def test_a_ppddl_goal_that_can_never_hold_says_why(tmp_path, capsys, which, old, new, names):
    texts = [HIKE_DOMAIN, HIKE_PROBLEM]
    assert old in texts[which]
    texts[which] = texts[which].replace(old, new)
    if which == 0:  # nor may the wader reach e1
        texts[0] = texts[0].replace("0.5 (and (at ?b)", "0 (and (at ?b)")
    d, p = hike_files(tmp_path, *texts)
    assert main(["run", "--domain", str(d), "--problem", str(p), "--episodes", "2", "--runs",
                 "1", "--jobs", "1", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"gdq-pddl: error: {p}: no plan: the goal cannot be reached"), err
    assert all(n in err for n in names), err


def test_cli_runs_a_ppddl_domain_nobody_has_seen_without_a_dynamics_file(tmp_path):
    (tmp_path / "d.pddl").write_text(HIKE_DOMAIN)
    (tmp_path / "p.pddl").write_text(HIKE_PROBLEM)
    out = tmp_path / "out"
    code = main(["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--episodes", "20", "--runs", "1",
                 "--jobs", "1", "--out", str(out)])
    assert code == 0
    report = (out / "REPORT.md").read_text()
    for method in ("GDQ", "GDQ-code", "DARLING", "Dyna-Q", "Q-learning"):  # the defaults
        assert f"| {method} |" in report or f"| **{method}** |" in report, method
    assert "hike-4" in report and "all-outcomes determinisation" in report
    assert "shortest plan: 3 actions" in report
    optimal = json.loads((out / "optimal.json").read_text())
    entry = next(iter(optimal.values()))
    assert entry["determinisation"] == "all-outcomes" and entry["r_max"] == 30.0
    assert entry["v_star"] == pytest.approx(solve(hike().model, GOAL_POS).V[0, 0])


def test_cli_most_likely_and_plan(tmp_path, capsys):
    (tmp_path / "d.pddl").write_text(HIKE_DOMAIN)
    (tmp_path / "p.pddl").write_text(HIKE_PROBLEM)
    assert main(["plan", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl")]) == 0
    assert "(wade_o1 w2 e2 e3)" in capsys.readouterr().out
    assert main(["plan", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--determinisation", "most-likely"]) == 0
    assert "(wade w2 e2 e3)" in capsys.readouterr().out
    out = tmp_path / "out"
    assert main(["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--determinisation", "most-likely",
                 "--method", "GDQ-code", "--episodes", "5", "--runs", "1", "--jobs", "1",
                 "--out", str(out)]) == 0
    assert "most-likely determinisation" in (out / "REPORT.md").read_text()
    (tmp_path / "o.toml").write_text("[actions.wade]\nsuccess = 0.5\n")
    assert main(["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--dynamics", str(tmp_path / "o.toml")]) == 2
    assert "o.toml: actions.wade.success: " in capsys.readouterr().err


def test_a_strips_domain_s_stated_cost_is_the_default_of_its_dynamics_file():
    domain = """(define (domain line) (:requirements :strips :action-costs)
      (:predicates (at1) (at2) (at3))
      (:functions (total-cost))
      (:action a :parameters () :precondition (at1)
        :effect (and (at2) (not (at1)) (increase (total-cost) 3)))
      (:action b :parameters () :precondition (at2)
        :effect (and (at3) (not (at2)) (increase (total-cost) 3))))"""
    problem = "(define (problem l) (:domain line) (:init (at1)) (:goal (at3)))"
    dynamics = "[actions.a]\nsuccess = 0.5\n[actions.b]\ncost = 0.5\n"
    inst = PDDLInstance.from_texts(domain, problem, dynamics)
    assert not inst.ppddl and inst.dynamics.outcomes("a", ()).success == 0.5
    assert expected_costs(inst.model).tolist() == [3.0, 0.5]


PPDDL_HASH_SEED_SCRIPT = """
import shutil, sys, tempfile
from pathlib import Path
import numpy as np
from gdq_pddl.envs.pddl_env import PDDLEnv
from gdq_pddl.learners import make_learner, pddl_task_context, run_episodes
folder = Path(tempfile.mkdtemp(prefix="gdq-hike-"))
(folder / "d.pddl").write_text(sys.argv[1])
(folder / "p.pddl").write_text(sys.argv[2])
env = PDDLEnv(str(folder / "d.pddl"), str(folder / "p.pddl"))
shutil.rmtree(folder)
inst = env.instance
print([op.name for op in inst.problem.task.ops], inst.model.prob.tolist())
env.reset(seed=0)
learner = make_learner("gdq", pddl_task_context(inst), variant="code")
print(run_episodes(learner, env, 20, np.random.default_rng(0)).returns.tolist())
"""


def start_ppddl_hash_seeds(item=None) -> list:
    """The hike run under two hash seeds, queued when collection ends to run beside the
    other tests (``tests.helpers.Background``)."""
    return [BACKGROUND.run(f"ppddl hash seed {seed}", [sys.executable, "-c",
                                                       PPDDL_HASH_SEED_SCRIPT, HIKE_DOMAIN,
                                                       HIKE_PROBLEM],
                           env=dict(os.environ, PYTHONHASHSEED=seed), timeout=300)
            for seed in ("1", "2")]


@pytest.mark.background.with_args(start_ppddl_hash_seeds)
def test_ppddl_runs_do_not_depend_on_the_hash_seed():
    """Ground actions, planner actions and outcomes come out in one order in every process."""
    outs = [future.result() for future in start_ppddl_hash_seeds()]
    for out in outs:
        assert out.returncode == 0, out.stderr[-2000:]
    assert outs[0].stdout == outs[1].stdout
