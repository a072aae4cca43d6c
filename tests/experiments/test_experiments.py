"""The experiment runner: results as data, identical for any jobs, resumable after a kill."""

from __future__ import annotations

import csv
import importlib.util
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest

from gdq_pddl.cli import main
from gdq_pddl.experiments import (
    Experiment,
    ResultsError,
    run_experiments,
    switch_experiment,
    task_experiments,
)
from tests.helpers import BACKGROUND

SMALL = dict(episodes=20, runs=2, methods=("GDQ", "Q-learning"))
COLUMNS = ["experiment", "method", "task", "run", "episode", "return", "steps", "success",
           *(f"area_{k}" for k in range(1, 8))]


def read_rows(out: Path) -> list[dict[str, str]]:
    with open(out / "episodes.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def test_episodes_csv_has_the_documented_columns_and_one_row_per_episode(tmp_path):
    exps = task_experiments(tasks=("A", "C"), **SMALL)
    exps.append(switch_experiment("C", "D", 10, runs=1, methods=("GDQ",)))
    run_experiments(exps, tmp_path, jobs=1)
    with open(tmp_path / "episodes.csv", newline="") as fh:
        assert next(csv.reader(fh)) == COLUMNS
    rows = read_rows(tmp_path)
    assert len(rows) == 2 * 2 * 2 * 20 + 20
    switch = [r for r in rows if r["experiment"] == "switch-C-D"]
    assert [r["task"] for r in switch] == ["C"] * 10 + ["D"] * 10
    assert [int(r["episode"]) for r in switch] == list(range(1, 21))
    for r in rows:
        steps = int(r["steps"])
        assert 1 <= steps <= 20
        assert sum(int(r[f"area_{k}"]) for k in range(1, 8)) <= steps
        assert r["success"] in ("0", "1")
    config = json.loads((tmp_path / "config.json").read_text())
    assert {"numpy", "numba", "gdq_pddl"} <= config["versions"].keys()
    assert len(config["experiments"]) == 3
    optimal = json.loads((tmp_path / "optimal.json").read_text())
    assert optimal["C"]["v_star"] == pytest.approx(11.51, abs=0.01)
    with open(tmp_path / "policies.csv", newline="") as fh:
        policies = list(csv.DictReader(fh))
    assert len(policies) == (2 * 2 * 2 + 1) * 31


@pytest.fixture(scope="module")
def two_jobs(tmp_path_factory) -> Path:
    """SMALL on task C with two local processes: what the other executors must equal."""
    out = tmp_path_factory.mktemp("jobs") / "two"
    return run_experiments(task_experiments(tasks=("C",), **SMALL), out, jobs=2)


def test_any_number_of_jobs_gives_identical_results(tmp_path, two_jobs):
    exps = task_experiments(tasks=("C",), **SMALL)
    run_experiments(exps, tmp_path / "one", jobs=1)
    assert (tmp_path / "one" / "episodes.csv").read_bytes() == \
        (two_jobs / "episodes.csv").read_bytes()


def test_existing_results_need_resume_and_the_same_configuration(tmp_path):
    exps = task_experiments(tasks=("C",), episodes=5, runs=1, methods=("Q-learning",))
    run_experiments(exps, tmp_path, jobs=1)
    with pytest.raises(ResultsError, match="--resume"):
        run_experiments(exps, tmp_path, jobs=1)
    other = task_experiments(tasks=("C",), episodes=6, runs=1, methods=("Q-learning",))
    with pytest.raises(ResultsError, match="different configuration"):
        run_experiments(other, tmp_path, jobs=1, resume=True)
    run_experiments(exps, tmp_path, jobs=1, resume=True)  # nothing left to do: fine


def test_a_killed_run_resumes_without_losing_or_duplicating(tmp_path):
    """Kill the CLI mid-way (SIGKILL: no chance to clean up), then --resume."""
    out = tmp_path / "killed"
    argv = [sys.executable, "-m", "gdq_pddl.cli", "run", "--task", "C", "--method", "GDQ",
            "Q-learning", "Dyna-Q", "--episodes", "400", "--runs", "4", "--jobs", "1",
            "--out", str(out), "--no-report"]
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    units = out / "units"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(units.glob("*.npz"))) < 2:
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    done = len(list(units.glob("*.npz")))
    assert 2 <= done < 12, "the run should have been killed mid-way"
    # the resume and a fresh run of the same command, in this process: its kernels are loaded
    assert main([*argv[3:], "--resume"]) == 0
    assert not list(units.glob(".*.tmp")), "no half-written files may remain"
    fresh = tmp_path / "fresh"
    assert main([*argv[3:-3], "--out", str(fresh), "--no-report"]) == 0
    assert (out / "episodes.csv").read_bytes() == (fresh / "episodes.csv").read_bytes()
    keys = [(r["method"], r["run"], r["episode"]) for r in read_rows(out)]
    assert len(keys) == len(set(keys)) == 3 * 4 * 400


