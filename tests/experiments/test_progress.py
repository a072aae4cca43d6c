"""How far a run is, where stderr is no terminal (a log file, CI): a line ``k of N runs
done`` at least every 30 s (issue 35), and a bar only on a terminal."""

from __future__ import annotations

import io
import time

from gdq_pddl import limits
from gdq_pddl.experiments import Experiment, run_experiments
from gdq_pddl.experiments.work import run_unit
from gdq_pddl.limits import Progress


def test_without_a_terminal_a_line_comes_every_interval_until_closed(monkeypatch):
    monkeypatch.setattr(limits, "PROGRESS_EVERY", 0.05)
    log = io.StringIO()
    bar = Progress(5, 1, stream=log)
    bar.update(2)
    time.sleep(0.3)
    bar.close()
    time.sleep(0.15)
    lines = log.getvalue().splitlines()
    assert len(lines) >= 3 and all(line.startswith("runs: 3 of 5 runs done (") for line in lines)
    assert log.getvalue() == "\n".join(lines) + "\n"  # nothing after close


def test_a_disabled_progress_prints_nothing(monkeypatch):
    monkeypatch.setattr(limits, "PROGRESS_EVERY", 0.02)
    log = io.StringIO()
    bar = Progress(2, stream=log, enabled=False)
    time.sleep(0.1)
    bar.update()
    bar.close()
    assert log.getvalue() == ""


def test_a_run_logged_to_a_file_says_how_many_runs_are_done(tmp_path, capsys, monkeypatch):
    """The runner's progress on a stderr that is no terminal (pytest's capture): lines
    counting the runs done, none drawn as a bar."""
    monkeypatch.setattr(limits, "PROGRESS_EVERY", 0.05)

    def slow(unit):
        time.sleep(0.3)
        return run_unit(unit)

    exp = Experiment("tasks", (("C", 3),), methods=("Q-learning",), runs=2)
    run_experiments([exp], tmp_path, jobs=1, work=slow)
    err = capsys.readouterr().err
    assert "runs: 0 of 2 runs done (" in err and "runs: 1 of 2 runs done (" in err
    assert "\r" not in err  # no bar
