"""Learning against building size (``gdq-pddl scale``): every method on generated buildings.

For each size N and each building seed ``S = seed, seed + 1, ...``, task A of the building
of ``gdq-pddl building --positions N --seed S``: each method runs ``runs`` times for
``episodes`` episodes over the compact model (:mod:`gdq_pddl.envs.compact`), run ``r``
seeded by ``(S, N, r)`` only (paired runs, the same whether or not resumed).
:func:`run_scale` writes::

    config.json           sizes, buildings, runs, episodes, seed, methods, package versions
    units/building-N-sS/building.json     the building, learner tables, plan-table time
    units/building-N-sS/<method>-<run>.npz   one finished run, written atomically
    building-N-sS.npz     every run on that building (:func:`save_building`)

The measures and why: ``docs/decisions.md``, "Generated buildings".
"""

from __future__ import annotations

import json
import numbers
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from itertools import groupby
from pathlib import Path

import numpy as np
import scipy.stats as sps
from tqdm import tqdm

from gdq_pddl.buildings import building_world, generate
from gdq_pddl.envs.office import CompactEnv, OfficeInstance
from gdq_pddl.envs.solve_compact import reference_value
from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.checks import EPISODE_BYTES, UNIT_BYTES
from gdq_pddl.experiments.folder import (
    FolderLock,
    ResultsError,
    load_unit,
    read_config,
    resume_config,
)
from gdq_pddl.experiments.interrupts import RunInterrupted
from gdq_pddl.experiments.protocol import SCALE_DEFAULT_METHODS as DEFAULT_METHODS
from gdq_pddl.experiments.protocol import safe_name
from gdq_pddl.experiments.runner import atomic_write, save_unit, versions
from gdq_pddl.learners import make_learner, registry
from gdq_pddl.learners.context import task_context
from gdq_pddl.learners.episodes import run_compact
from gdq_pddl.learners.tables import table_bytes
from gdq_pddl.limits import check_count, check_memory
from gdq_pddl.outputs import output_folder

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
    return mean, se * float(sps.t.ppf(0.975, n - 1)) if n > 1 else 0.0


def building_context(positions: int, seed: int) -> tuple[dict, tuple]:
    """The building's description and what a run needs: ``(world, context, env)``."""
    world = building_world(positions, seed)
    t0 = time.perf_counter()
    ctx = task_context(OfficeInstance.of("A", world=world), darling_tolerance=TOLERANCE,
                       darling_kind="routes")
    context_s = time.perf_counter() - t0
    env = CompactEnv(task="A", world=world)
    header = {"positions": positions, "seed": seed, "doors": len(world.doors),
              "n_states": int(ctx.n_states), "n_actions": int(ctx.n_actions),
              "plan_length": int(ctx.plans.length[ctx.s0]),
              "step_limit": int(world.step_limit), "r_max": float(world.r_max),
              "v_ref": float(reference_value(world, "A")), "context_s": context_s}
    return header, (world, ctx, env)


_WARMED: set[str] = set()
"""Methods whose compiled episode loop this process has already run once."""


def run_one(setting: tuple, name: str, key: tuple[int, int, int],
            episodes: int) -> dict[str, np.ndarray]:
    """The arrays of one run of method ``name`` in ``setting`` (:func:`building_context`),
    seeded by ``key = (building seed, positions, run)`` only (paired runs)."""
    world, ctx, env = setting
    env_seed, learner_seed = np.random.SeedSequence(list(key)).generate_state(2)
    gamma = 1.0 - 1.0 / world.step_limit
    if name not in _WARMED:  # numba loads the compiled loop on first use: not timed
        run_compact(make_learner(name, ctx, defaults={"gamma": gamma}), env, 1,
                    np.random.default_rng(0))
        _WARMED.add(name)
    learner = make_learner(name, ctx, defaults={"gamma": gamma})
    env.reset(seed=int(env_seed))  # after the warm-up: the results do not depend on it
    t1 = time.perf_counter()
    records = run_compact(learner, env, episodes, np.random.default_rng(learner_seed))
    wall = time.perf_counter() - t1
    return {"returns": np.asarray(records.returns, dtype=np.float64),
            "success": np.asarray(records.success, dtype=np.bool_),
            "steps": np.int64(records.steps.sum()), "wall_s": np.float64(wall),
            "table_mb": np.float64(learner.nbytes / 1e6)}


