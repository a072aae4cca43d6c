"""Hostile use of the runner and its files (issue 19): results written whole and in their
own folder, names that stay one CSV field and one plain file name, what a stop leaves
and what it says, a damaged numba cache, and layers that keep import cycles out. The
command line's inputs and options: test_hostile_cli.py.

Each test is one case a careless or malicious user tried, with what must hold instead of
what happened.
"""

from __future__ import annotations

import ast
import csv
import io
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gdq_pddl import _jit_cache
from gdq_pddl.errors import ResultsError
from gdq_pddl.experiments import Experiment, run_experiments, task_experiments
from gdq_pddl.experiments import runner as runner_module
from gdq_pddl.experiments.collect import csv_field
from gdq_pddl.experiments.protocol import Unit, safe_name
from tests.cli.hostile import OFFICE
from tests.helpers import cli

PACKAGE = Path(__file__).resolve().parents[2]


# --- results written whole and in their own folder ----------------------------------------

def test_every_area_has_its_column(tmp_path):
    """A world with 8 areas writes area_1 .. area_8 (the columns stopped at 7)."""
    world = tmp_path / "eight.toml"
    world.write_text(OFFICE.replace('7 = ["p13", "p18"]', '7 = ["p13"]\n8 = ["p18"]'),
                     encoding="utf-8")
    exp = Experiment("run", (("C", 3),), ("Q-learning",), runs=1, world=str(world))
    run_experiments([exp], tmp_path / "o", jobs=1)
    with open(tmp_path / "o" / "episodes.csv", newline="") as fh:
        header = next(csv.reader(fh))
    assert header[-8:] == [f"area_{k}" for k in range(1, 9)]


def test_a_fresh_run_never_reuses_saved_runs_it_cannot_check(tmp_path):
    """config.json and episodes.csv deleted, a run with another seed, no --resume: the
    units of seed 0 used to be taken for seed 7 ("0 run(s) to do")."""
    exps = task_experiments(tasks=("C",), episodes=3, runs=1, methods=("Q-learning",))
    run_experiments(exps, tmp_path, jobs=1)
    (tmp_path / "config.json").unlink()
    (tmp_path / "episodes.csv").unlink()
    seven = task_experiments(tasks=("C",), episodes=3, runs=1, methods=("Q-learning",),
                             seed=7)
    with pytest.raises(ResultsError, match="no config.json"):
        run_experiments(seven, tmp_path, jobs=1)


@pytest.mark.parametrize("name", ['a,b"c', "p3->p13", "line\nbreak", "plain"])
def test_a_name_stays_one_csv_field(name):
    """Names reach episodes.csv from world files and the API too: each is one field."""
    row = f"{csv_field(name)},{csv_field('GDQ')}\n"
    assert next(csv.reader(io.StringIO(row))) == [name, "GDQ"]


@pytest.mark.parametrize("name", ["../../x", "a/b", ".hidden", "a" * 300, "p3->p13 x"])
def test_safe_names_are_one_plain_file_name(name):
    safe = safe_name(name)
    assert "/" not in safe and not safe.startswith(".") and len(safe) <= 150
    assert safe != safe_name(name + "y")


def test_plain_unit_keys_are_unchanged():
    """Saved folders of earlier versions resume: their unit file names are the same."""
    exp = Experiment("switch-C-D", (("C", 5), ("p3->p13", 5)), ("GDQ-code",), runs=1)
    assert Unit(exp, "GDQ-code", 0).key == "switch-C-D__C-p3_to_p13__GDQ-code__run0"


# --- what a stop leaves, and what it says -------------------------------------------------

def test_a_stop_before_anything_is_saved_does_not_advise_resume(tmp_path, monkeypatch):
    def interrupted(unit):
        raise KeyboardInterrupt

    monkeypatch.setattr(runner_module, "run_unit", interrupted)
    exps = task_experiments(tasks=("C",), episodes=3, runs=1, methods=("Q-learning",))
    with pytest.raises(ResultsError) as info:
        run_experiments(exps, tmp_path, jobs=1)
    assert "without --resume" in str(info.value) and "and --resume" not in str(info.value)
    assert not (tmp_path / "config.json").exists()  # so the advice works


def test_colliding_unit_files_are_named(tmp_path):
    exps = [Experiment("a", (("C", 3),), ("Q-learning",), runs=1, seed=s) for s in (0, 1)]
    with pytest.raises(ResultsError, match=r"would both be saved as units/a__C__Q-learning"):
        run_experiments(exps, tmp_path, jobs=1)


