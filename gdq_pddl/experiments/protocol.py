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
from gdq_pddl.learners import registry
from gdq_pddl.limits import check_count
from gdq_pddl.pddl.ppddl import DETERMINISATIONS

METHODS = registry.built_in_names()
"""The built-in learning methods by name (:mod:`gdq_pddl.learners.registry` declares them,
and those of other packages): ``GDQ`` the library's (SPEC section 4), ``GDQ-literal`` the
paper's Algorithms 1-3 read literally, ``GDQ-code`` and ``DARLING-code`` as the GDQ
authors' released code runs them (``docs/learners.md``)."""

PAPER_METHODS = registry.built_in_names("paper")
"""The paper's four methods (its GDQ being the library's)."""

GDQ_VARIANTS = registry.variants_of(registry.REFERENCE)
"""The library's GDQ and the two readings of the paper it is compared with."""

DEFAULT_METHODS = registry.built_in_names("default")
"""What the commands (``gdq-pddl scale`` too) compare unless told otherwise (not
GDQ-literal: it never learns, ``docs/decisions.md``)."""


@dataclass(frozen=True)
class Hyper:
    """Learning hyperparameters shared by every method (SPEC sections 5 and 6)."""

    alpha: float = 0.1  # step size of the TD update
    gamma: float = 0.95  # discount factor
    epsilon: float = 0.1  # probability of a uniformly random (allowed) action


EXPLORATIONS = ("enumerate", "online")
"""How a problem's states are found: all enumerated first, or as episodes reach them."""


@dataclass(frozen=True)
class ProblemSpec:
    """A PDDL problem an experiment learns on: its files and how its states are found."""

    domain: str
    """The domain file (the knowledge; of a PPDDL domain, reality too)."""
    problem: str
    """The problem file."""
    dynamics: str = ""
    """The dynamics file (a STRIPS domain's reality, a PPDDL domain's overlay); ``""``: none."""
    determinisation: str = DETERMINISATIONS[0]
    """What the planner knows of a PPDDL domain (``all-outcomes`` or ``most-likely``)."""
    exploration: str = EXPLORATIONS[0]
    """``enumerate``: every reachable state first; ``online``: states found as episodes
    reach them, a fresh instance per run (:class:`~gdq_pddl.envs.online.OnlineInstance`)."""

    def __post_init__(self) -> None:
        """Refuse a value no run can be made of (a ConfigError naming the field)."""
        for name, known in (("determinisation", DETERMINISATIONS),
                            ("exploration", EXPLORATIONS)):
            if getattr(self, name) not in known:
                raise ConfigError(f"ProblemSpec.{name}: expected one of {', '.join(known)}, "
                                  f"got {getattr(self, name)!r}")

    online = property(lambda self: self.exploration == "online")
    files = property(lambda self: (self.domain, self.problem, self.dynamics))

    @classmethod
    def from_record(cls, value: object) -> ProblemSpec:
        """The spec config.json records: its fields, or the list of earlier versions
        (``[domain, problem, dynamics[, determinisation[, "online"]]]``); a ConfigError
        for anything else."""
        if isinstance(value, cls):
            return value
        if isinstance(value, dict):
            try:
                return cls(**value)
            except TypeError:
                pass
        elif isinstance(value, list) and 3 <= len(value) <= 5 and value[4:] in ([], ["online"]):
            return cls(*value[:4], exploration="online" if value[4:] else EXPLORATIONS[0])
        raise ConfigError(f"a recorded problem must be the fields of a ProblemSpec, got "
                          f"{value!r}")


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
    ``office:<variant>``); of a PDDL experiment, the path of the knowledge's domain file
    (reality's states and outcomes, other probabilities:
    :func:`~gdq_pddl.experiments.knowledge.knowledge_instance`); None: reality itself.
    Not part of unit keys or seeds."""
    pddl: ProblemSpec | None = None
    """Learn on this PDDL problem instead of an office world (``world`` is then unused;
    each schedule entry names the problem)."""

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
        if not self.methods:
            raise ConfigError(f"experiment {self.name}: no method (known: "
                              f"{', '.join(registry.names())})")
        methods = tuple(registry.canonical(m) for m in self.methods)  # ConfigError if unknown
        object.__setattr__(self, "methods", methods)
        if self.pddl is not None and not isinstance(self.pddl, ProblemSpec):
            raise ConfigError(f"experiment {self.name}: pddl must be a ProblemSpec(domain=..., "
                              f"problem=...), got {type(self.pddl).__name__} {self.pddl!r}")
        if self.pddl is not None and self.pddl.online:
            for m in methods:
                if not registry.parse_method(m).entry.online:
                    raise ConfigError(f"method {m} cannot run on a problem explored online")

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
    kw.setdefault("methods", registry.built_in_names("robot"))
    return Experiment("robot", (("X", trials),), runs=runs, world="office_robot",
                      hyper=Hyper(alpha=0.5, gamma=0.95, epsilon=0.1), **kw)


PAPER_SIZE = (2500, 10)
"""Episodes per task and runs of ``gdq-pddl reproduce``: the paper's protocol."""
QUICK_SIZE = (300, 3)
"""Episodes per task and runs of ``gdq-pddl reproduce --quick``: a first look."""


def paper_protocol(quick: bool = False, seed: int = 0) -> list[Experiment]:
    """Everything the paper reports; ``quick`` is a small version for a first look."""
    episodes, runs = QUICK_SIZE if quick else PAPER_SIZE
    methods = registry.built_in_names("reproduce")
    out = task_experiments(episodes=episodes, runs=runs, methods=methods, seed=seed)
    out += [switch_experiment("C", "D", episodes, runs=runs, methods=methods, seed=seed),
            switch_experiment("C", "E", episodes, runs=runs, methods=methods, seed=seed),
            robot_experiment(runs=runs, seed=seed)]
    return out

