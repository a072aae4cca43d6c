"""A planner from another distribution is found through the entry points, CLI included.

The example plugin (examples/planner_plugin) is installed with ``pip --target`` into a
temporary directory, never into site-packages, and used from subprocesses that have that
directory on PYTHONPATH.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
from concurrent.futures import Future
from importlib.metadata import entry_points
from pathlib import Path

import pytest

import gdq_pddl
from tests.helpers import BACKGROUND, REPO_ROOT, cli

TEMPLATE = REPO_ROOT / "examples" / "planner_plugin"
# A distribution whose planner cannot be imported: the listing must survive it.
BROKEN_DIST = "gdq_broken_planner-0.1.dist-info"


PLUGIN_DIRS: list[Path] = []


def _dirs() -> tuple[Path, Path, Path]:
    """The plugin's source copy, the ``pip --target`` directory and a directory holding the
    broken distribution (one temporary folder for the session)."""
    if not PLUGIN_DIRS:
        PLUGIN_DIRS.append(Path(tempfile.mkdtemp(prefix="gdq-plugin-")))
    tmp = PLUGIN_DIRS[0]
    return tmp / "src", tmp / "site", tmp / "broken"


def _env() -> dict[str, str]:
    """PYTHONPATH: the plugin, the broken distribution and the gdq_pddl under test."""
    _, site, broken = _dirs()
    paths = [str(site), str(broken)]
    package_root = Path(gdq_pddl.__file__).resolve().parents[1]
    if (package_root / "gdq_pddl" / "data" / "domains").is_dir():
        paths.append(str(package_root))  # the gdq_pddl under test, if it has its data
    return dict(os.environ, PYTHONPATH=os.pathsep.join(paths))


def start_install(item=None) -> Future | None:
    """``pip install --target`` of the example plugin, queued when collection ends (before
    the commands below, which the Background queue runs after it, one at a time)."""
    if not TEMPLATE.is_dir():
        return None
    source, site, broken = _dirs()
    if not source.exists():
        shutil.copytree(TEMPLATE, source)  # builds leave nothing in the repo
        dist = broken / BROKEN_DIST
        dist.mkdir(parents=True)
        (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: gdq-broken-planner\n"
                                       "Version: 0.1\n")
        (dist / "entry_points.txt").write_text(
            "[gdq_pddl.planners]\nbroken = gdq_no_such_module:Planner\n")
    return BACKGROUND.run("plugin install", [
        sys.executable, "-m", "pip", "install", "--no-deps", "--no-build-isolation",
        "--no-index", "--quiet", "--target", str(site), str(source)], timeout=300)


def _start(key: str, *args: str):
    """A start function for the Background queue: Python with the plugin on its path, from
    a neutral directory (queued after the install, whichever tests are selected)."""
    def start(item=None) -> Future:
        start_install()
        return BACKGROUND.run(f"plugin {key}", [sys.executable, *args], env=_env(),
                              cwd=_dirs()[0].parent, timeout=120)
    return start


@pytest.fixture(scope="module")
def site() -> Path:
    """The directory holding the installed example plugin."""
    install = start_install()
    if install is None:
        pytest.skip("examples/planner_plugin is not in this checkout")
    proc = install.result()
    if proc.returncode != 0:  # a required test: never skip it silently
        pytest.fail("cannot build the example plugin (is the test extra installed? "
                    f"pip install '.[test]'): {proc.stderr.strip()[-500:]}")
    yield _dirs()[1]
    shutil.rmtree(PLUGIN_DIRS[0], ignore_errors=True)


@pytest.mark.background.with_args(start_install)
def test_the_plugin_is_not_installed_in_this_process(site):
    assert "toy" not in {ep.name for ep in entry_points(group="gdq_pddl.planners")}
    assert (site / "gdq_toy_planner" / "__init__.py").is_file()


API_CODE = """if True:
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
start_api = _start("api", "-c", API_CODE)


@pytest.mark.background.with_args(start_api)
def test_python_api_finds_and_runs_the_plugin(site):
    proc = start_api().result()
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["planners"]["toy"] == [True, ""]
    usable, reason = out["planners"]["broken"]
    assert not usable and "cannot be loaded" in reason and "gdq_no_such_module" in reason
    assert out["planner"] == "toy" and out["length"] == 8 and out["in_graph"]


start_list = _start("list", "-m", "gdq_pddl.cli", "planners", "--json")


@pytest.mark.background.with_args(start_list)
def test_cli_lists_the_plugin(site):
    proc = start_list().result()
    assert proc.returncode == 0, proc.stderr
    listed = {p["name"]: p for p in json.loads(proc.stdout)}
    assert {"graph", "pyperplan", "clingo", "toy", "broken"} <= listed.keys()
    assert listed["toy"]["usable"] is True and listed["toy"]["reason"] == ""
    assert listed["broken"]["usable"] is False


start_plan = _start("plan", "-m", "gdq_pddl.cli", "plan", "--start", "p0", "--goal", "p17",
                    "--planner", "toy", "--json")


@pytest.mark.background.with_args(start_plan)
def test_cli_plans_with_the_plugin(site, capsys):
    proc = start_plan().result()
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


start_broken = _start("broken", "-m", "gdq_pddl.cli", "plan", "--task", "C", "--planner",
                      "broken")


@pytest.mark.background.with_args(start_broken)
def test_cli_names_the_plugin_when_it_cannot_load(site):
    proc = start_broken().result()
    assert proc.returncode != 0
    assert "broken" in proc.stderr and "Traceback" not in proc.stderr