def test_resume_removes_what_a_killed_csv_write_left(tmp_path):
    exps = task_experiments(tasks=("C",), episodes=3, runs=1, methods=("Q-learning",))
    run_experiments(exps, tmp_path, jobs=1)
    stale = tmp_path / ".episodes.csv.k1ll3d.tmp"
    stale.write_text("half a file")
    run_experiments(exps, tmp_path, jobs=1, resume=True)
    assert not stale.exists()


def test_results_are_readable_as_the_umask_says(tmp_path):
    old = os.umask(0o022)
    try:
        exps = task_experiments(tasks=("C",), episodes=3, runs=1, methods=("Q-learning",))
        run_experiments(exps, tmp_path, jobs=1)
    finally:
        os.umask(old)
    for path in (tmp_path / "episodes.csv", tmp_path / "config.json",
                 next((tmp_path / "units").glob("*.npz"))):
        assert stat.S_IMODE(path.stat().st_mode) == 0o644, path


def _children(pid: int) -> set[int]:
    out = set()
    for task in Path(f"/proc/{pid}/task").glob("*"):
        children = task / "children"
        if children.exists():
            out |= {int(c) for c in children.read_text().split()}
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_stop_signal_ends_the_workers_and_leaves_a_resumable_folder(tmp_path, capsys):
    """SIGTERM during --jobs 2 used to kill the driver alone (exit 143) while its workers
    ran on as orphans and then printed BrokenPipeError tracebacks. (SIGHUP takes the same
    path: interrupts.STOP_SIGNALS.)"""
    signum = signal.SIGTERM
    argv = [sys.executable, "-m", "gdq_pddl.cli", "run", "--task", "C", "--episodes", "20000",
            "--runs", "6", "--method", "Q-learning", "--jobs", "2", "--out", str(tmp_path),
            "--no-report"]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    units = tmp_path / "units"
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and not list(units.glob("*.npz")):
        time.sleep(0.05)
    workers = _children(proc.pid)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signum, err[-2000:]
    assert "--resume" in err and "Traceback" not in err, err[-2000:]
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_alive(w) for w in workers):
        time.sleep(0.1)
    assert not [w for w in workers if _alive(w)], "workers outlived the driver"
    code, out = cli(capsys, *argv[3:], "--resume")  # here: the kernels are loaded already
    assert code == 0, out[-2000:]
    assert len(list(units.glob("*.npz"))) == 6


# --- the numba cache ----------------------------------------------------------------------

def test_a_damaged_numba_cache_file_is_removed_and_a_whole_one_kept(tmp_path):
    """A cache file cut short gave an UnpicklingError on every later run."""
    import pickle

    for folder in _jit_cache.JIT_FOLDERS:
        (tmp_path / folder / "__pycache__").mkdir(parents=True)
    _jit_cache.refresh(tmp_path)  # the sources' digest is recorded: the cache is fresh
    cache = tmp_path / "learners" / "__pycache__"
    whole = cache / "core.act-1.py311.nbi"
    whole.write_bytes(pickle.dumps("0.68") + pickle.dumps(("stamp", {"k": "v"})))
    data = cache / "core.act-1.py311.1.nbc"
    data.write_bytes(pickle.dumps(b"x" * 10_000)[:5000])
    index_only = cache / "core.other-2.py311.nbi"
    index_only.write_bytes(pickle.dumps("0.68"))  # cut right after numba's version
    assert _jit_cache.refresh(tmp_path) is False
    assert whole.exists() and not data.exists() and not index_only.exists()


# --- layers -------------------------------------------------------------------------------

def _imports(path: Path) -> set[str]:
    """Every gdq_pddl module ``path`` imports, at the top or inside a function."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
        elif isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
    return {m for m in out if m.startswith("gdq_pddl")}


@pytest.mark.parametrize("low, high", [
    ("pddl/writer.py", "gdq_pddl.planning"),
    ("experiments/collect.py", "gdq_pddl.experiments.runner"),
    ("experiments/knowledge.py", "gdq_pddl.experiments.work"),
    ("experiments/folder.py", "gdq_pddl.experiments.runner"),
])
def test_no_import_cycle_between_these_layers(low, high):
    imported = _imports(PACKAGE / "gdq_pddl" / low)
    assert not [m for m in imported if m == high or m.startswith(high + ".")], imported
