"""What an experiment is: a world, a schedule of tasks, methods, runs and hyperparameters.

An :class:`Experiment` expands into :class:`Unit` s, one per (method, run): what runs on
one core, is saved when it finishes and is skipped by ``--resume``. Its seeds come from
the experiment's seed and the unit's identity only, whatever the jobs or their order.
"""

from __future__ import annotations

import re
import zlib
from dataclasses import dataclass, field

import numpy as np

from gdq_pddl.errors import ConfigError
from gdq_pddl.limits import check_count

METHODS = ("GDQ", "GDQ-literal", "GDQ-code", "DARLING", "DARLING-code", "Dyna-Q",
           "Q-learning")
"""Learning methods by name: ``GDQ`` the library's (SPEC section 4), ``GDQ-literal`` the
paper's Algorithms 1-3 read literally, ``GDQ-code`` and ``DARLING-code`` as the GDQ
authors' released code runs them (``docs/learners.md``)."""

PAPER_METHODS = ("GDQ", "DARLING", "Dyna-Q", "Q-learning")
"""The paper's four methods (its GDQ being the library's)."""

GDQ_VARIANTS = ("GDQ", "GDQ-literal", "GDQ-code")
"""The library's GDQ and the two readings of the paper it is compared with."""

DEFAULT_METHODS = ("GDQ", "GDQ-code", "DARLING", "Dyna-Q", "Q-learning")
"""What the commands compare unless told otherwise (not GDQ-literal: it never learns)."""

SCALE_METHODS: dict[str, tuple[str, dict]] = {
    "GDQ": ("gdq", {}),
    "GDQ-literal": ("gdq", {"variant": "literal"}),
    "GDQ-code": ("gdq", {"variant": "code", "plan_tolerance": 0.3}),
    "DARLING": ("darling", {"tolerance": 0.3}),
    "Dyna-Q": ("dynaq", {}),
    "Q-learning": ("qlearning", {}),
}
"""The methods of ``gdq-pddl scale``: name -> (``make_learner`` name, its arguments)."""

SCALE_DEFAULT_METHODS = tuple(m for m in SCALE_METHODS if m != "GDQ-literal")
"""Every method but GDQ-literal, which never learns (``docs/decisions.md``)."""


@dataclass(frozen=True)
class Hyper:
    """Learning hyperparameters shared by every method (SPEC sections 5 and 6)."""

    alpha: float = 0.1  # step size of the TD update
    gamma: float = 0.95  # discount factor
    epsilon: float = 0.1  # probability of a uniformly random (allowed) action


@dataclass(frozen=True)
class Experiment:
    """One experiment: each method learns ``runs`` times along ``schedule``."""

    name: str
    """Label written in the ``experiment`` column (``tasks``, ``switch-C-D``, ``robot`` ...)."""
    schedule: tuple[tuple[str, int], ...]
    """``(task, episodes)`` in order; a task is a name (``C``) or ``start->goal``."""
    methods: tuple[str, ...] = PAPER_METHODS
    runs: int = 10
    world: str = "office"
    """``office``, ``office_robot`` (built in) or a path to a world file."""
    hyper: Hyper = field(default_factory=Hyper)
    planner: str = "graph"
    seed: int = 0
    knowledge: str | None = None
    """The world the knowledge is built from, named like ``world`` (also
    ``office:<variant>``); None: ``world`` itself. Not part of unit keys or seeds."""
    pddl: tuple[str, ...] | None = None
    """``(domain, problem, dynamics[, determinisation])`` file paths (dynamics ``""``:
    none): learn on that PDDL problem instead of an office world (``world`` and
    ``knowledge`` are then unused; each schedule entry names the problem)."""

    def __post_init__(self) -> None:
        """Refuse what no run can be made of (a ConfigError naming the field)."""
        check_count("runs", self.runs)
        check_count("seed", self.seed)
        if self.runs < 1:
            raise ConfigError(f"runs must be at least 1, got {self.runs}")
        if not self.schedule:
            raise ConfigError(f"experiment {self.name}: the schedule is empty")
        for task, episodes in self.schedule:
            check_count(f"episodes of {task}", episodes)
            if episodes < 1:
                raise ConfigError(f"episodes of {task} must be at least 1, got {episodes}")
        unknown = [m for m in self.methods if m not in METHODS]
        if unknown or not self.methods:
            raise ConfigError(f"unknown method {unknown[0] if unknown else None!r} "
                              f"(known: {', '.join(METHODS)})")

    @property
    def episodes(self) -> int:
        return sum(n for _, n in self.schedule)

    def units(self) -> list[Unit]:
        return [Unit(self, m, r) for m in self.methods for r in range(self.runs)]


