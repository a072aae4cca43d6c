"""Hostile use of the command line, the runner and the input and output files (issue 19).

Each test is one case a careless or malicious user tried, with what must hold instead of
what happened: a clear one-line refusal (exit 2), or the right result.
"""

from __future__ import annotations

import ast
import csv
import io
import json
import os
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from gdq_pddl import _jit_cache
from gdq_pddl.errors import ResultsError
from gdq_pddl.experiments import Experiment, run_experiments, task_experiments
from gdq_pddl.experiments import runner as runner_module
from gdq_pddl.experiments.collect import csv_field
from gdq_pddl.experiments.protocol import Unit, safe_name
from gdq_pddl.resources import data_file, world_text
from tests.helpers import cli

OFFICE = world_text("office")
KEYS_DOMAIN = data_file("domains", "keys.pddl").read_text(encoding="utf-8")
KEYS_PROBLEM = data_file("problems", "keys-1.pddl").read_text(encoding="utf-8")
KEYS_DYNAMICS = data_file("dynamics", "keys.toml").read_text(encoding="utf-8")
FAST = ["--episodes", "3", "--runs", "1", "--method", "Q-learning", "--jobs", "1",
        "--no-report"]
PACKAGE = Path(__file__).resolve().parents[2]


def refused(code, text: str, *names: str) -> None:
    assert code == 2, text
    assert "Traceback" not in text, text
    for name in names:
        assert name in text, f"{name!r} not named in: {text}"


def keys_files(tmp_path: Path, problem: str = KEYS_PROBLEM, domain: str = KEYS_DOMAIN
               ) -> tuple[Path, Path, Path]:
    paths = tmp_path / "keys.pddl", tmp_path / "keys-1.pddl", tmp_path / "keys.toml"
    for path, text in zip(paths, (domain, problem, KEYS_DYNAMICS), strict=True):
        path.write_text(text, encoding="utf-8")
    return paths


def keys_run(capsys, files, *extra) -> tuple[int, str]:
    d, p, y = files
    return cli(capsys, "run", "--domain", d, "--problem", p, "--dynamics", y, *FAST, *extra)


# --- a name means one thing in every process ----------------------------------------------

def test_a_world_file_named_office_is_that_file_everywhere(capsys, tmp_path, monkeypatch):
    """``--world office`` with a file ``./office``: the file, recorded with its hash (the
    workers used to run the built-in office while the command line checked the file)."""
    monkeypatch.chdir(tmp_path)
    Path("office").write_text(OFFICE.replace("step_limit = 20 ", "step_limit = 19 "),
                              encoding="utf-8")
    code, text = cli(capsys, "run", "--world", "office", "--task", "C", *FAST, "--out", "o")
    assert code == 0, text
    config = json.loads(Path("o/config.json").read_text())
    world = config["experiments"][0]["world"]
    assert Path(world) == tmp_path / "office"
    assert config["inputs"][world].startswith("sha256:")


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


def test_a_problem_name_never_becomes_a_path(capsys, tmp_path, monkeypatch):
    """``(problem ../../../../x)`` used to write outside --out (and outside results/): the
    reader now refuses a name that is not a PDDL name, at its line, and nothing is
    written anywhere."""
    work = tmp_path / "a" / "b" / "c" / "d"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    files = keys_files(work, KEYS_PROBLEM.replace("(problem keys-1)", "(problem ../../../../x)"))
    for extra in (("--out", "o"), ()):  # the default --out was built from the name
        code, text = keys_run(capsys, files, *extra)
        assert code == 2 and "keys-1.pddl:2: expected a problem name" in text, text
    written = [p for p in tmp_path.rglob("*") if p.is_file() and p.suffix != ".pddl"
               and p.suffix != ".toml"]
    assert not written, written


def test_a_comma_in_a_problem_name_is_refused_at_its_line(capsys, tmp_path):
    """A comma in a problem name used to break episodes.csv's columns: it is not a PDDL
    name character, so the reader refuses it where it stands."""
    files = keys_files(tmp_path, KEYS_PROBLEM.replace("(problem keys-1)", '(problem a,b"c)'))
    code, text = keys_run(capsys, files, "--out", tmp_path / "o")
    assert code == 2 and "keys-1.pddl:2:" in text and "','" in text, text
    assert not (tmp_path / "o" / "episodes.csv").exists()


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


# --- input files are checked before they are read -----------------------------------------

@pytest.mark.parametrize("option", ["--domain", "--problem", "--dynamics"])
def test_a_device_as_input_is_refused_at_once(capsys, tmp_path, option):
    files = dict(zip(("--domain", "--problem", "--dynamics"), keys_files(tmp_path),
                     strict=True))
    files[option] = Path("/dev/zero")
    t0 = time.perf_counter()
    code, text = cli(capsys, "run", *(x for kv in files.items() for x in kv), *FAST,
                     "--out", tmp_path / "o")
    refused(code, text, "/dev/zero", "not a regular file")
    assert time.perf_counter() - t0 < 30


def test_a_world_that_is_a_device_is_refused(capsys):
    refused(*cli(capsys, "plan", "--world", "/dev/zero", "--task", "C"), "/dev/zero")


