"""Graded exercises for a class on planning-guided reinforcement learning, in the order
of the tutorial (``docs/tutorial.md``; ``docs/exercises.md`` says how to use them).

Each exercise is one function a student writes in a stub (:data:`EXERCISES`; the stubs
are the modules of :mod:`gdq_pddl.exercises.stubs`); :func:`check` runs it on seeded
cases of the office against the package's own learners (:mod:`.grading`) and says what
differs, on which input, in plain words. The reference solutions are in
:mod:`gdq_pddl.exercises.solutions`, which :func:`write_stubs` does not write.
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from gdq_pddl.errors import ConfigError

__all__ = ["EXERCISES", "Exercise", "check", "exercise", "load_function", "stub_text",
           "write_stubs"]


@dataclass(frozen=True)
class Exercise:
    """One graded exercise."""

    number: int
    """Its place in the lesson, from 1."""
    stem: str
    """The stub's file name without ``.py``."""
    function: str
    """The name of the function the student writes."""
    title: str
    """What it is about, in a few words."""
    section: str
    """Where the tutorial teaches it."""

    @property
    def file_name(self) -> str:
        """The stub's file name."""
        return f"{self.stem}.py"


EXERCISES: tuple[Exercise, ...] = (
    Exercise(1, "ex1_q_update", "q_update", "the Q-learning update", "section 2"),
    Exercise(2, "ex2_dyna_planning", "dyna_planning", "Dyna-Q's planning step", "section 3"),
    Exercise(3, "ex3_optinit", "optinit", "values from the planner's knowledge: OptInit",
             "section 5"),
    Exercise(4, "ex4_hybrid_backup", "hybrid_backup", "GDQ's hybrid backup", "section 5"),
    Exercise(5, "ex5_wrong_knowledge", "trials_to_turn_away",
             "wrong knowledge: when GDQ turns away from a door that does not open", "section 6"),
)
"""The exercises, in the order of the lesson."""


def exercise(number: int) -> Exercise:
    """The exercise ``number`` (a :class:`ConfigError` for one that does not exist)."""
    if not 1 <= number <= len(EXERCISES):
        raise ConfigError(f"exercise {number}: there are exercises 1 to {len(EXERCISES)} "
                          "(`gdq-pddl exercises` lists them)")
    return EXERCISES[number - 1]


def stub_text(number: int) -> str:
    """The text of exercise ``number``'s stub, as :func:`write_stubs` writes it."""
    stubs = resources.files("gdq_pddl.exercises.stubs")
    return stubs.joinpath(exercise(number).file_name).read_text(encoding="utf-8")


def write_stubs(folder: Path, overwrite: bool = False) -> list[Path]:
    """Write every exercise's stub into ``folder`` (made if missing) and return the paths.
    A stub already there is a student's work: refused (a :class:`ConfigError` naming it)
    unless ``overwrite``."""
    folder = Path(folder)
    paths = [folder / e.file_name for e in EXERCISES]
    there = [p for p in paths if p.exists()]
    if there and not overwrite:
        raise ConfigError(f"{there[0]} exists (your work?): pick another folder, or give "
                          "--force to replace the stubs")
    if folder.exists() and not folder.is_dir():
        raise ConfigError(f"{folder} is a file, not a folder")
    folder.mkdir(parents=True, exist_ok=True)
    for e, path in zip(EXERCISES, paths, strict=True):
        path.write_text(stub_text(e.number), encoding="utf-8")
    return paths


class StudentCodeError(Exception):
    """A student's file cannot be loaded or lacks its function (a failed check, exit 1,
    not bad usage)."""


def load_function(path: Path, name: str) -> Callable:
    """The function ``name`` of the Python file ``path``: a :class:`ConfigError` if the
    file does not exist, a :class:`StudentCodeError` if it fails to load or has no such
    function."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: no such file (write the stubs with `gdq-pddl exercises "
                          "init DIR`, then give the path of yours)")
    spec = importlib.util.spec_from_file_location(f"_gdq_exercise_{path.stem}", path)
    if spec is None or spec.loader is None:
        raise ConfigError(f"{path}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the student's file: whatever it raises, say it
        line = getattr(exc, "lineno", None)
        where = f" (line {line})" if line else ""
        raise StudentCodeError(f"{path} failed to load{where}: {type(exc).__name__}: "
                               f"{exc}") from None
    finally:
        sys.modules.pop(spec.name, None)
    function = getattr(module, name, None)
    if not callable(function):
        raise StudentCodeError(f"{path} has no function {name}()")
    return function


def check(number: int, path: Path | None = None, function: Callable | None = None):
    """Grade exercise ``number``: ``function``, or the one in ``path`` (default: the
    stub's file name in the current folder). Returns a
    :class:`~gdq_pddl.exercises.grading.Verdict`."""
    from gdq_pddl.exercises.grading import Verdict, grade  # start-up time: numba learners

    e = exercise(number)
    if function is None:
        try:
            function = load_function(Path(path) if path else Path(e.file_name), e.function)
        except StudentCodeError as exc:
            return Verdict(False, f"Exercise {number} ({e.title}): {exc}")
    return grade(number, function, e.title)
