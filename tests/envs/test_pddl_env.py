"""Any PDDL domain with a dynamics file: validation, the compiled model, plan tables from
the state graph, the env contract, the office as one instance, learning on the shipped
domains, and the command line end to end on a domain written here."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from gdq_pddl.abstraction.pddl import PDDLAbstraction, graph_plan_table
from gdq_pddl.abstraction.table import build_plan_table
from gdq_pddl.cli import main
from gdq_pddl.dynamics import parse_dynamics
from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLEnv, PDDLInstance
from gdq_pddl.envs.solve import optimal_value, solve
from gdq_pddl.envs.step import pair_of
from gdq_pddl.errors import PlanningError, WorldError
from gdq_pddl.learners import make_learner, pddl_task_context, run_episodes
from gdq_pddl.pddl.reachable import reachable_graph
from gdq_pddl.planning import get_planner
from gdq_pddl.world import load_world
from tests.helpers import DYNAMICS as DYN
from tests.helpers import REPO_ROOT as ROOT

# A domain no shipped file knows: switch lamps on along a line of rooms.
LAMPS_DOMAIN = """
(define (domain lamps)
  (:requirements :strips :typing)
  (:types room)
  (:predicates (at ?r - room) (next ?a ?b - room) (dark ?r - room) (lit ?r - room))
  (:action go :parameters (?a ?b - room)
    :precondition (and (at ?a) (next ?a ?b)) :effect (and (at ?b) (not (at ?a))))
  (:action switch :parameters (?r - room)
    :precondition (and (at ?r) (dark ?r)) :effect (and (lit ?r) (not (dark ?r)))))
"""
LAMPS_PROBLEM = """
(define (problem lamps-3) (:domain lamps)
  (:objects r1 r2 r3 r4 - room)
  (:init (at r1) (next r1 r2) (next r2 r1) (next r2 r3) (next r3 r2) (next r3 r4)
         (next r4 r3) (dark r1) (dark r2) (dark r3) (dark r4))
  (:goal (and (lit r2) (lit r4))))
"""
LAMPS_DYNAMICS = """
[dynamics]
r_max = 10.0
step_limit = 15

[actions.go]
success = 0.9
failure = ["go"]

[actions.switch]
success = 0.8
stuck = 0.05
cost = { dist = "normal", mean = 1.0, sd = 0.2 }

