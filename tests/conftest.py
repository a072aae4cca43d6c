"""Fixtures shared by the test folders (plain helpers are in ``tests/helpers.py``).

The tests are laid out by the package's layers (``tests/pddl``, ``tests/planning`` ...,
``tests/cli``); each folder is a package, so modules import helpers as ``tests.helpers``.
"""

from __future__ import annotations

import io

import pytest
from tqdm import tqdm

from gdq_pddl import limits
from gdq_pddl.learners import office_task_context, precompile
from gdq_pddl.world import load_world
from gdq_pddl.world_types import World
from tests.helpers import BACKGROUND, WARMER, start_warm_kernels


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "background(start, first=False): start(item) queues the "
                            "test's subprocess when collection ends (first ones first; "
                            "tests.helpers.Background)")


WARM_KERNELS_FROM = 500
"""A session of at least this many tests (the suite has about 2,000) first queues
:func:`~tests.helpers.start_warm_kernels`; a few files end before it would help."""


def pytest_collection_finish(session: pytest.Session) -> None:
    if session.config.option.collectonly:
        return
    marked = [(item, item.get_closest_marker("background")) for item in session.items]
    marked = [(item, mark) for item, mark in marked if mark is not None]
    warming = start_warm_kernels() if len(session.items) >= WARM_KERNELS_FROM else None
    # first the subprocesses with a numba cache of their own; the others after the warmer:
    # on a fresh checkout they then load the kernels the warmer and this process compiled
    # meanwhile (started sooner, the notebook's kernel compiled two loops a third time)
    for item, mark in marked:
        if mark.kwargs.get("first"):
            mark.args[0](item)
    if warming is not None:
        BACKGROUND.after(warming)
    for item, mark in marked:
        if not mark.kwargs.get("first"):
            mark.args[0](item)


def pytest_sessionfinish(session: pytest.Session) -> None:
    WARMER.stop()  # first: the queue may be waiting for it
    BACKGROUND.stop()


@pytest.fixture(scope="session", autouse=True)
def no_loop_precompile():
    """No second process to compile the episode loop before a run on several processes
    (:mod:`gdq_pddl.learners.precompile`): here the loop is compiled, or loaded, by the
    tests run before, so each such process only imported the package again (about 3 s of
    CPU) to load it. The CLI run in a subprocess still starts one."""
    patch = pytest.MonkeyPatch()
    patch.setattr(precompile, "start", lambda methods=(): None)
    yield
    patch.undo()


@pytest.fixture(scope="session")
def office() -> World:
    """The shipped office world (a frozen value: one for the whole session)."""
    return load_world(None)


@pytest.fixture(scope="module")
def ctx_c(office: World):
    """The learners' task context of the office's task C (one per test module, as a
    learner's start_task may keep a reference to it)."""
    return office_task_context(office, "C")


@pytest.fixture
def bars(monkeypatch) -> list[tqdm]:
    """Every bar :func:`slow_progress` makes, shown at once into a buffer (not stderr)."""
    made: list[tqdm] = []

    class Shown(tqdm):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs | {"disable": False, "delay": 0,
                                                "file": io.StringIO()})
            made.append(self)

    monkeypatch.setattr(limits, "tqdm", Shown)
    return made
