"""Hostile inputs where results go: unusable output folders and files, full disks,
`--resume` on damaged or changed folders, and `report` on damaged results (the rules of
``test_bad_inputs``: a non-zero exit, no traceback, the file or value named)."""

from __future__ import annotations

import errno
import io
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from gdq_pddl.cli import main
from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.scale import run_scale
from tests.cli.hostile import (
    FAST,
    OFFICE,
    edit,
    pddl_files,
    pddl_run,
    refused,
)
from tests.helpers import cli

# --- where the results go ----------------------------------------------------------------

def _out_cases(tmp_path: Path) -> dict[str, Path]:
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    return {"existing-file": a_file, "under-a-file": a_file / "sub", "proc": Path("/proc/gdq"),
            "sys": Path("/sys/gdq"), "dev-null": Path("/dev/null")}


@pytest.mark.parametrize("case", ["existing-file", "under-a-file", "proc", "sys", "dev-null"])
@pytest.mark.parametrize("command", [
    ["run", "--task", "C", *FAST], ["switch", "--episodes", "2", "--runs", "1"],
    ["building", "--positions", "100"], ["scale", "--sizes", "100", "--runs", "1"],
    ["problem", "--all"]])
def test_unusable_output_folders(capsys, tmp_path, case, command):
    out = _out_cases(tmp_path)[case]
    code, text = cli(capsys, *command, "--out", out)
    refused(code, text, "--out", str(out))


@pytest.mark.parametrize("case", ["a-folder", "under-a-file", "proc"])
def test_unusable_problem_output_file(capsys, tmp_path, case):
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    out = {"a-folder": tmp_path, "under-a-file": a_file / "x.pddl",
           "proc": Path("/proc/gdq.pddl")}[case]
    code, text = cli(capsys, "problem", "--task", "C", "--out", out)
    refused(code, text, "--out", str(out))


def _full_disk(*args, **kwargs):
    """A write on a full disk: the OSError names no file."""
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full here")
def test_a_full_device_is_named(capsys):
    code, text = cli(capsys, "problem", "--task", "C", "--out", "/dev/full")
    refused(code, text, "/dev/full", "No space left on device")


@pytest.mark.parametrize("command", [["planners"], ["problem", "--task", "C"]])
def test_a_full_standard_output_is_named(capsys, monkeypatch, command):
    class Full(io.StringIO):
        write = _full_disk

    monkeypatch.setattr(sys, "stdout", Full())
    code, text = cli(capsys, *command)
    refused(code, text, "standard output", "No space left on device")


def test_a_disk_filling_up_names_the_file(capsys, tmp_path, monkeypatch):
    import matplotlib.figure

    with monkeypatch.context() as m:  # the building's world file
        m.setattr(Path, "write_text", _full_disk)
        code, text = cli(capsys, "building", "--positions", "40", "--out", tmp_path / "b")
    refused(code, text, str(tmp_path / "b" / "building-40-s0.toml"), "No space left")
    with monkeypatch.context() as m:  # a run's unit file (every atomic write)
        m.setattr(np, "savez", _full_disk)
        code, text = _run(capsys, tmp_path / "o")
    refused(code, text, str(tmp_path / "o" / "units"), ".npz", "No space left")
    assert _run(capsys, tmp_path / "r")[0] == 0
    with monkeypatch.context() as m:  # a figure of the report
        m.setattr(matplotlib.figure.Figure, "savefig", _full_disk)
        code, text = cli(capsys, "report", tmp_path / "r")
    refused(code, text, str(tmp_path / "r"), ".png", "No space left")


def test_problem_out_in_a_new_folder_is_written(capsys, tmp_path):
    code, _ = cli(capsys, "problem", "--task", "C", "--out", tmp_path / "new" / "c.pddl")
    assert code == 0 and (tmp_path / "new" / "c.pddl").read_text().startswith(";")


# --- --resume and damaged results folders ----------------------------------------------

def test_a_rerun_into_a_folder_with_results_names_a_new_folder(capsys, tmp_path):
    """Rerunning a command refuses to mix results and says the three ways on: --resume,
    a new folder that does not exist yet (named), or deleting the old one."""
    out = tmp_path / "run-C"
    args = ["run", "--task", "C", *FAST, "--no-report", "--out", out]
    assert cli(capsys, *args)[0] == 0
    code, text = cli(capsys, *args)
    refused(code, text, "--resume", f"--out {out}-2", f"delete {out}")
    (tmp_path / "run-C-2").mkdir()  # taken: the next free name is suggested
    code, text = cli(capsys, *args)
    refused(code, text, f"--out {out}-3")
    code, text = cli(capsys, *args[:-1], f"{out}-3")  # the suggestion works as given
    assert code == 0, text