def test_policies_csv_is_left_out_past_its_row_limit(tmp_path, monkeypatch):
    """A PDDL problem of millions of states would make gigabytes of policies.csv: past
    MAX_POLICY_ROWS it is not written (said), the report still is, the policies stay in
    the unit files."""
    from gdq_pddl.experiments import collect

    argv = ["run", "--domain", "keys-ppddl", "--problem", "keys-ppddl-1", "--episodes", "5",
            "--runs", "2", "--method", "GDQ", "--jobs", "1"]
    assert main([*argv, "--out", str(tmp_path / "all")]) == 0
    rows = (tmp_path / "all" / "policies.csv").read_text().count("\n") - 1
    monkeypatch.setattr(collect, "MAX_POLICY_ROWS", rows - 1)
    with pytest.warns(UserWarning, match=f"policies.csv left out: .* {rows:,} rows"):
        assert main([*argv, "--out", str(tmp_path / "capped")]) == 0
    assert not (tmp_path / "capped" / "policies.csv").exists()
    assert (tmp_path / "capped" / "REPORT.md").exists()
    units = sorted((tmp_path / "capped" / "units").glob("*.npz"))
    assert len(units) == 2 and all("policy" in np.load(u) for u in units)


def test_workers_are_capped_by_the_memory_their_tables_need():
    from gdq_pddl.experiments.executors import memory_jobs

    gb = 10**9
    assert memory_jobs(2, per_run=gb, have=16 * gb, in_use=gb) == 2
    assert memory_jobs(8, per_run=5 * gb, have=16 * gb, in_use=gb) == 2  # 12 GB share - 1
    assert memory_jobs(4, per_run=20 * gb, have=16 * gb, in_use=gb) == 1  # one always runs
    assert memory_jobs(4, per_run=0, have=16 * gb, in_use=20 * gb) == 1


def test_too_many_jobs_for_memory_run_fewer_with_the_same_results(tmp_path, two_jobs,
                                                                 monkeypatch):
    # a machine where the parent fits but not a second worker's tables: one process,
    # said, and the results of any number of jobs
    import gdq_pddl.experiments.executors as executors

    monkeypatch.setattr(executors, "physical_memory", lambda: 1)
    with pytest.warns(UserWarning, match=r"2 worker processes \(--jobs\) capped at 1"):
        run_experiments(task_experiments(tasks=("C",), **SMALL), tmp_path / "capped", jobs=2)
    assert (tmp_path / "capped" / "episodes.csv").read_bytes() == \
        (two_jobs / "episodes.csv").read_bytes()


def test_interrupt_message_says_how_to_resume(tmp_path):
    """Ctrl-C while the workers run: one clear line, no traceback, runs already saved."""
    argv = [sys.executable, "-m", "gdq_pddl.cli", "run", "--task", "C", "--episodes", "10000",
            "--runs", "8", "--method", "GDQ", "Dyna-Q", "--jobs", "2", "--out", str(tmp_path),
            "--no-report"]
    # as from a terminal: a shell starts background jobs with SIGINT ignored, and a
    # child of such a test run would inherit that
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    units = tmp_path / "units"
    deadline = time.monotonic() + 300  # the first unit waits for the kernels to compile
    while time.monotonic() < deadline and not list(units.glob("*.npz")):
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    saved = len(list(units.glob("*.npz")))
    assert 1 <= saved < 16, "the interrupt should come while the runs are under way"
    assert proc.returncode == 130
    assert "--resume" in err and "Traceback" not in err, err[-2000:]