def test_a_fifo_as_input_does_not_hang(capsys, tmp_path):
    fifo = tmp_path / "world.toml"
    os.mkfifo(fifo)
    done = threading.Event()
    result: list = []

    def call() -> None:
        result.append(cli(capsys, "plan", "--world", fifo, "--task", "C"))
        done.set()

    threading.Thread(target=call, daemon=True).start()
    if not done.wait(30):  # unblock the reader so the thread can end, then fail
        with open(fifo, "w") as fh:
            fh.write("")
        pytest.fail("reading a FIFO hung")
    refused(*result[0], str(fifo), "FIFO")


def test_an_input_past_the_size_cap_is_refused_before_it_is_read(capsys, tmp_path):
    files = keys_files(tmp_path)
    with open(files[1], "r+b") as fh:
        fh.truncate(200 * 1000**2)  # sparse: 200 MB that take no disk
    t0 = time.perf_counter()
    code, text = keys_run(capsys, files, "--out", tmp_path / "o")
    refused(code, text, str(files[1]), "200 MB")
    assert time.perf_counter() - t0 < 30


def test_a_byte_order_mark_is_accepted_in_every_input(capsys, tmp_path):
    d, p, y = keys_files(tmp_path)
    for path in (d, p, y):
        path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    code, text = keys_run(capsys, (d, p, y), "--out", tmp_path / "o")
    assert code == 0, text
    world = tmp_path / "w.toml"
    world.write_bytes(b"\xef\xbb\xbf" + OFFICE.encode())
    code, text = cli(capsys, "plan", "--world", world, "--task", "C")
    assert code == 0, text


def test_a_world_too_large_to_plan_over_is_refused_naming_it(capsys, monkeypatch):
    from gdq_pddl.cli import common

    monkeypatch.setattr(common, "MAX_WORLD_POSITIONS", 10)
    refused(*cli(capsys, "plan", "--task", "C"), "office.toml", "19 positions")


def test_a_problem_too_large_to_plan_over_is_refused_naming_it(capsys, tmp_path, monkeypatch):
    from gdq_pddl.planning import base

    monkeypatch.setattr(base, "MAX_INIT_ATOMS", 5)
    d, p, _ = keys_files(tmp_path)
    refused(*cli(capsys, "plan", "--domain", d, "--problem", p), str(p), "initial state")


# --- options that would be ignored are refused --------------------------------------------

@pytest.mark.parametrize("argv, names", [
    (["run", "--task", "C", "--address", "1.2.3.4:6379", *FAST], ["--address", "ray"]),
    (["run", "--task", "C", "--determinisation", "most-likely", *FAST],
     ["--determinisation", "office"]),
    (["plan", "--task", "C", "--determinisation", "most-likely"], ["--determinisation"]),
    (["plan", "--planner", "pyperplan", "--tolerance", "0.5", "--task", "C"],
     ["--tolerance", "pyperplan"]),
])
def test_an_option_that_would_be_ignored_is_refused(capsys, tmp_path, argv, names):
    refused(*cli(capsys, *argv, *(["--out", tmp_path / "o"] if argv[0] == "run" else [])),
            *names)
    assert not (tmp_path / "o" / "config.json").exists()


def test_plan_refuses_a_task_with_a_problem(capsys, tmp_path):
    d, p, _ = keys_files(tmp_path)
    for option in (["--task", "C"], ["--start", "p0"], ["--world", tmp_path / "w.toml"]):
        refused(*cli(capsys, "plan", "--domain", d, "--problem", p, *option), option[0],
                "--problem")


def test_a_one_plan_planner_for_plan_learners_is_said(capsys, tmp_path):
    code, text = cli(capsys, "run", "--task", "C", "--planner", "pyperplan", "--episodes",
                     "3", "--runs", "1", "--method", "DARLING", "--jobs", "1", "--no-report",
                     "--out", tmp_path / "o")
    assert code == 0, text
    assert "warning" in text and "one plan" in text and "DARLING" in text


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


def test_a_finished_folder_has_no_lock_and_resume_has_nothing_to_do(capsys, tmp_path):
    argv = ["run", "--task", "C", *FAST, "--out", tmp_path]
    assert cli(capsys, *argv)[0] == 0
    assert not (tmp_path / ".lock").exists()
    code, text = cli(capsys, *argv, "--resume")
    assert code == 0, text
    assert "nothing to run" in text and "ran 0 runs" in text


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


def test_a_tight_address_space_limit_is_refused_before_the_libraries_load():
    """Under `ulimit -v` 400 MB OpenBLAS used to spin forever while scipy loaded (and
    under 500 MB numba's import died with a MemoryError traceback): the command line
    refuses at once, naming the limit."""
    import resource

    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (400 * 1000**2, resource.RLIM_INFINITY))

    result = subprocess.run([sys.executable, "-m", "gdq_pddl.cli", "plan", "--task", "C"],
                            capture_output=True, text=True, timeout=120, preexec_fn=cap)
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert "address-space limit (ulimit -v) is 400 MB" in result.stderr
