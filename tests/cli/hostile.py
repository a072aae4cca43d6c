"""What the hostile-input tests share (``test_bad_inputs``, ``test_bad_results``,
``test_bad_api``): the shipped texts they edit, a fast run's options, and the checks that a
refusal is one clear line naming what is at fault. ``test_hostile_cli`` and
``test_hostile_runs`` take the shipped texts from here too; their fast options (without a
report) and refusal check (exit 2) are their own."""

from __future__ import annotations

from pathlib import Path

from gdq_pddl.resources import data_file, world_text
from tests.helpers import cli

OFFICE = world_text("office")
KEYS_DOMAIN = data_file("domains", "keys.pddl").read_text(encoding="utf-8")
KEYS_PROBLEM = data_file("problems", "keys-1.pddl").read_text(encoding="utf-8")
KEYS_DYNAMICS = data_file("dynamics", "keys.toml").read_text(encoding="utf-8")
FAST = ["--episodes", "3", "--runs", "1", "--method", "Q-learning", "--jobs", "1"]


def refused(code, text: str, *names: str) -> None:
    assert code not in (0, None), text
    assert "Traceback" not in text, text
    for name in names:
        assert name in text, f"{name!r} not named in: {text}"


def edit(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def pddl_files(tmp_path: Path, problem: str = KEYS_PROBLEM, dynamics: str = KEYS_DYNAMICS):
    files = (tmp_path / "domain.pddl", tmp_path / "problem.pddl", tmp_path / "dynamics.toml")
    for path, text in zip(files, (KEYS_DOMAIN, problem, dynamics), strict=True):
        path.write_text(text, encoding="utf-8")
    return files


def pddl_run(capsys, tmp_path, files, *extra):
    d, p, y = files
    return cli(capsys, "run", "--domain", d, "--problem", p, "--dynamics", y, *FAST,
               "--out", tmp_path / "o", *extra)
