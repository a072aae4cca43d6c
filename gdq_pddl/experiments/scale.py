"""Learning against building size (``gdq-pddl scale``): every method on generated buildings.

For each size N and each building seed ``S = seed, seed + 1, ...``, task A of the building
of ``gdq-pddl building --positions N --seed S`` is one
:class:`~gdq_pddl.experiments.protocol.Experiment` named ``building-N-sS`` (world
``building:N:S``, gamma ``1 - 1 / step limit``), run by the experiment runner with its own
work and collect, as ``gdq-pddl pairs`` is (so ``--jobs``, Ray and ``--resume`` as every
command has them). Each method runs ``runs`` times for ``episodes`` episodes over the
compact model (:mod:`gdq_pddl.envs.compact`), run ``r`` seeded by ``(S, N, r)`` only
(paired runs, the same whether or not resumed, whatever the jobs)::

    config.json           the experiments (one per building), package versions
    units/building-N-sS__A__<method>__run<r>.npz   one finished run (:data:`SCALE_ARRAYS`)
    building-N-sS.npz     every run on that building (:func:`save_building`)

The measures and why: ``docs/decisions.md``, "Generated buildings".
"""
from __future__ import annotations

import numbers
import time
from dataclasses import dataclass, field
from functools import lru_cache
from itertools import groupby
from pathlib import Path

import numpy as np
from scipy.special import stdtrit  # t's quantile: scipy.stats costs 0.6 s of start-up

from gdq_pddl.buildings import building_world
from gdq_pddl.envs.office import CompactEnv, OfficeInstance
from gdq_pddl.envs.solve_compact import reference_value
from gdq_pddl.errors import ConfigError, GdqError
from gdq_pddl.experiments.checks import EPISODE_BYTES, UNIT_BYTES, check_sizes
from gdq_pddl.experiments.folder import read_unit
from gdq_pddl.experiments.knowledge import BUILDING_PREFIX, building_of, load_world_named
from gdq_pddl.experiments.protocol import DEFAULT_METHODS, Experiment, Hyper, Unit
from gdq_pddl.experiments.runner import run_experiments, save_unit
from gdq_pddl.experiments.work import make_learner
from gdq_pddl.learners.context import task_context
from gdq_pddl.learners.episodes import run_compact
from gdq_pddl.learners.registry import parse_method
from gdq_pddl.learners.tables import table_bytes
from gdq_pddl.limits import check_count, check_memory

WINDOW = 50
"""Episodes of the moving average of the return that decides convergence."""
FRACTION = 0.9
"""A run has converged once that average reaches ``r_fail + FRACTION (v_ref - r_fail)``."""
TOLERANCE = 0.3
"""Plan-length tolerance of DARLING's and GDQ-code's door-route plans."""
FIRST = 300
"""Episodes of the early-learning measure (the mean return over a run's first ones)."""
MAX_BUILDINGS = 1000
"""The most ``--buildings`` per size."""


@dataclass
class BuildingResult:
    """Everything measured on one building."""

    positions: int
    seed: int  # gdq-pddl building --seed
    doors: int
    n_states: int
    n_actions: int
    plan_length: int
    step_limit: int
    r_max: float
    v_ref: float  # the task's reference value (a lower bound on V*)
    context_s: float
    returns: dict[str, np.ndarray] = field(default_factory=dict)  # runs x episodes
    success: dict[str, np.ndarray] = field(default_factory=dict)  # runs x episodes, bool
    steps: dict[str, int] = field(default_factory=dict)  # of all runs of a method
    wall_s: dict[str, float] = field(default_factory=dict)  # of their compiled loops
    table_mb: dict[str, float] = field(default_factory=dict)  # one learner's tables

    @property
    def name(self) -> str:
        """The building's name, as ``gdq-pddl building`` names its file."""
        return building_name(self.positions, self.seed)

    @property
    def r_fail(self) -> float:
        """The worst return: a timeout."""
        return -self.r_max - (self.step_limit - 1)

    @property
    def threshold(self) -> float:
        """The moving average at which a run has converged (:func:`converged_at`)."""
        return self.r_fail + FRACTION * (self.v_ref - self.r_fail)


def building_name(positions: int, seed: int) -> str:
    """``building-N-sS``: the name :func:`gdq_pddl.buildings.generate` gives a building."""
    return f"building-{positions}-s{seed}"


