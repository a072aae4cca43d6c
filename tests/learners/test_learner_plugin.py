"""A learner from another package (examples/learner_plugin: Expected SARSA), found through
the ``gdq_pddl.learners`` entry points: listed, made by name with settings, run in the
compiled loop (the same bits as the Python loop), run by the experiment runner.

The fast tests fake the entry point (the example's source on ``sys.path``); the slow one
installs the example with ``pip --target`` into a temporary directory and runs the
command line from it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from importlib.metadata import EntryPoint
from pathlib import Path

import numpy as np
import pytest

from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import registry

DEEP_NAMES = ("MaskablePPO", "PPO", "DQN")  # registry.DEEP: listed whether sb3 is there or not

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "learner_plugin"
NAME = "Expected-SARSA"


def _fake(monkeypatch, *points: tuple[str, str]) -> None:
    """The registry sees exactly these ``(name, "module:attr")`` learner entry points."""
    monkeypatch.syspath_prepend(str(EXAMPLE))
    eps = [EntryPoint(name, value, registry.GROUP) for name, value in points]
    monkeypatch.setattr(registry, "entry_points", lambda group: eps)
    registry.refresh()


@pytest.fixture
def plugin(monkeypatch):
    if not EXAMPLE.is_dir():
        pytest.skip("examples/learner_plugin is not in this checkout")
    _fake(monkeypatch, (NAME, "gdq_expected_sarsa:ENTRY"))
    yield
    monkeypatch.undo()
    registry.refresh()
    sys.modules.pop("gdq_expected_sarsa", None)


def test_the_plugin_is_listed_after_the_built_in_learners(plugin):
    assert registry.names() == (*registry.built_in_names(), *DEEP_NAMES, NAME)
    assert registry.canonical("expected_sarsa:alpha=0.2") == "Expected-SARSA:alpha=0.2"
    assert registry.colour(NAME) == "#8c564b"
    with pytest.raises(ConfigError, match="epsilon must be a number in"):
        registry.parse_method("Expected-SARSA:epsilon=2")


def test_broken_and_clashing_plugins_are_left_out_with_a_reason(monkeypatch):
    _fake(monkeypatch, ("broken", "gdq_no_such_module:ENTRY"),
          ("Q-learning", "gdq_expected_sarsa:ENTRY"))
    try:
        assert registry.names() == (*registry.built_in_names(), *DEEP_NAMES)
        why = sorted(registry.plugin_problems())
        assert len(why) == 2 and "gdq_no_such_module" in why[1] and "'broken'" in why[1]
        assert "its entry point is 'Q-learning' and its name 'Expected-SARSA'" in why[0]
    finally:
        monkeypatch.undo()
        registry.refresh()


def test_the_plugin_runs_in_the_compiled_loop_with_the_python_loops_bits(plugin):
    import gymnasium

    import gdq_pddl  # noqa: F401  (registers the env)
    from gdq_pddl.learners import make_learner, office_task_context, run_episodes
    from gdq_pddl.learners.episodes import why_not_compiled

    env = gymnasium.make("gdq_pddl/Office-v0", task="C")
    ctx = office_task_context(env.unwrapped.world, env.unwrapped.task)
    runs = []
    for fast in (True, False):
        learner = make_learner("expected-sarsa:alpha=0.3", ctx)
        assert why_not_compiled(learner, env) is None and learner.config.alpha == 0.3
        env.reset(seed=3)
        records = run_episodes(learner, env, 40, np.random.default_rng(4), fast=fast)
        runs.append((records.returns, records.steps, learner.q.copy()))
    for fast, slow in zip(*runs, strict=True):
        assert np.array_equal(fast, slow)
    assert np.any(runs[0][2] != 0.0)  # it learned something


def test_the_runner_runs_the_plugin_with_its_settings(plugin):
    from gdq_pddl.experiments.protocol import Experiment, Unit
    from gdq_pddl.experiments.work import run_unit

    exp = Experiment("t", (("C", 5),), methods=("expected_sarsa:epsilon=0.2",), runs=1)
    assert exp.methods == ("Expected-SARSA:epsilon=0.2",)
    out = run_unit(Unit(exp, exp.methods[0], 0))
    assert len(out["returns"]) == 5 and out["steps"].sum() > 0


@pytest.mark.slow
def test_installed_plugin_is_listed_and_run_by_the_command_line(tmp_path):
    import gdq_pddl

    source, site = tmp_path / "src", tmp_path / "site"
    shutil.copytree(EXAMPLE, source)  # builds leave nothing in the repo
    install = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps",
                              "--no-build-isolation", "--no-index", "--quiet", "--target",
                              str(site), str(source)], capture_output=True, text=True,
                             timeout=300)
    assert install.returncode == 0, install.stderr
    root = Path(gdq_pddl.__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=f"{site}{os.pathsep}{root}")
    cli = [sys.executable, "-m", "gdq_pddl.cli"]
    listed = subprocess.run([*cli, "list"], capture_output=True, text=True, env=env,
                            cwd=tmp_path, timeout=300)
    assert listed.returncode == 0 and f"  {NAME} " in listed.stdout, listed.stderr
    ran = subprocess.run([*cli, "run", "--task", "C", "--method", NAME, "--episodes", "3",
                          "--runs", "1", "--jobs", "1", "--no-report", "--out",
                          str(tmp_path / "out")], capture_output=True, text=True, env=env,
                         cwd=tmp_path, timeout=600)
    assert ran.returncode == 0, ran.stderr
    rows = (tmp_path / "out" / "episodes.csv").read_text().splitlines()
    assert len(rows) == 4 and all(f",{NAME}," in r for r in rows[1:])