@dataclass(frozen=True)
class Unit:
    """One method's one run of an experiment."""

    experiment: Experiment
    method: str
    run: int

    @property
    def key(self) -> str:
        """A file-name-safe identity, unique within an output folder (:func:`safe_name`)."""
        tasks = "-".join(t.replace("->", "_to_") for t, _ in self.experiment.schedule)
        return safe_name(f"{self.experiment.name}__{tasks}__{self.method}__run{self.run}")

    def seeds(self) -> tuple[np.random.Generator, int]:
        """The learner's Generator and the env's integer seed, from the experiment and the
        run only: run ``r`` of every method starts from the same seeds (paired runs)."""
        ident = zlib.crc32(f"{self.experiment.name}|{self.experiment.schedule}".encode())
        seq = np.random.SeedSequence([self.experiment.seed, ident, self.run])
        learner, env = seq.spawn(2)
        return np.random.default_rng(learner), int(env.generate_state(1)[0])


SAFE = re.compile(r"[A-Za-z0-9_.+=-]+")
"""The characters a name may keep in a file name: no separator, no space, no quote."""
MAX_NAME = 150
"""The longest file name :func:`safe_name` makes (file systems allow 255 bytes)."""


def safe_name(name: str) -> str:
    """``name`` as one file name inside a folder: itself when made of :data:`SAFE`
    characters, not starting with a dot and at most :data:`MAX_NAME` long; otherwise
    every other character replaced by ``_``, cut and followed by a hash of the whole name
    (``../../x`` gives ``_._.._x-<hash>``: never a path out of the folder)."""
    if SAFE.fullmatch(name) and not name.startswith(".") and len(name) <= MAX_NAME:
        return name
    digest = f"{zlib.crc32(name.encode('utf-8', 'surrogatepass')):08x}"
    cleaned = re.sub(r"[^A-Za-z0-9_.+=-]", "_", name)
    cleaned = "_" + cleaned[1:] if cleaned.startswith(".") else cleaned
    return f"{cleaned[:MAX_NAME - 9]}-{digest}"


def task_experiments(tasks: tuple[str, ...] = ("A", "B", "C", "D"), episodes: int = 2500,
                     **kw) -> list[Experiment]:
    """The paper's first experiment: each task learnt from scratch."""
    return [Experiment("tasks", ((t, episodes),), **kw) for t in tasks]


def switch_experiment(first: str, second: str, episodes: int = 2500, **kw) -> Experiment:
    """The paper's task switch: ``episodes`` on ``first``, then as many on ``second``."""
    if first.upper() == second.upper():  # task names are upper-cased
        raise ConfigError(f"first and second are the same task ({first}): a switch needs two")
    return Experiment(f"switch-{first}-{second}", ((first, episodes), (second, episodes)), **kw)


def robot_experiment(trials: int = 30, runs: int = 10, **kw) -> Experiment:
    """SPEC section 6: the real-robot protocol, simulated with durations as costs."""
    kw.setdefault("methods", ("GDQ", "GDQ-literal", "GDQ-code", "Dyna-Q"))
    return Experiment("robot", (("X", trials),), runs=runs, world="office_robot",
                      hyper=Hyper(alpha=0.5, gamma=0.95, epsilon=0.1), **kw)


PAPER_SIZE = (2500, 10)
"""Episodes per task and runs of ``gdq-pddl reproduce``: the paper's protocol."""
QUICK_SIZE = (300, 3)
"""Episodes per task and runs of ``gdq-pddl reproduce --quick``: a first look."""


def paper_protocol(quick: bool = False, seed: int = 0) -> list[Experiment]:
    """Everything the paper reports; ``quick`` is a small version for a first look."""
    episodes, runs = QUICK_SIZE if quick else PAPER_SIZE
    methods = ("GDQ", "GDQ-literal", "GDQ-code", "DARLING", "Dyna-Q", "Q-learning")
    out = task_experiments(episodes=episodes, runs=runs, methods=methods, seed=seed)
    out += [switch_experiment("C", "D", episodes, runs=runs, methods=methods, seed=seed),
            switch_experiment("C", "E", episodes, runs=runs, methods=methods, seed=seed),
            robot_experiment(runs=runs, seed=seed)]
    return out

