"""Deep-RL agents in the runner (gdq_pddl.learners.deep): refused in one line without the
sb3 extra (its absence simulated), and, where it is installed, trained by ``gdq-pddl run``
into the same episodes.csv as the tabular learners, with the same seeds, --jobs, --resume
and report."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gdq_pddl
from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import registry
from gdq_pddl.learners.config import SB3_MODULES, DQNConfig, PPOConfig
from tests.helpers import cli

HINT = "needs `pip install 'gdq_pddl[sb3]'`"
DEEP = ("MaskablePPO", "PPO", "DQN")


@pytest.fixture
def no_sb3(monkeypatch):
    """The sb3 extra absent: importing its modules fails, as on a default install."""
    for module in SB3_MODULES:
        monkeypatch.setitem(sys.modules, module, None)


def test_without_the_extra_the_agents_are_listed_as_needing_it(no_sb3, capsys):
    code, out = cli(capsys, "methods")
    assert code == 0
    for name in DEEP:
        line = next(x for x in out.splitlines() if x.startswith(f"{name}:"))
        assert HINT in line
    assert HINT not in next(x for x in out.splitlines() if x.startswith("GDQ:"))
    code, out = cli(capsys, "list")
    assert code == 0
    assert sum(HINT in x for x in out.splitlines()) == len(DEEP)


@pytest.mark.parametrize("method", ["PPO", "MaskablePPO:steps=20000", "dqn"])
def test_without_the_extra_a_run_is_refused_in_one_line(no_sb3, capsys, tmp_path, method):
    code, out = cli(capsys, "run", "--task", "C", "--method", "GDQ", method, "--episodes", 2,
                    "--runs", 1, "--out", tmp_path / "out")
    assert code == 2
    assert out.strip().count("\n") == 0 and HINT in out and "Traceback" not in out
    assert not (tmp_path / "out").exists()


def test_without_the_extra_the_python_api_refuses_the_agents(no_sb3):
    from gdq_pddl.learners import office_task_context
    from gdq_pddl.learners.deep import PPO
    from gdq_pddl.world import builtin_world

    ctx = office_task_context(builtin_world("office"), "C")
    with pytest.raises(ConfigError, match=re.escape(f"method 'MaskablePPO' {HINT}")):
        registry.make_learner("MaskablePPO", ctx)
    with pytest.raises(ConfigError, match=re.escape(f"method 'PPO' {HINT}")):
        PPO(ctx)


def test_the_extra_is_found_when_its_modules_are(monkeypatch):
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: object())
    for module in SB3_MODULES:
        monkeypatch.delitem(sys.modules, module, raising=False)
    assert registry.missing(registry.entry("PPO")) == ""
    assert registry.canonical("ppo:steps=20000") == "PPO:steps=20000"


def test_importing_the_package_and_its_commands_does_not_import_torch():
    code = ("import sys, gdq_pddl, gdq_pddl.cli, gdq_pddl.learners.deep, "
            "gdq_pddl.experiments.runner; from gdq_pddl.learners import registry; "
            "[e.learner_class() for e in registry.entries()]; "
            "print(sorted(m for m in ('torch', 'stable_baselines3', 'sb3_contrib') "
            "if m in sys.modules))")
    root = str(Path(gdq_pddl.__file__).resolve().parents[1])
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={"PYTHONPATH": root, "PATH": ""}, timeout=300)
    assert out.stdout.strip() == "[]"


def test_settings_are_checked_against_the_agents_configs():
    method = registry.parse_method("PPO:shaping=distance,obs=facts,steps=20000")
    assert method.settings == {"shaping": "distance", "obs": "facts", "steps": 20000}
    config = method.entry.config(**method.config_kwargs({"alpha": 0.1, "gamma": 0.9}))
    assert isinstance(config, PPOConfig) and config.gamma == 0.9  # the experiment's gamma
    assert isinstance(registry.entry("DQN").config(), DQNConfig)
    with pytest.raises(ConfigError, match="shaping must be one of none, distance, plan-step"):
        registry.parse_method("PPO:shaping=plans")
    with pytest.raises(ConfigError, match="PPO has no setting 'buffer_size'"):
        registry.parse_method("PPO:buffer_size=10")
    with pytest.raises(ConfigError, match="hidden must be a whole number in"):
        registry.parse_method("DQN:hidden=0")
    assert not registry.entry("MaskablePPO").online
    assert set(DEEP).isdisjoint(registry.built_in_names())  # not run by default


# -- with the extra installed ------------------------------------------------------------


def _unit(method: str, episodes: int = 3):
    from gdq_pddl.experiments.protocol import Experiment, Unit

    exp = Experiment("deep", (("C", episodes),), methods=(method,), runs=1, world="office")
    return Unit(exp, method, 0)


def test_the_same_seeds_give_the_same_rows():
    pytest.importorskip("sb3_contrib")
    from gdq_pddl.experiments.work import run_unit

    first, again = run_unit(_unit("MaskablePPO:n_steps=16,batch_size=8")), \
        run_unit(_unit("MaskablePPO:n_steps=16,batch_size=8"))
    for key in ("returns", "steps", "success", "areas", "policy"):
        np.testing.assert_array_equal(first[key], again[key])
    assert len(first["returns"]) == 3 and first["steps"].min() >= 1
    assert len(first["policy"]) == 31  # the office's learner states, masked greedy actions


def test_a_step_budget_still_gives_every_episode_a_row():
    pytest.importorskip("sb3_contrib")
    from gdq_pddl.experiments.work import run_unit

    out = run_unit(_unit("DQN:steps=5,learning_starts=0", episodes=3))
    assert len(out["returns"]) == 3 and (out["steps"] >= 1).all()


def test_shaping_and_facts_leave_the_rows_unshaped():
    pytest.importorskip("sb3_contrib")
    pytest.importorskip("gdq_pddl.wrappers")
    from gdq_pddl.experiments.work import run_unit

    out = run_unit(_unit("PPO:shaping=distance,obs=facts,n_steps=16,batch_size=8"))
    assert len(out["returns"]) == 3
    # the office's rewards are whole numbers; gamma 0.95 shaping terms are not
    np.testing.assert_array_equal(out["returns"], np.round(out["returns"]))
    assert len(out["policy"]) == 0  # not a function of the state index: no policy rows


@pytest.mark.slow
def test_run_resume_and_report_compare_deep_agents_like_the_others(capsys, tmp_path):
    pytest.importorskip("sb3_contrib")
    from gdq_pddl.experiments.results import load_results

    out = tmp_path / "out"
    args = ("run", "--task", "C", "--method", "PPO", "MaskablePPO", "--episodes", 5,
            "--runs", 1, "--out", out)
    code, text = cli(capsys, *args, "--jobs", 2)
    assert code == 0, text
    df = load_results(out)
    assert sorted(df["method"].unique()) == ["MaskablePPO", "PPO"]
    assert len(df) == 10 and (df.groupby("method", observed=True)["episode"].max() == 5).all()
    before = (out / "episodes.csv").read_text()
    code, text = cli(capsys, *args, "--resume")
    assert code == 0 and "nothing to run" in text
    assert (out / "episodes.csv").read_text() == before
    code, text = cli(capsys, "report", out)
    assert code == 0, text
    report = (out / "REPORT.md").read_text()
    assert "MaskablePPO" in report and "| PPO |" in report


def test_train_steps_calls_checkpoints_after_each_update():
    """benchmarks/deep_rl.py's path: a step budget, checkpoints every ``every`` steps,
    each after the update of its rollout (the last one sees the trained network)."""
    pytest.importorskip("sb3_contrib")
    import gymnasium

    from gdq_pddl.learners import office_task_context
    from gdq_pddl.learners.registry import make_learner

    env = gymnasium.make("gdq_pddl/Office-v0", task="C").unwrapped
    agent = make_learner("MaskablePPO:n_steps=32,batch_size=16", office_task_context(
        env.world, "C"))
    seen: list[tuple[int, int]] = []  # (steps, updates so far)
    env.reset(seed=0)
    records = agent.train_steps(env, 64, np.random.default_rng(0), every=32,
                                checkpoint=lambda n: seen.append((n, agent.model._n_updates)))
    assert [n for n, _ in seen] == [0, 32, 64]
    assert [u for _, u in seen] == [0, 10, 20]  # PPO counts its 10 epochs per update
    assert records.steps.sum() <= 64
    obs = np.arange(5)
    masks = env.mask_table[:5].astype(bool)
    actions = agent.greedy_actions(obs, masks)
    assert actions.shape == (5,) and masks[np.arange(5), actions].all()