[actions.switch.objects.r4]
success = 0.5
"""


def lamps() -> PDDLInstance:
    return PDDLInstance.from_texts(LAMPS_DOMAIN, LAMPS_PROBLEM, LAMPS_DYNAMICS)


@pytest.fixture(scope="module")
def office_c() -> PDDLInstance:
    return PDDLInstance.from_files(ROOT / "domains" / "office.pddl",
                                   ROOT / "problems" / "task-c.pddl",
                                   ROOT / "gdq_pddl" / "data" / "office.toml")


def shipped(domain: str, problem: str) -> PDDLInstance:
    return PDDLInstance.from_files(ROOT / "domains" / f"{domain}.pddl",
                                   ROOT / "problems" / f"{problem}.pddl", DYN / f"{domain}.toml")


# --- the dynamics file --------------------------------------------------------------

@pytest.mark.parametrize("old,new,where", [
    ("[actions.go]", "[actions.fly]", "actions.fly"),
    ("[actions.switch.objects.r4]", "[actions.switch.objects.r9]", "actions.switch.objects.r9"),
    ("success = 0.9", "success = 1.5", "actions.go.success"),
    ("stuck = 0.05", "stuck = 0.3", "actions.switch"),
    ('failure = ["go"]', 'failure = ["jump"]', "actions.go.failure"),
    ('failure = ["go"]', 'failure = "explode"', "actions.go.failure"),
    ('failure = ["go"]', 'failure = "stuck"\nstuck = 0.1', "actions.go.stuck"),
    ("sd = 0.2", "sd = -1", "actions.switch.cost"),
    ("step_limit = 15", "step_limit = 0", "dynamics.step_limit"),
    ("r_max = 10.0", "r_max = 10.0\nrmax = 3", "dynamics.rmax"),
    ("success = 0.5", "succes = 0.5", "actions.switch.objects.r4.succes"),
])
def test_dynamics_errors_name_the_file_and_key(old, new, where):
    inst = lamps()
    text = LAMPS_DYNAMICS.replace(old, new)
    assert text != LAMPS_DYNAMICS
    with pytest.raises(WorldError) as err:
        parse_dynamics(text, inst.problem.domain, inst.problem.problem, source="lamps.toml")
    assert str(err.value).startswith(f"lamps.toml: {where}: "), str(err.value)


def test_object_overrides_inherit_from_the_schema():
    d = lamps().dynamics
    assert d.outcomes("switch", ("r4",)).success == 0.5
    assert d.outcomes("switch", ("r4",)).stuck == 0.05
    assert d.outcomes("switch", ("r1",)).success == 0.8
    assert d.outcomes("go", ("r1", "r2")).failure == ("go",)


def test_failure_stuck_means_the_rest_is_stuck():
    inst = lamps()
    text = LAMPS_DYNAMICS.replace('failure = ["go"]', 'failure = "stuck"')
    d = parse_dynamics(text, inst.problem.domain, inst.problem.problem)
    assert d.outcomes("go", ("r1", "r2")).stuck == pytest.approx(0.1)


# --- the compiled model ---------------------------------------------------------------

def test_every_pair_has_outcomes_summing_to_one():
    m = lamps().model
    counts = np.diff(m.ptr)
    assert ((counts > 0) == (m.acts.ravel() >= 0)).all()  # every offered pair, no padding
    sums = np.add.reduceat(m.prob, m.ptr[:-1][counts > 0])
    np.testing.assert_allclose(sums, 1.0)


def test_a_slip_is_a_random_applicable_action_of_the_listed_schemas():
    inst = lamps()
    m, g = inst.model, inst.graph
    r2 = next(i for i in range(g.n_states) if "(at r2)" in inst.atoms(i)
              and "(lit r1)" not in inst.atoms(i) and "(lit r2)" not in inst.atoms(i))
    go = next(a for a in range(inst.n_actions) if inst.action_name(a) == "(go r2 r3)")
    i = pair_of(m, r2, go)
    k = slice(m.ptr[i], m.ptr[i + 1])
    out = {next(x for x in inst.atoms(int(t)) if x.startswith("(at")): p
           for t, p in zip(m.next[k], m.prob[k], strict=True)}
    assert out == pytest.approx({"(at r3)": 0.9 + 0.05, "(at r1)": 0.05})


def test_state_cap_is_a_clear_error():
    inst = lamps()
    with pytest.raises(PlanningError, match="more than 5 reachable states"):
        reachable_graph(inst.problem.task, max_states=5)


def test_office_through_the_generic_env_has_the_office_v_star(office_c):
    assert office_c.n_states == 828  # reachable, goal states not expanded
    assert office_c.n_actions == 58
    v = solve(office_c.model, GOAL_POS).V[0, 0]
    assert v == pytest.approx(optimal_value(load_world(), "C"), abs=1e-9)


# --- plan tables --------------------------------------------------------------------

@pytest.mark.parametrize("tolerance", [0.0, 0.3])
def test_plan_table_is_the_graph_planners(office_c, tolerance):
    abstraction = PDDLAbstraction(office_c.graph)
    fast = graph_plan_table(office_c.graph, tolerance)
    states = [0, 1, 57, 200, 433, 827]
    slow = build_plan_table(abstraction, office_c.problem, get_planner("graph"),
                            abstraction.goal(), tolerance, states=states)
    for s in states:
        assert fast.plans_from(s) == slow.plans_from(s), s
        assert fast.length[s] == slow.length[s]
    assert fast.length[0] == 8
    lengths = np.diff(fast.pair_ptr)
    assert lengths.max() <= np.floor(1.3 * fast.length.max()) or tolerance == 0


def test_goal_with_a_negative_literal():
    text = LAMPS_PROBLEM.replace("(:goal (and (lit r2) (lit r4)))",
                                 "(:goal (and (lit r4) (not (dark r4)) (at r3)))")
    domain = LAMPS_DOMAIN.replace(":strips :typing", ":strips :typing :negative-preconditions")
    inst = PDDLInstance.from_texts(domain, text, LAMPS_DYNAMICS)
    assert PDDLAbstraction(inst.graph).goal() is None  # a set of atoms cannot say "not"
    table = graph_plan_table(inst.graph)
    assert table.length[0] == 5  # go go go switch go


# --- the env and the learners -------------------------------------------------------

def test_env_passes_the_checker_and_the_fast_path_matches():
    inst = lamps()
    env = PDDLEnv(instance=inst)
    check_env(env, skip_render_check=True)
    ctx = pddl_task_context(inst)
    out = []
    for fast in (True, False):
        env.reset(seed=3)
        learner = make_learner("gdq", ctx, variant="code")
        out.append(run_episodes(learner, env, 40, np.random.default_rng(4), fast=fast))
    np.testing.assert_array_equal(out[0].returns, out[1].returns)
    np.testing.assert_array_equal(out[0].steps, out[1].steps)


def _mean_return(inst: PDDLInstance, method: str, episodes: int, runs: int, **config) -> float:
    ctx = pddl_task_context(inst)
    env = PDDLEnv(instance=inst)
    totals = []
    for run in range(runs):
        env.reset(seed=run)
        learner = make_learner(method, ctx, **config)
        totals.append(run_episodes(learner, env, episodes, np.random.default_rng(run))
                      .returns.mean())
    return float(np.mean(totals))


@pytest.mark.parametrize("domain,problem", [("delivery", "delivery-1"),
                                            ("delivery", "delivery-2"),
                                            ("keys", "keys-1"), ("keys", "keys-2")])
def test_gdq_code_beats_q_learning_on_the_shipped_domains(domain, problem):
    inst = shipped(domain, problem)
    gdq = _mean_return(inst, "gdq", 200, 3, variant="code")
    q = _mean_return(inst, "qlearning", 200, 3)
    assert gdq > q + 10, (gdq, q)


@pytest.mark.parametrize("domain,problem", [("delivery", "delivery-1"),
                                            ("delivery", "delivery-2"), ("keys", "keys-2")])
def test_the_best_route_is_not_a_shortest_plan(domain, problem):
    """The optimal policy's first actions leave every shortest plan (the planner's H)."""
    inst = shipped(domain, problem)
    sol = solve(inst.model, GOAL_POS)
    shortest = graph_plan_table(inst.graph, 0.0)
    s, on_shortest = 0, True
    for t in range(inst.dynamics.step_limit):
        a = int(sol.policy[t, s])
        on_shortest &= bool(shortest.first_actions[s, a])
        nxt = dict(inst.graph.edges(s)).get(a)
        if nxt is None or inst.graph.is_goal[nxt]:
            break
        s = nxt
    assert not on_shortest


# --- the command line ---------------------------------------------------------------

def test_cli_runs_a_domain_nobody_has_seen(tmp_path):
    for name, text in (("d.pddl", LAMPS_DOMAIN), ("p.pddl", LAMPS_PROBLEM),
                       ("f.toml", LAMPS_DYNAMICS)):
        (tmp_path / name).write_text(text)
    out = tmp_path / "out"
    code = main(["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--dynamics", str(tmp_path / "f.toml"),
                 "--method", "GDQ-code", "Q-learning", "--episodes", "30", "--runs", "2",
                 "--jobs", "1", "--out", str(out)])
    assert code == 0
    report = (out / "REPORT.md").read_text()
    assert "lamps-3" in report and "GDQ-code" in report and "V*" in report
    assert "shortest plan: 5 actions" in report


def test_cli_pddl_errors(tmp_path, capsys):
    (tmp_path / "f.toml").write_text(LAMPS_DYNAMICS.replace("[actions.go]", "[actions.fly]"))
    (tmp_path / "d.pddl").write_text(LAMPS_DOMAIN)
    (tmp_path / "p.pddl").write_text(LAMPS_PROBLEM)
    assert main(["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl")]) == 2
    assert "d.pddl is a STRIPS domain" in capsys.readouterr().err
    assert main(["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
                 str(tmp_path / "p.pddl"), "--dynamics", str(tmp_path / "f.toml")]) == 2
    assert "f.toml: actions.fly: unknown action schema" in capsys.readouterr().err


def test_domains_doc_code_runs(monkeypatch):
    import re

    text = (ROOT / "docs" / "domains.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks
    monkeypatch.chdir(ROOT)
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, "domains.md", "exec"), namespace)
    assert len(namespace["records"]) == 300
