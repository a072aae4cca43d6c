"""Hostile options, end to end: numbers on the command line, sizes past memory, the
memory override and --jobs, each refused with one clear line before any work (the files'
cases are in test_bad_inputs.py)."""

from __future__ import annotations

import time

import pytest

from gdq_pddl.errors import GdqError
from gdq_pddl.resources import data_file
from tests.cli.hostile import FAST, refused
from tests.helpers import cli

# --- numbers on the command line ------------------------------------------------------------


@pytest.mark.parametrize(("argv", "names"), [
    (["run", "--task", "C", "--jobs", "-2"], ["--jobs", "-2"]),
    (["run", "--task", "C", "--jobs", "0"], ["--jobs", "0"]),
    (["run", "--task", "C", "--jobs", "two"], ["--jobs", "two"]),
    (["run", "--task", "C", "--seed", "-1"], ["--seed", "-1"]),
    (["run", "--task", "C", "--episodes", "0"], ["--episodes", "0"]),
    (["run", "--task", "C", "--runs", "-3"], ["--runs", "-3"]),
    (["run", "--task", "C", "--episodes", "1e3"], ["--episodes", "1e3"]),
    (["switch", "--seed", "-5"], ["--seed", "-5"]),
    (["reproduce", "--seed", "-1"], ["--seed", "-1"]),
    (["knowledge", "--runs", "0"], ["--runs", "0"]),
    (["scale", "--sizes", "0"], ["--sizes", "0"]),
    (["scale", "--episodes", "-1"], ["--episodes", "-1"]),
    (["building", "--positions", "-5"], ["--positions", "-5"]),
    (["building", "--positions", "100", "--seed", "-1"], ["--seed", "-1"]),
    (["building", "--positions", "40", "--doors", "4"], ["doors", "got 4"]),  # 2 rooms, 3 tasks
    (["building", "--positions", "40", "--doors", "1000000000000"], ["doors", "1000000000000"]),
    (["building", "--positions", "150", "--doors", "33"], ["doors", "33", "fire doors"]),
    (["plan", "--task", "C", "--tolerance", "nan"], ["--tolerance", "nan"]),
    (["plan", "--task", "C", "--tolerance", "inf"], ["--tolerance", "inf"]),
    (["plan", "--task", "C", "--tolerance", "-0.5"], ["--tolerance", "-0.5"]),
    (["plan", "--task", "C", "--tolerance", "1e308"], ["--tolerance", "1e308"]),  # overflowed
    (["plan", "--task", "C", "--tolerance", "101"], ["--tolerance", "101"]),
    (["plan", "--domain", data_file("domains", "keys-ppddl.pddl"), "--problem",
      data_file("problems", "keys-ppddl-1.pddl"), "--tolerance", "1e308"],
     ["--tolerance", "1e308"]),
])
def test_bad_numbers_on_the_command_line(capsys, argv, names):
    code, out = cli(capsys, *argv)
    refused(code, out, *names)


@pytest.mark.parametrize("to", ["C", "c"])
def test_a_switch_to_the_same_task_is_refused(capsys, tmp_path, to):
    from gdq_pddl.experiments import switch_experiment

    code, out = cli(capsys, "switch", "--from", "C", "--to", to, *FAST, "--out", tmp_path / "o")
    refused(code, out, "--from and --to are the same task (C)")
    assert not (tmp_path / "o").exists()
    with pytest.raises(GdqError, match="same task"):
        switch_experiment("C", to, 3)


@pytest.mark.parametrize(("argv", "names"), [
    (["--episodes", "1000000000000", "--runs", "1"], ["--episodes", "1,000,000,000,000"]),
    (["--runs", "1000000000"], ["--runs", "1,000,000,000"]),
    (["--episodes", "100000", "--runs", "100000"], ["the report", "--no-report"]),
])
def test_sizes_past_memory_are_refused_up_front(capsys, tmp_path, argv, names):
    t0 = time.perf_counter()
    code, out = cli(capsys, "run", "--task", "C", *argv, "--out", tmp_path / "o")
    refused(code, out, *names, "would need", "memory")
    assert time.perf_counter() - t0 < 10
    assert not (tmp_path / "o").exists()