def assemble(header: dict, units: dict[tuple[str, int], dict], methods: list[str],
             runs: int, log: Callable[[str], None]) -> BuildingResult:
    """A building's :class:`BuildingResult` from its description and its units."""
    out = BuildingResult(**header)
    for name in methods:
        done = [units[name, run] for run in range(runs)]
        out.returns[name] = np.stack([u["returns"] for u in done])
        out.success[name] = np.stack([u["success"] for u in done]).astype(np.bool_)
        out.steps[name] = sum(int(u["steps"]) for u in done)
        out.wall_s[name] = sum(float(u["wall_s"]) for u in done)
        out.table_mb[name] = float(done[-1]["table_mb"])
        log(f"  {name}: {steps_per_s([out], name):,.0f} steps/s, tables "
            f"{out.table_mb[name]:,.0f} MB, converged at "
            f"{[converged_at(x, out.threshold) for x in out.returns[name]]}")
    return out


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
              progress: bool = True, log: Callable[[str], None] | None = None,
              command: str | None = None) -> list[BuildingResult]:
    """Run every building of every size into ``out`` and return their results, by size then
    seed; Ctrl-C raises :class:`RunInterrupted` naming ``command`` (with ``--resume``)."""
    log = log or tqdm.write  # clears the progress bar, writes, draws it again
    methods = list(methods or DEFAULT_METHODS)
    _check_buildings(seed, buildings)  # before the list of seeds is made
    seeds = list(range(seed, seed + buildings))
    _check(sizes, runs, episodes, seeds, methods)
    out = output_folder(out)
    rerun = command or "the same command and --resume"
    with FolderLock(out):
        _prepare(out, {"sizes": list(sizes), "buildings": buildings, "runs": runs,
                       "episodes": episodes, "seed": seed, "methods": methods}, resume)
        results = []
        try:
            for n in sizes:
                for s in seeds:
                    results.append(_building_into(out, n, s, runs, episodes, methods,
                                                  progress, log, rerun))
                    save_building(results[-1], out / f"{results[-1].name}.npz")
        except KeyboardInterrupt:
            done = len(list((out / "units").glob("building-*/*.npz")))
            total = len(sizes) * buildings * len(methods) * runs
            raise RunInterrupted(f"interrupted: {done} of {total} runs are saved in {out}; "
                                 f"continue with: {rerun}") from None
        except Exception:
            if not resume and not any((out / "units").glob("building-*/*.npz")):
                (out / "config.json").unlink(missing_ok=True)  # nothing saved: no blocker
            raise
    return results


def _check_buildings(seed: int, buildings: int) -> None:
    """``--buildings`` in ``[1, MAX_BUILDINGS]`` and the last building seed in range."""
    check_count("seed", seed)
    whole = isinstance(buildings, numbers.Integral) and not isinstance(buildings, bool)
    if not whole or not 1 <= buildings <= MAX_BUILDINGS:
        raise GdqError(f"--buildings {buildings!r}: must be 1 to {MAX_BUILDINGS:,} per size "
                       "(each building is a marker of scale.png and a row of every table "
                       "of REPORT.md)")
    check_count("the last building seed (--seed + --buildings - 1)", seed + buildings - 1)