def test_resume_removes_files_a_killed_write_left(tmp_path):
    """A kill between writing a unit and renaming it leaves a temporary file behind."""
    exps = task_experiments(tasks=("C",), episodes=5, runs=2, methods=("Q-learning",))
    run_experiments(exps, tmp_path, jobs=1)
    (tmp_path / "units" / next((tmp_path / "units").glob("*.npz")).name).unlink()
    stale = tmp_path / "units" / ".tasks__C__Q-learning__run0.npz.k1ll3d.tmp"
    stale.write_bytes(b"half a file")
    run_experiments(exps, tmp_path, jobs=1, resume=True)
    assert not stale.exists()
    assert len(list((tmp_path / "units").glob("*.npz"))) == 2


def test_unit_seeds_depend_only_on_identity_and_pair_the_methods():
    exp = Experiment("tasks", (("C", 5),), ("GDQ", "Q-learning"), runs=2)
    a = [(u.method, u.run, u.seeds()[0].random(), u.seeds()[1]) for u in exp.units()]
    b = [(u.method, u.run, u.seeds()[0].random(), u.seeds()[1]) for u in exp.units()]
    assert a == b
    by_run = {}
    for _method, run, learner, env in a:
        by_run.setdefault(run, set()).add((learner, env))
    assert all(len(seeds) == 1 for seeds in by_run.values())  # paired across methods
    assert len({next(iter(seeds)) for seeds in by_run.values()}) == 2  # runs differ
    other = Experiment("tasks", (("D", 5),), ("GDQ",), runs=1).units()[0].seeds()[1]
    assert other != a[0][3]  # and so do experiments


# The test owns its Ray cluster: a head started with --block in its own process group,
# inside a loopback-only network namespace, with a private --temp-dir (sessions and
# sockets live there, and a namespace does not separate them; the path must stay
# short: Ray puts unix sockets in it). It is stopped by SIGTERM to the head alone, which
# then stops the processes it started (about 2 s; a SIGTERM to the whole group makes them
# race their own shutdown and took 35 s), then SIGKILL to the group for anything left;
# never with `ray stop`, which kills every Ray process on the machine. The cost is fixed
# (start the head, start a worker that loads the compiled kernels), so the head has one
# CPU: one worker runs the 4 units one after another (a second worker would only load the
# kernels again); that results do not depend on the order units finish in is proven by
# the two local processes the Ray results are compared with.
RAY_SCRIPT = """
import os, shutil, signal, socket, subprocess, sys, tempfile, time
from pathlib import Path
from gdq_pddl.experiments import run_experiments, task_experiments
exps = task_experiments(tasks=("C",), episodes=20, runs=2, methods=("GDQ", "Q-learning"))
subprocess.run(["ip", "link", "set", "lo", "up"], check=True)
temp = tempfile.mkdtemp(prefix="gdqray", dir="/tmp")
head = subprocess.Popen(["ray", "start", "--head", "--block", "--port=6399", "--num-cpus=1",
                         "--include-dashboard=false", "--disable-usage-stats",
                         f"--temp-dir={temp}"], stdout=subprocess.DEVNULL,
                        stderr=subprocess.PIPE, text=True, start_new_session=True)
try:
    deadline = time.monotonic() + 120
    while True:
        if head.poll() is not None:
            sys.exit("ray start failed: " + head.stderr.read()[-3000:])
        try:
            socket.create_connection(("127.0.0.1", 6399), timeout=1).close()
            break
        except OSError:
            if time.monotonic() > deadline:
                sys.exit("the Ray head did not come up within 120 s")
            time.sleep(0.5)
    run_experiments(exps, Path(sys.argv[1]), executor="ray", address="127.0.0.1:6399")
finally:
    head.send_signal(signal.SIGTERM)
    try:
        head.wait(timeout=60)
    except subprocess.TimeoutExpired:
        pass
    try:
        os.killpg(head.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    shutil.rmtree(temp, ignore_errors=True)
"""


