"""What the analysis tests share (``test_analysis``, ``test_run_report``): a small
synthetic experiment output folder (tasks, task switches and the robot, with fake
episodes whose return rises with each method's quality), the policies written into
it, and the constants it is drawn from."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from gdq_pddl.abstraction import OfficeAbstraction, build_plan_table
from gdq_pddl.envs.model import compile_model, full_state
from gdq_pddl.envs.solve import solve
from gdq_pddl.planning import PlanningProblem, get_planner
from gdq_pddl.resources import domain_text
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import builtin_world, load_world
from gdq_pddl.world_types import World, office_problem

METHODS = ("GDQ", "GDQ-code", "DARLING", "Dyna-Q", "Q-learning")
ROBOT_METHODS = ("GDQ", "GDQ-literal", "GDQ-code", "Dyna-Q")  # robot_experiment's default
QUALITY = {"GDQ": 1.0, "GDQ-code": 0.9, "DARLING": 0.6, "Dyna-Q": 0.4, "Q-learning": 0.2}
V_STAR = {"A": 14.6, "B": 15.7, "C": 11.5, "D": 11.4, "E": 14.6}
RELEVANT = {"A": [2, 4, 6, 7], "B": [4, 7], "C": [1, 2, 3, 6], "D": [1, 3, 4, 7],
            "E": [4, 6, 7]}
PAPER_IRR = {"A": [1, 2, 3], "B": [1, 2, 3, 6], "C": [4, 5, 7], "D": [2, 5], "E": []}
ROUTE = {"A": [4, 7, 6], "B": [4, 7], "C": [1, 3, 2, 6], "D": [1, 3, 4, 7], "E": [6, 7, 4]}
RUNS, EPISODES = 2, 60
SWITCH_AT = EPISODES + 1
HEADER = ["experiment", "method", "task", "run", "episode", "return", "steps", "success",
          *[f"area_{k}" for k in range(1, 8)]]


def optimal_policy(world: World, task: str) -> dict[int, int]:
    """Learner policy from the true optimal policy at step 0 (only the local door open)."""
    model = compile_model(world)
    sol = solve(model, world.index[world.task(task).goal])
    spaces = LearnerSpaces(world)
    out = {}
    for s, (p, is_open) in enumerate(spaces.states):
        door = world.door_at.get(p)
        fs = full_state(world, p, frozenset({door.name}) if door and is_open else frozenset())
        out[s] = int(sol.policy[0, fs])
    return out


def plan_policy(world: World, task: str) -> dict[int, int]:
    """Learner policy: the first action of the first shortest graph plan from each state."""
    ab = OfficeAbstraction(world)
    problem = PlanningProblem.from_texts(domain_text(), office_problem(world, world.task(task)))
    table = build_plan_table(ab, problem, get_planner("graph"), ab.goal(world.task(task).goal))
    return {s: plans[0][0][1] for s in range(ab.n_states) if (plans := table.plans_from(s))}


def _episode(rng: np.random.Generator, q: float, episode: int, task: str, v_star: float,
             r_max: float, route_from: int) -> tuple[float, int, int, list[int]]:
    """One fake episode: return rising with quality ``q``; area visits on the task's route
    (off-route areas visited with a probability that falls with ``q``)."""
    level = -r_max + (v_star + r_max) * q * (1 - np.exp(-episode / 10))
    ret = float(level + rng.normal(0, r_max / 10))
    areas = [0] * 7
    for a in ROUTE[task] if episode >= route_from else RELEVANT[task]:
        areas[a - 1] += int(rng.integers(1, 3))
    for a in range(1, 8):
        if a not in RELEVANT[task] and rng.random() < (1.05 - q) * 0.8:
            areas[a - 1] += int(rng.integers(1, 4))
    success = int(ret > 0)
    return ret, sum(areas), success, areas


def write_output(out: Path, worse_task: str | None = None, switches: bool = True,
                 robot: bool = True, worse_method: str = "GDQ") -> Path:
    """A synthetic output folder; GDQ (and GDQ-code) are best unless ``worse_task`` makes
    ``worse_method`` worst there."""
    rng = np.random.default_rng(7)
    world, robot_world = load_world(), builtin_world("office_robot")
    out.mkdir(parents=True, exist_ok=True)
    rows: list[list] = []

    def quality(method: str, task: str) -> float:
        return 0.05 if method == worse_method and task == worse_task else QUALITY[method]

    def add(exp: str, method: str, task: str, run: int, ep: int, local: int, v: float,
            r_max: float, route_from: int) -> None:
        ret, steps, success, areas = _episode(rng, quality(method, task), local, task, v,
                                              r_max, route_from)
        rows.append([exp, method, task, run, ep, f"{ret:.3f}", steps, success, *areas])

    for method in METHODS:
        route_from = 20 if method.startswith("GDQ") else 10**6
        for task in "ABCD":
            for run in range(RUNS):
                for e in range(1, EPISODES + 1):
                    add("tasks", method, task, run, e, e, V_STAR[task], 20.0, route_from)
        if switches:
            for second in "DE":
                for run in range(RUNS):
                    for e in range(1, 2 * EPISODES + 1):
                        task = "C" if e < SWITCH_AT else second
                        local = e if task == "C" else e - SWITCH_AT + 1
                        add(f"switch-C-{second}", method, task, run, e, local,
                            V_STAR[task], 20.0, route_from)
    if robot:
        for method in ROBOT_METHODS:
            for run in range(RUNS):
                for e in range(1, 31):
                    if method.startswith("GDQ"):
                        ret, success = 900.0 - 600 * np.exp(-e / 5) + rng.normal(0, 20), 1
                        areas = [0, 2, 2, 0, 0, 2, 0] if e > 10 else [0, 1, 2, 0, 0, 2, 1]
                    else:
                        ret, success, areas = -1000.0 - rng.uniform(0, 200), 0, [0, 0, 3, 2,
                                                                                0, 0, 0]
                    rows.append(["robot", method, "X", run, e, f"{ret:.3f}", sum(areas),
                                 success, *areas])
    with (out / "episodes.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(HEADER)
        w.writerows(rows)

    policies: list[list] = []
    good, short = optimal_policy(world, "C"), plan_policy(world, "C")
    for method in METHODS:
        for run in range(RUNS):
            pol = good if method.startswith("GDQ") or (method == "DARLING" and run == 0) \
                else short
            policies += [["tasks", method, "C", run, s, a] for s, a in pol.items()]
    if robot:
        good_x = optimal_policy(robot_world, "X")
        for run in range(RUNS):
            policies += [["robot", "GDQ", "X", run, s, a] for s, a in good_x.items()]
            policies += [["robot", "GDQ-code", "X", run, s, a] for s, a in good_x.items()]
            policies += [["robot", "Dyna-Q", "X", run, s, 0] for s in good_x]
    with (out / "policies.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["experiment", "method", "task", "run", "state", "action"])
        w.writerows(policies)

    optimal = {t: {"v_star": V_STAR[t], "relevant_areas": RELEVANT[t],
                   "irrelevant_areas_paper": PAPER_IRR[t], "optimal_route_areas": ROUTE[t]}
               for t in "ABCDE"}
    # the runner's layout: one entry per experiment (tasks: one per task), versions
    entries = [{"name": "tasks", "schedule": [[t, EPISODES]], "methods": list(METHODS),
                "runs": RUNS, "world": "office", "seed": 1} for t in "ABCD"]
    entries += [{"name": f"switch-C-{t}", "schedule": [["C", EPISODES], [t, EPISODES]],
                 "methods": list(METHODS), "runs": RUNS, "world": "office", "seed": 1}
                for t in "DE" if switches]
    if robot:
        entries.append({"name": "robot", "schedule": [["X", 30]], "methods": list(ROBOT_METHODS),
                        "runs": RUNS, "world": "office_robot", "seed": 1})
        optimal["X@office_robot"] = {"v_star": 900.0, "relevant_areas": [2, 3, 6],
                                     "irrelevant_areas_paper": []}
    config = {"experiments": entries, "versions": {"gdq_pddl": "test"},
              "unknown_key": {"ignored": True}}
    (out / "optimal.json").write_text(json.dumps(optimal))
    (out / "config.json").write_text(json.dumps(config))
    return out