def _run(capsys, out, *extra, world=None):
    w = ["--world", world] if world else []
    return cli(capsys, "run", "--task", "C", *w, "--episodes", "4", "--runs", "2", "--method",
               "Q-learning", "Dyna-Q", "--jobs", "1", "--no-report", "--out", out, *extra)


@pytest.mark.parametrize("make", ["missing", "empty"])
def test_resume_of_nothing_is_refused(capsys, tmp_path, make):
    out = tmp_path / "o"
    if make == "empty":
        out.mkdir()
    code, text = _run(capsys, out, "--resume")
    refused(code, text, str(out), "without --resume")


def test_resume_refuses_a_changed_world_file(capsys, tmp_path):
    world = tmp_path / "w.toml"
    world.write_text(OFFICE, encoding="utf-8")
    out = tmp_path / "o"
    assert _run(capsys, out, world=world)[0] == 0
    world.write_text(edit(OFFICE, "success = 0.6\nstuck = 0.2", "success = 0.7\nstuck = 0.2"))
    code, text = _run(capsys, out, "--resume", world=world)
    refused(code, text, str(world), "changed")
    world.write_text(OFFICE, encoding="utf-8")  # restored: the resume goes on
    assert _run(capsys, out, "--resume", world=world)[0] == 0


@pytest.mark.parametrize("which", [1, 2])
def test_resume_refuses_changed_pddl_inputs(capsys, tmp_path, which):
    files = pddl_files(tmp_path)
    assert pddl_run(capsys, tmp_path, files, "--no-report")[0] == 0
    files[which].write_text(files[which].read_text() + "; edited\n", "utf-8")
    code, text = pddl_run(capsys, tmp_path, files, "--no-report", "--resume")
    refused(code, text, str(files[which]), "changed")


def _units(out: Path) -> list[Path]:
    return sorted((out / "units").glob("*.npz"))


@pytest.mark.parametrize("damage", ["truncated", "empty", "short", "missing-array"])
def test_resume_names_a_damaged_unit_and_how_to_rerun_it(capsys, tmp_path, damage):
    out = tmp_path / "o"
    assert _run(capsys, out)[0] == 0
    unit = _units(out)[1]
    if damage == "truncated":
        unit.write_bytes(unit.read_bytes()[:200])
    elif damage == "empty":
        unit.write_bytes(b"")
    else:
        with np.load(unit) as saved:
            data = {k: saved[k] for k in saved.files}
        if damage == "short":
            data["returns"] = data["returns"][:2]
        else:
            del data["policy"]
        np.savez(unit, **data)
    code, text = _run(capsys, out, "--resume")
    refused(code, text, unit.name, "delete it", "--resume")
    unit.unlink()  # as the message says: the run is done again, and the rest kept
    assert _run(capsys, out, "--resume")[0] == 0
    assert len(_units(out)) == 4


@pytest.mark.parametrize("content", ["{not json", "[1, 2]", "\xff"])
def test_resume_names_a_damaged_config(capsys, tmp_path, content):
    out = tmp_path / "o"
    assert _run(capsys, out)[0] == 0
    (out / "config.json").write_bytes(content.encode("latin-1"))
    code, text = _run(capsys, out, "--resume")
    refused(code, text, str(out / "config.json"), "damaged")


def test_resume_names_what_differs(capsys, tmp_path):
    out = tmp_path / "o"
    assert _run(capsys, out)[0] == 0
    code, text = cli(capsys, "run", "--task", "C", "--episodes", "5", "--runs", "2", "--method",
                     "Q-learning", "Dyna-Q", "--jobs", "1", "--out", out, "--resume")
    refused(code, text, "schedule")


def test_scale_resume_names_damaged_files(capsys, tmp_path):
    out = tmp_path / "s"
    argv = ["scale", "--sizes", "40", "--buildings", "1", "--runs", "1", "--episodes", "3",
            "--method", "DARLING", "Q-learning", "--jobs", "1", "--out", out]
    code, text = cli(capsys, *argv, "--resume")
    refused(code, text, str(out), "without --resume")
    # the run itself through the API: the CLI's figure and report are not what is tested
    run_scale(out, [40], 1, 3, buildings=1, methods=["DARLING", "Q-learning"], progress=False)
    unit = next((out / "units").glob("building-40-s0__*.npz"))
    unit.write_bytes(b"PK")
    refused(*cli(capsys, *argv, "--resume"), unit.name, "delete it")
    unit.unlink()
    (out / "config.json").write_text("[]")
    refused(*cli(capsys, *argv, "--resume"), "config.json", "damaged")