def converged_at(returns: np.ndarray, threshold: float, window: int = WINDOW) -> int | None:
    """Episodes to convergence of one run: the first episode at which the trailing
    ``window``-episode mean return reaches ``threshold`` (first passage), or None."""
    if len(returns) < window:
        return None
    avg = np.convolve(returns, np.ones(window) / window, mode="valid")
    hit = np.flatnonzero(avg >= threshold)
    return int(hit[0] + window) if len(hit) else None


def by_size(results: list[BuildingResult]) -> dict[int, list[BuildingResult]]:
    """The buildings of each size, as :func:`run_scale` returns them (by size, then seed)."""
    return {n: list(group) for n, group in groupby(results, key=lambda r: r.positions)}


def convergence(group: list[BuildingResult], name: str) -> tuple[float | None, int, int]:
    """Median episodes to convergence over the converged runs of ``name`` on the buildings
    of ``group``, how many converged and how many runs there were."""
    runs = [converged_at(x, r.threshold) for r in group for x in r.returns[name]]
    done = [c for c in runs if c is not None]
    return (float(np.median(done)) if done else None), len(done), len(runs)


def first_means(group: list[BuildingResult], name: str) -> np.ndarray:
    """Every run's mean return over its first :data:`FIRST` episodes, building by building."""
    return np.concatenate([r.returns[name][:, :FIRST].mean(axis=1) for r in group])


def steps_per_s(group: list[BuildingResult], name: str) -> float:
    """Env steps/s of ``name`` on ``group``: all its runs' steps over their wall time."""
    wall = sum(r.wall_s[name] for r in group)
    return sum(r.steps[name] for r in group) / wall if wall > 0 else float("nan")


def paired_difference(group: list[BuildingResult], a: str, b: str) -> tuple[float, float]:
    """Mean and standard error of ``a`` minus ``b`` in each run's :func:`first_means`, run
    ``r`` against run ``r`` of the same building (same seeds); standard error 0 with one run."""
    diff = first_means(group, a) - first_means(group, b)
    se = diff.std(ddof=1) / np.sqrt(diff.size) if diff.size > 1 else 0.0
    return float(diff.mean()), float(se)


def paired_interval(r: BuildingResult, a: str, b: str) -> tuple[float, float]:
    """:func:`paired_difference` of ``a`` minus ``b`` on one building, with the half-width
    of its 95% t-interval over the runs (0 with one run)."""
    mean, se = paired_difference([r], a, b)
    n = len(r.returns[b])
    return mean, se * float(stdtrit(n - 1, 0.975)) if n > 1 else 0.0


HEADER = ("positions", "seed", "doors", "n_states", "n_actions", "plan_length", "step_limit",
          "r_max", "v_ref", "context_s")
"""A building's figures, as :class:`BuildingResult` names them (saved with every run)."""
SCALE_ARRAYS = ("returns", "success", "steps", "wall_s", "table_mb", *HEADER)
"""What :func:`run_scale_unit` saves of a run (what ``--resume`` checks)."""


def scale_experiments(sizes: list[int], runs: int, episodes: int, seed: int = 0,
                      buildings: int = 2, methods: list[str] | None = None
                      ) -> list[Experiment]:
    """One experiment per building, by size then building seed; bad arguments fail here,
    before anything is written or run."""
    methods = list(methods or DEFAULT_METHODS)
    _check_buildings(seed, buildings)  # before the list of seeds is made
    _check(sizes, runs, episodes, buildings, methods)
    out = []
    for n in sizes:
        for s in range(seed, seed + buildings):
            world = building_world(n, s)  # a WorldError says what is wrong with the size
            out.append(Experiment(building_name(n, s), (("A", episodes),),
                                  methods=tuple(methods), runs=runs, seed=s,
                                  world=f"{BUILDING_PREFIX}{n}:{s}",
                                  hyper=Hyper(gamma=1.0 - 1.0 / world.step_limit)))
    return out


