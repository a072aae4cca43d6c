"""A planner from another distribution is found through the entry points, CLI included.

The example plugin (examples/planner_plugin) is installed with ``pip --target`` into a
temporary directory, never into site-packages, and used from subprocesses that have that
directory on PYTHONPATH.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from importlib.metadata import entry_points
from pathlib import Path

import pytest

import gdq_pddl
from tests.helpers import REPO_ROOT, cli

TEMPLATE = REPO_ROOT / "examples" / "planner_plugin"
# A distribution whose planner cannot be imported: the listing must survive it.
BROKEN_DIST = "gdq_broken_planner-0.1.dist-info"


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """A directory holding the installed example plugin and a broken one."""
    if not TEMPLATE.is_dir():
        pytest.skip("examples/planner_plugin is not in this checkout")
    tmp = tmp_path_factory.mktemp("plugin")
    source = shutil.copytree(TEMPLATE, tmp / "src")  # builds leave nothing in the repo
    target = tmp / "site"
    proc = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps",
                           "--no-build-isolation", "--no-index", "--quiet", "--target",
                           str(target), str(source)], capture_output=True, text=True,
                          timeout=300)
    if proc.returncode != 0:  # a required test: never skip it silently
        pytest.fail("cannot build the example plugin (is the test extra installed? "
                    f"pip install '.[test]'): {proc.stderr.strip()[-500:]}")
    broken = target / BROKEN_DIST
    broken.mkdir()
    (broken / "METADATA").write_text("Metadata-Version: 2.1\nName: gdq-broken-planner\n"
                                     "Version: 0.1\n")
    (broken / "entry_points.txt").write_text(
        "[gdq_pddl.planners]\nbroken = gdq_no_such_module:Planner\n")
    return target


def _run(site: Path, *args: str) -> subprocess.CompletedProcess:
    """Run Python with the plugin directory on its path, from a neutral directory."""
    paths = [str(site)]
    package_root = Path(gdq_pddl.__file__).resolve().parents[1]
    if (package_root / "gdq_pddl" / "data" / "domains").is_dir():
        paths.append(str(package_root))  # the gdq_pddl under test, if it has its data
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(paths))
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env,
                          cwd=site.parent, timeout=120)


def _cli(site: Path, *args: str) -> subprocess.CompletedProcess:
    return _run(site, "-m", "gdq_pddl.cli", *args)


def test_the_plugin_is_not_installed_in_this_process(site):
    assert "toy" not in {ep.name for ep in entry_points(group="gdq_pddl.planners")}
    assert (site / "gdq_toy_planner" / "__init__.py").is_file()


def test_python_api_finds_and_runs_the_plugin(site):
    code = """if True:
        import json
        from gdq_pddl.planning import get_planner, planners
        from gdq_pddl.planning.graph import GraphPlanner
        from gdq_pddl.planning.validate import validate_plan
        from gdq_pddl.world import office_problem
        from gdq_pddl.planning import PlanningProblem
        from gdq_pddl.resources import domain_text
        from gdq_pddl.world import load_world

        world = load_world()
        problem = PlanningProblem.from_texts(domain_text(),
                                             office_problem(world, world.task("C")))
        result = get_planner("toy").solve(problem)
        for plan in result.plans:
            validate_plan(problem, plan)
        graph = {p.actions for p in GraphPlanner().solve(problem).plans}
        print(json.dumps({
            "planners": {i.name: [i.usable, i.reason] for i in planners()},
            "planner": result.planner, "length": result.length,
            "in_graph": all(p.actions in graph for p in result.plans)}))
    """
    proc = _run(site, "-c", code)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["planners"]["toy"] == [True, ""]
    usable, reason = out["planners"]["broken"]
    assert not usable and "cannot be loaded" in reason and "gdq_no_such_module" in reason
    assert out["planner"] == "toy" and out["length"] == 8 and out["in_graph"]


def test_cli_lists_the_plugin(site):
    proc = _cli(site, "planners", "--json")
    assert proc.returncode == 0, proc.stderr
    listed = {p["name"]: p for p in json.loads(proc.stdout)}
    assert {"graph", "pyperplan", "clingo", "toy", "broken"} <= listed.keys()
    assert listed["toy"]["usable"] is True and listed["toy"]["reason"] == ""
    assert listed["broken"]["usable"] is False


def test_cli_plans_with_the_plugin(site, capsys):
    proc = _cli(site, "plan", "--start", "p0", "--goal", "p17", "--planner", "toy", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["length"] == 8
    assert len(out["plans"]) == 1
    plan = out["plans"][0]
    assert len(plan["actions"]) == 8 and plan["actions"][-1].endswith("p17)")
    assert len(plan["learner"]) == 8
    assert all({"state", "action"} <= step.keys() for step in plan["learner"])
    code, graph = cli(capsys, "plan", "--start", "p0", "--goal", "p17", "--json")  # no plugin
    assert code == 0 and plan["actions"] in [p["actions"] for p in json.loads(graph)["plans"]]


def test_cli_names_the_plugin_when_it_cannot_load(site):
    proc = _cli(site, "plan", "--task", "C", "--planner", "broken")
    assert proc.returncode != 0
    assert "broken" in proc.stderr and "Traceback" not in proc.stderr