def _can_unshare_network() -> bool:
    try:
        return subprocess.run(["unshare", "-n", "true"], capture_output=True).returncode == 0
    except OSError:
        return False


RAY_OUT: list[Path] = []


def start_ray(item=None):
    """The Ray run, queued when collection ends to run beside the other tests
    (``tests.helpers.Background``); None where the test is skipped."""
    if importlib.util.find_spec("ray") is None or not _can_unshare_network():
        return None
    if not RAY_OUT:
        RAY_OUT.append(Path(tempfile.mkdtemp(prefix="gdq-ray-test-")) / "ray")
    env = dict(os.environ, RAY_AUTH_MODE="disabled", RAY_USAGE_STATS_ENABLED="0")
    return BACKGROUND.run("ray", ["unshare", "-n", sys.executable, "-c", RAY_SCRIPT,
                                  str(RAY_OUT[0])], env=env, timeout=600)


@pytest.mark.skipif(not _can_unshare_network(), reason="needs a private network namespace")
@pytest.mark.background.with_args(start_ray)
def test_ray_executor_matches_local_processes(two_jobs):
    """A local Ray cluster, started by the test inside a loopback-only network namespace."""
    pytest.importorskip("ray")
    try:
        result = start_ray().result()
        assert result.returncode == 0, result.stderr[-3000:]
        assert (RAY_OUT[0] / "episodes.csv").read_bytes() == \
            (two_jobs / "episodes.csv").read_bytes()
    finally:
        shutil.rmtree(RAY_OUT[0].parent, ignore_errors=True)


def test_unreachable_ray_address_is_a_clear_error(tmp_path):
    pytest.importorskip("ray")
    exps = task_experiments(tasks=("C",), episodes=2, runs=1, methods=("GDQ",))
    with pytest.raises(ResultsError, match="cannot reach a Ray cluster at 127.0.0.1:1"):
        run_experiments(exps, tmp_path, executor="ray", address="127.0.0.1:1")


def test_results_are_arrays_of_the_right_shape(tmp_path):
    exps = task_experiments(tasks=("B",), episodes=7, runs=1, methods=("DARLING",))
    run_experiments(exps, tmp_path, jobs=1)
    data = np.load(next((tmp_path / "units").glob("*.npz")))
    assert data["returns"].shape == (7,) and data["areas"].shape == (7, 7)
    assert data["policy"].shape == (31,)


def test_a_problem_is_a_problem_spec_not_a_positional_tuple():
    """``pddl`` was ``(domain, problem, dynamics[, determinisation[, "online"]])``: now a
    ProblemSpec, checked; config.json's old lists read as the same spec."""
    from gdq_pddl.errors import ConfigError
    from gdq_pddl.experiments import Experiment, ProblemSpec

    with pytest.raises(ConfigError, match=r"pddl must be a ProblemSpec\(domain=.*got tuple"):
        Experiment("x", (("keys-1", 3),), world="pddl", pddl=("d.pddl", "p.pddl", ""))
    with pytest.raises(ConfigError, match=r"ProblemSpec.exploration: expected one of "
                                          r"enumerate, online, got 'lazy'"):
        ProblemSpec("d.pddl", "p.pddl", exploration="lazy")
    spec = ProblemSpec("d.pddl", "p.pddl", "", "most-likely", "online")
    assert spec.online and spec.files == ("d.pddl", "p.pddl", "")
    assert ProblemSpec.from_record(["d.pddl", "p.pddl", "", "most-likely", "online"]) == spec
    assert ProblemSpec.from_record(["d.pddl", "p.pddl", "k.toml"]) == \
        ProblemSpec("d.pddl", "p.pddl", "k.toml", "all-outcomes", "enumerate")
    assert ProblemSpec.from_record({"domain": "d.pddl", "problem": "p.pddl", "dynamics": "",
                                    "determinisation": "most-likely",
                                    "exploration": "online"}) == spec
    with pytest.raises(ConfigError, match="a recorded problem"):
        ProblemSpec.from_record(["d.pddl", "p.pddl", "", "all-outcomes", "lazy"])
