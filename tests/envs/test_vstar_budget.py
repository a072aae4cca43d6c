"""V* is computed within a budget; past it the run goes on with a bound (issue 22)."""

from __future__ import annotations

import json

from gdq_pddl.envs.pddl_env import PDDLInstance, load_instance
from gdq_pddl.envs.solve import Budget, solve, value_within
from gdq_pddl.experiments.checks import check_instance
from gdq_pddl.resources import data_file
from tests.helpers import cli


def test_vstar_within_the_budget_equals_value_iteration():
    inst = load_instance("keys-ppddl", "keys-ppddl-2")
    assert inst.optimal()["v_star"] == solve(inst.model, inst.goal_pos).V[0, 0]


def test_past_the_budget_vstar_is_skipped_said_and_bounded():
    inst = load_instance("keys-ppddl", "keys-ppddl-2")
    out = value_within(inst.model, inst.goal_pos, 0, Budget(bytes=1000, work=10**9))
    assert out["v_star"] is None and "not computed" in out["v_star_note"]
    assert "VSTAR_BUDGET" in out["v_star_note"]
    v = solve(inst.model, inst.goal_pos).V[0, 0]
    assert v <= out["v_star_upper_bound"] < inst.model.r_max
    assert value_within(inst.model, inst.goal_pos, 0, Budget(work=10))["v_star"] is None


def test_a_run_past_the_budget_writes_the_note(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(value_within, "__defaults__", (Budget(bytes=1000),))
    code, _ = cli(capsys, "run", "--domain", data_file("domains", "keys-ppddl.pddl"),
                  "--problem", data_file("problems", "keys-ppddl-1.pddl"),
                  "--method", "Q-learning", "--episodes", "3", "--runs", "1", "--jobs", "1",
                  "--no-report", "--out", tmp_path / "o")
    assert code == 0
    (entry,) = json.loads((tmp_path / "o" / "optimal.json").read_text()).values()
    assert entry["v_star"] is None and entry["v_star_upper_bound"] <= entry["r_max"]


def test_a_step_limit_past_memory_leaves_vstar_out_instead_of_refusing_the_problem():
    text = data_file("dynamics", "keys.toml").read_text().replace(
        "step_limit = 25", "step_limit = 3000000000")
    inst = PDDLInstance.from_texts(data_file("domains", "keys.pddl").read_text(),
                                   data_file("problems", "keys-1.pddl").read_text(), text)
    check_instance(inst)  # preflight lets it run
    out = inst.optimal()
    assert out["v_star"] is None and "GB" in out["v_star_note"]