@lru_cache(maxsize=1)  # a process runs the units of one building one after the other
def building_context(world_name: str) -> tuple[dict, tuple]:
    """The building's figures (:data:`HEADER`) and what a run needs: ``(context, env)``."""
    positions, seed = building_of(world_name)
    world = load_world_named(world_name)
    t0 = time.perf_counter()
    ctx = task_context(OfficeInstance.of("A", world=world), darling_tolerance=TOLERANCE,
                       darling_kind="routes")
    context_s = time.perf_counter() - t0
    header = {"positions": positions, "seed": seed, "doors": len(world.doors),
              "n_states": int(ctx.n_states), "n_actions": int(ctx.n_actions),
              "plan_length": int(ctx.plans.length[ctx.s0]),
              "step_limit": int(world.step_limit), "r_max": float(world.r_max),
              "v_ref": float(reference_value(world, "A")), "context_s": context_s}
    return header, (ctx, CompactEnv(task="A", world=world))


_WARMED: set[str] = set()
"""Methods whose compiled episode loop this process has already run once."""


def _warm(exp: Experiment, method: str) -> None:
    """Run ``method``'s compiled loop once in this process (numba loads it then: the time
    of a run does not count it); forked workers inherit it."""
    if method not in _WARMED:
        _, (ctx, env) = building_context(exp.world)
        run_compact(make_learner(method, ctx, exp.hyper), env, 1, np.random.default_rng(0))
        _WARMED.add(method)


def run_scale_unit(unit: Unit) -> dict[str, np.ndarray]:
    """One run (the runner's ``work``): its returns, successes and steps per episode, the
    wall time of its compiled loop, its learner's tables (MB) and the building's figures;
    seeded by ``(building seed, positions, run)`` only (paired runs)."""
    exp = unit.experiment
    positions, seed = building_of(exp.world)
    _warm(exp, unit.method)
    header, (ctx, env) = building_context(exp.world)
    env_seed, learner_seed = np.random.SeedSequence([seed, positions, unit.run]
                                                    ).generate_state(2)
    learner = make_learner(unit.method, ctx, exp.hyper)
    env.reset(seed=int(env_seed))  # after the warm-up: the results do not depend on it
    t1 = time.perf_counter()
    records = run_compact(learner, env, exp.episodes, np.random.default_rng(learner_seed))
    wall = time.perf_counter() - t1
    return {"returns": np.asarray(records.returns, dtype=np.float64),
            "success": np.asarray(records.success, dtype=np.bool_),
            "steps": np.asarray(records.steps, dtype=np.int64), "wall_s": np.float64(wall),
            "table_mb": np.float64(learner.nbytes / 1e6),
            **{k: np.asarray(v) for k, v in header.items()}}


def warm_scale(units: list[Unit]) -> int:
    """Before forking workers: compile every method's loop here on the first unit's
    building; returns the bytes of a learner's tables on the largest building."""
    for method in dict.fromkeys(u.method for u in units):
        _warm(units[0].experiment, method)
    n = max(building_of(u.experiment.world)[0] for u in units)
    return _table_bytes(n)


def check_scale(experiments: list[Experiment], jobs: int) -> None:
    """The runner's check: the runs' records, and ``jobs`` learners' tables on the largest
    building, fit in memory."""
    check_sizes(experiments, jobs)
    n = max(building_of(e.world)[0] for e in experiments)
    check_memory(min(jobs, sum(e.runs * len(e.methods) for e in experiments)) *
                 _table_bytes(n), f"--sizes {n}: a learner's tables at {n:,} positions in "
                 f"each of {jobs} process(es)", "give smaller --sizes or fewer --jobs")