def test_scale_sizes_past_memory_are_refused(capsys, tmp_path):
    code, out = cli(capsys, "scale", "--sizes", "100000", "--out", tmp_path / "o")
    refused(code, out, "--sizes 100000", "would need")
    code, out = cli(capsys, "scale", "--runs", "1000000000", "--out", tmp_path / "o")
    refused(code, out, "--runs 1,000,000,000", "would need")
    code, out = cli(capsys, "scale", "--episodes", "1000000000000", "--out", tmp_path / "o")
    refused(code, out, "--episodes 1,000,000,000,000", "would need")
    code, out = cli(capsys, "building", "--positions", "10000000000", "--out", tmp_path / "b")
    refused(code, out, "positions = 10,000,000,000", "would need")


SCALE_FAST = ["scale", "--sizes", "40", "--runs", "1", "--episodes", "3", "--method",
              "Q-learning"]


@pytest.mark.parametrize("buildings", ["1000000000", "100000", "1001"])
def test_absurd_buildings_are_refused_up_front(capsys, tmp_path, buildings):
    # 10**9 was killed for memory before printing anything, 100000 ran for hours
    t0 = time.perf_counter()
    code, out = cli(capsys, *SCALE_FAST, "--buildings", buildings, "--out", tmp_path / "o")
    refused(code, out, f"--buildings {buildings}", "1,000")
    assert time.perf_counter() - t0 < 10
    assert not (tmp_path / "o").exists()


def test_scale_checks_the_memory_of_all_buildings_together(capsys, tmp_path, monkeypatch):
    # a machine of 3 MB: a learner's tables (2.6 MB) and one building's runs fit, not the
    # runs of 1000 buildings held until the report (4.1 MB)
    monkeypatch.setenv("GDQ_PDDL_MEMORY", str(3 * 10**6))
    code, out = cli(capsys, *SCALE_FAST, "--runs", "2", "--buildings", "1000",
                    "--out", tmp_path / "o")
    refused(code, out, "1,000 buildings", "--buildings", "would need")
    code, out = cli(capsys, *SCALE_FAST, "--buildings", "2", "--seed", "4611686018427387904",
                    "--out", tmp_path / "o")
    refused(code, out, "--seed + --buildings - 1", "4611686018427387905")


@pytest.mark.parametrize("text, have", [("17179869184", 17179869184), ("16GB", 16 * 10**9),
                                        ("16 GiB", 16 * 1024**3), ("1.5tb", 15 * 10**11),
                                        ("512MB", 512 * 10**6), ("", None), ("  ", None)])
def test_the_memory_override_takes_bytes_or_a_unit(monkeypatch, text, have):
    from gdq_pddl.limits import memory_override, physical_memory

    monkeypatch.setenv("GDQ_PDDL_MEMORY", text)
    assert memory_override() == have
    if have is not None:
        assert physical_memory() == have


@pytest.mark.parametrize("text", ["abc", "0", "-5", "8XB", "8 G B", "nan", "inf", "1e300"])
def test_a_mistyped_memory_override_is_refused_before_any_work(capsys, tmp_path,
                                                               monkeypatch, text):
    # before, a value that was not all digits was ignored without a word
    monkeypatch.setenv("GDQ_PDDL_MEMORY", text)
    code, out = cli(capsys, "run", "--task", "C", "--episodes", "3", "--runs", "1",
                    "--out", tmp_path / "o")
    refused(code, out, "GDQ_PDDL_MEMORY", repr(text.strip()), "16GB")
    assert not (tmp_path / "o").exists()


def test_jobs_are_capped_at_the_runs_and_said(capsys, tmp_path):
    # one run: it runs in this process (two would start a pool of workers, each loading
    # the kernels, for the same message)
    code, out = cli(capsys, "run", "--task", "C", "--episodes", "3", "--runs", "1",
                    "--method", "Q-learning", "--jobs", "40", "--out", tmp_path / "o",
                    "--no-report")
    assert code == 0, out
    assert "1 run(s) to do on 1 process(es) (--jobs 40 capped" in out