def _check(sizes: list[int], runs: int, episodes: int, seeds: list[int],
           methods: list[str]) -> None:
    """Bad arguments fail before anything is written or run."""
    check_count("runs", runs)
    check_count("episodes", episodes)
    if runs < 1 or episodes < 1:
        raise GdqError("--runs and --episodes must be at least 1")
    check_memory(episodes * EPISODE_BYTES, f"--episodes {episodes:,}", "give fewer --episodes")
    # every run's returns and successes are held until the report
    n_buildings = len(sizes) * len(seeds)
    check_memory(n_buildings * len(methods) * runs * (episodes * 9 * 2 + UNIT_BYTES),
                 f"--runs {runs:,} x --episodes {episodes:,} x {len(methods)} methods x "
                 f"{n_buildings:,} buildings", "give fewer --runs or --buildings")
    if not sizes or len(set(sizes)) != len(sizes):
        raise GdqError(f"--sizes must be one or more different sizes, got {list(sizes)}")
    canonical = [registry.canonical(m) for m in methods]  # a ConfigError if unknown
    if canonical != list(methods) or len(set(methods)) != len(methods):
        raise GdqError(f"methods must be different ones of {', '.join(registry.names())} "
                       f"(with settings, as registry.canonical writes them), got {methods}")
    for n in sizes:
        # a learner's tables: about 1.25 n states x 5 n actions, 8 successor slots
        check_memory(table_bytes(n + n // 4, 5 * n, 8), f"--sizes {n}: a learner's tables "
                     f"at {n:,} positions", "give smaller --sizes")
        for s in seeds:
            generate(n, s)  # a WorldError says what is wrong with the size


def _prepare(out: Path, config: dict, resume: bool) -> None:
    """Check ``out`` against ``config`` (see :func:`resume_config`); write ``config.json``."""
    cfg_path = out / "config.json"
    held = cfg_path.exists() or (out / "units").exists() or any(out.glob("building-*.npz"))
    old = resume_config(out, held, resume, "units/ or building-*.npz")
    if old is not None:
        differ = [f"{k} {old.get(k)} there, {v} now" for k, v in config.items()
                  if old.get(k) != v]
        if differ:
            grown = [k for k in ("sizes", "buildings", "methods") if old.get(k) != config[k]]
            hint = (f"; --resume cannot add or drop {', '.join(grown)}: run them into "
                    "another --out" if grown else "")
            raise ResultsError(f"{out} holds results of a different configuration "
                               f"({'; '.join(differ)}): --resume needs the same command "
                               f"line{hint}")
    # what a write killed midway left (never a unit file: those appear by atomic rename)
    for stale in out.glob("**/.*.tmp"):
        stale.unlink(missing_ok=True)
    if old is not None:  # keep the record of the run being continued (its versions, start)
        return
    config = config | {"versions": versions(), "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    atomic_write(cfg_path, lambda tmp: tmp.write_text(json.dumps(config, indent=2)))


def _read_header(path: Path, rerun: str) -> dict:
    """A building's ``building.json``; :class:`ResultsError` naming it if it is damaged."""
    header = read_config(path)
    missing = [k for k in ("positions", "doors", "n_states", "n_actions", "plan_length",
                           "step_limit", "r_max", "v_ref", "context_s") if k not in header]
    if missing:
        raise ResultsError(f"{path} is damaged (no {missing[0]!r}): delete it and run "
                           f"{rerun} to measure the building again")
    return header


def _building_into(out: Path, n: int, seed: int, runs: int, episodes: int, methods: list[str],
                   progress: bool, log: Callable[[str], None], rerun: str) -> BuildingResult:
    """Run the missing units of building ``(n, seed)``, then read them all."""
    name = building_name(n, seed)
    folder = out / "units" / name
    paths = {(m, run): folder / f"{safe_name(m)}-{run}.npz" for m in methods
             for run in range(runs)}
    missing = [key for key, path in paths.items() if not path.exists()]
    header_path = folder / "building.json"
    bar = tqdm(total=len(paths), initial=len(paths) - len(missing), unit="run", desc=name,
               dynamic_ncols=True, disable=not progress or not sys.stderr.isatty())
    try:
        header = _read_header(header_path, rerun) if header_path.exists() else None
        if missing or header is None:
            built, setting = building_context(n, seed)
            if header is None:  # the first measurement stays, so a resumed report is the same
                header = built
                atomic_write(header_path, lambda tmp: tmp.write_text(json.dumps(header)))
        log(f"{name}: {header['doors']} doors, {header['n_states']} states x "
            f"{header['n_actions']} actions, L = {header['plan_length']}, V_ref = "
            f"{header['v_ref']:.1f}, plans for every state in {header['context_s']:.1f} s")
        for m, run in missing:
            save_unit(paths[m, run], run_one(setting, m, (seed, n, run), episodes))
            bar.update(1)
    finally:
        bar.close()
    expect = {"returns": episodes, "success": episodes, "steps": -1, "wall_s": -1,
              "table_mb": -1}
    units = {(m, run): load_unit(path, f"{m}, run {run} of {name}", expect, rerun)
             for (m, run), path in paths.items()}
    return assemble(header, units, methods, runs, log)