def test_a_run_that_fails_leaves_no_config_json_behind(tmp_path, monkeypatch):
    from gdq_pddl.experiments import Experiment, run_experiments, runner

    exps = [Experiment("tasks", (("C", 3),), methods=("Q-learning",), runs=2)]

    def broken(unit):
        raise GdqError("the planner went away")

    monkeypatch.setattr(runner, "run_unit", broken)
    with pytest.raises(GdqError, match="went away"):
        run_experiments(exps, tmp_path, jobs=1, progress=False)
    assert not (tmp_path / "config.json").exists()
    monkeypatch.undo()
    run_experiments(exps, tmp_path, jobs=1, progress=False)  # the corrected command
    assert (tmp_path / "episodes.csv").exists()


def test_a_second_process_on_one_folder_is_refused(capsys, tmp_path):
    out = tmp_path / "o"
    argv = [sys.executable, "-m", "gdq_pddl.cli", "run", "--task", "C", "--episodes", "4000",
            "--runs", "4", "--method", "GDQ", "--jobs", "1", "--no-report", "--out", str(out)]
    first = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.time() + 120
        while not (out / "config.json").exists() and time.time() < deadline:
            time.sleep(0.1)
        assert (out / "config.json").exists()
        code, text = cli(capsys, *argv[3:], "--resume")
        refused(code, text, str(out), "in use by another", str(first.pid))
    finally:
        first.send_signal(signal.SIGKILL)
        first.wait()
    code, text = cli(capsys, *argv[3:6], "--episodes", "4000", "--runs", "4", "--method",
                     "GDQ", "--jobs", "1", "--no-report", "--out", out, "--resume")
    assert code == 0, text  # the kill released the lock


# --- report -------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def office_results(tmp_path_factory):
    out = tmp_path_factory.mktemp("office") / "o"
    assert main(["run", "--task", "C", "--episodes", "30", "--runs", "2", "--method",
                 "Q-learning", "DARLING", "--jobs", "1", "--no-report", "--out",
                 str(out)]) == 0
    return out


@pytest.mark.parametrize(("name", "damage"), [
    ("episodes.csv", "truncated"), ("episodes.csv", "garbage"), ("episodes.csv", "latin-1"),
    ("episodes.csv", "not a number"), ("policies.csv", "garbage"), ("optimal.json", "garbage"),
])
def test_report_on_damaged_results(capsys, tmp_path, office_results, name, damage):
    import shutil

    out = tmp_path / "copy"
    shutil.copytree(office_results, out)
    path = out / name
    text = path.read_text()
    path.write_bytes({"truncated": text[: len(text) // 2].encode(),
                      "garbage": b"experiment,method\n\x01,,,\n{{{",
                      "latin-1": b"experiment,m\xe9thode\n",
                      "not a number": text.replace(",C,0,1,", ",C,0,one,", 1).encode(),
                      }[damage])
    code, out_text = cli(capsys, "report", out)
    refused(code, out_text, str(path))


@pytest.mark.parametrize(("column", "value"), [
    ("return", "nan"), ("return", "inf"), ("return", "-1e999"), ("steps", "-5"),
    ("steps", "2.5"), ("success", "7"), ("episode", "0"), ("run", "-1"), ("area_1", "-3"),
    (None, None),  # only the header
])
def test_report_refuses_values_no_run_writes(capsys, tmp_path, office_results, column, value):
    import shutil

    out = tmp_path / "copy"
    shutil.copytree(office_results, out)
    path = out / "episodes.csv"
    lines = path.read_text().splitlines(keepends=True)
    if column is None:
        lines = lines[:1]
    else:
        header = lines[0].strip().split(",")
        cells = lines[5].rstrip("\n").split(",")
        cells[header.index(column)] = value
        lines[5] = ",".join(cells) + "\n"
    path.write_text("".join(lines))
    code, text = cli(capsys, "report", out)
    refused(code, text, str(path))
    if column is not None:
        assert f"line 6, column {column}" in text


def test_report_on_a_pddl_run_folder(capsys, tmp_path):
    files = pddl_files(tmp_path)
    assert pddl_run(capsys, tmp_path, files, "--no-report")[0] == 0
    code, text = cli(capsys, "report", tmp_path / "o")
    assert code == 0, text
    assert "PDDL" in (tmp_path / "o" / "REPORT.md").read_text()