def _table_bytes(n: int) -> int:
    """A learner's tables at ``n`` positions: about 1.25 n states x 5 n actions, 8
    successor slots."""
    return table_bytes(n + n // 4, 5 * n, 8)


def runner_kw() -> dict:
    """What :func:`~gdq_pddl.experiments.runner.run_experiments` needs to run scale
    experiments besides them (read at call time: tests replace :func:`run_scale_unit`)."""
    return {"work": run_scale_unit, "collect": collect_scale, "unit_arrays": SCALE_ARRAYS,
            "check": check_scale, "warm": warm_scale}


def collect_scale(out: Path, experiments: list[Experiment]) -> None:
    """Write ``building-N-sS.npz`` of every building from ``out/units``."""
    for exp in experiments:
        save_building(assemble(out, exp), out / f"{exp.name}.npz")


def assemble(out: Path, exp: Experiment) -> BuildingResult:
    """A building's :class:`BuildingResult` from its saved units (its figures: the first
    run's, so a resumed report is the same)."""
    units = {(u.method, u.run): read_unit(out, u, SCALE_ARRAYS) for u in exp.units()}
    first = units[exp.methods[0], 0]
    result = BuildingResult(**{k: first[k].item() for k in HEADER})
    for name in exp.methods:
        done = [units[name, run] for run in range(exp.runs)]
        result.returns[name] = np.stack([u["returns"] for u in done])
        result.success[name] = np.stack([u["success"] for u in done]).astype(np.bool_)
        result.steps[name] = sum(int(u["steps"].sum()) for u in done)
        result.wall_s[name] = sum(float(u["wall_s"]) for u in done)
        result.table_mb[name] = float(done[-1]["table_mb"])
    return result


def save_building(result: BuildingResult, path) -> None:
    """Write the returns and successes of every method on one building (keys
    ``returns/<method>``, ``success/<method>``) and the building's figures."""
    save_unit(Path(path), {"positions": result.positions, "seed": result.seed,
                           "v_ref": result.v_ref, "r_fail": result.r_fail,
                           "threshold": result.threshold,
                           **{f"returns/{k}": v for k, v in result.returns.items()},
                           **{f"success/{k}": v for k, v in result.success.items()}},
              compressed=True)


def run_scale(out: Path, sizes: list[int], runs: int, episodes: int, seed: int = 0,
              buildings: int = 2, methods: list[str] | None = None, resume: bool = False,
              progress: bool = True, jobs: int | None = 1, executor: str = "local",
              address: str | None = None) -> list[BuildingResult]:
    """Run every building of every size into ``out`` (the experiment runner: ``jobs``
    processes, or Ray; ``resume`` goes on with a stopped run) and return their results,
    by size then seed."""
    experiments = scale_experiments(sizes, runs, episodes, seed, buildings, methods)
    run_experiments(experiments, out, jobs=jobs, executor=executor, address=address,
                    resume=resume, progress=progress, **runner_kw())
    return [assemble(Path(out), e) for e in experiments]


def _check_buildings(seed: int, buildings: int) -> None:
    """``--buildings`` in ``[1, MAX_BUILDINGS]`` and the last building seed in range."""
    check_count("seed", seed)
    whole = isinstance(buildings, numbers.Integral) and not isinstance(buildings, bool)
    if not whole or not 1 <= buildings <= MAX_BUILDINGS:
        raise GdqError(f"--buildings {buildings!r}: must be 1 to {MAX_BUILDINGS:,} per size "
                       "(each building is a marker of scale.png and a row of every table "
                       "of REPORT.md)")
    check_count("the last building seed (--seed + --buildings - 1)", seed + buildings - 1)


def _check(sizes: list[int], runs: int, episodes: int, buildings: int,
           methods: list[str]) -> None:
    """Bad arguments fail before anything is written or run."""
    check_count("runs", runs)
    check_count("episodes", episodes)
    if runs < 1 or episodes < 1:
        raise GdqError("--runs and --episodes must be at least 1")
    check_memory(episodes * EPISODE_BYTES, f"--episodes {episodes:,}", "give fewer --episodes")
    # every run's returns and successes are held until the report
    n_buildings = len(sizes) * buildings
    check_memory(n_buildings * len(methods) * runs * (episodes * 9 * 2 + UNIT_BYTES),
                 f"--runs {runs:,} x --episodes {episodes:,} x {len(methods)} methods x "
                 f"{n_buildings:,} buildings", "give fewer --runs or --buildings")
    if not sizes or len(set(sizes)) != len(sizes):
        raise GdqError(f"--sizes must be one or more different sizes, got {list(sizes)}")
    for m in map(parse_method, methods):  # a deep-RL agent: no tables, no loop to time
        if hasattr(m.entry.learner_class(), "run_own_episodes"):
            raise ConfigError(f"method {m.text} cannot run in scale, which times tabular "
                              "learners' compiled loops on generated buildings: it runs its "
                              "own episodes (compare it with `gdq-pddl run`)")
    for n in sizes:
        check_memory(_table_bytes(n), f"--sizes {n}: a learner's tables at {n:,} positions",
                     "give smaller --sizes")
