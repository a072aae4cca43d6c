"""Hostile use of the command line (issue 19): a name that means one thing in every
process, problem names that never become paths, input files checked before they are
read, options that would be ignored refused, a finished folder, a tight address-space
limit. The runner and its files: test_hostile_runs.py.

Each test is one case a careless or malicious user tried, with what must hold instead of
what happened: a clear one-line refusal (exit 2), or the right result.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tests.cli.hostile import KEYS_DOMAIN, KEYS_DYNAMICS, KEYS_PROBLEM, OFFICE
from tests.helpers import cli

FAST = ["--episodes", "3", "--runs", "1", "--method", "Q-learning", "--jobs", "1",
        "--no-report"]


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


# --- a problem name never becomes a path, nor breaks a CSV row ----------------------------

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


# --- a finished folder, and a limit the libraries cannot load under -----------------------

def test_a_finished_folder_has_no_lock_and_resume_has_nothing_to_do(capsys, tmp_path):
    argv = ["run", "--task", "C", *FAST, "--out", tmp_path]
    assert cli(capsys, *argv)[0] == 0
    assert not (tmp_path / ".lock").exists()
    code, text = cli(capsys, *argv, "--resume")
    assert code == 0, text
    assert "nothing to run" in text and "ran 0 runs" in text


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
