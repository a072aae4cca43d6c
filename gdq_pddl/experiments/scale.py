"""Learning against building size: every method on generated buildings of N positions.

For each size N (default 100, 300, 1000) the building of ``gdq-pddl building
--positions N --seed S`` and its task A (start and goal in rooms far apart), each method
runs ``runs`` times for ``episodes`` episodes over the compact model
(:mod:`gdq_pddl.envs.compact`; the full-state model would need ``2**n_doors`` states).
Seeds come from ``(seed, N, method index, run)`` only, so a run gives the same returns
whether it ran straight through or was interrupted and resumed.

:func:`run_scale` (``gdq-pddl scale``) writes to its output folder, as the office
runner (:mod:`gdq_pddl.experiments.runner`) does::

    config.json           sizes, runs, episodes, seed, methods and package versions
    units/size-N/size.json    the building, learner tables and plan-table time of size N
    units/size-N/<method>-<run>.npz
                          one finished run, written atomically as soon as it is done:
                          returns, success (per episode), steps, wall_s, table_mb
    size-N.npz            every run of size N (:func:`save_size`), once its units are done
    scale.png/pdf, REPORT.md  at the end, from the units

An interrupted run (Ctrl-C, or killed) loses at most the run in flight; ``--resume``
checks that the configuration is the same and runs only the missing units (it cannot add
sizes: those go into another folder). Env steps/s are the saved runs' steps over their
wall time, so a resumed run's size files, figure and report are made the same way.

Decisions, where the office protocol does not carry over:

- **Reference value** ``V_ref``: the pessimistic value iteration of
  :func:`gdq_pddl.envs.solve_compact.reference_value`, a proven lower bound on V* (equal
  to it on the office), since V* itself needs ``2**n_doors`` door masks. The worst
  return is ``R_fail = -r_max - (step_limit - 1)`` (a timeout).
- **Discount** ``gamma = 1 - 1 / step_limit`` (the office: 0.95 = 1 - 1/20). With the
  office's 0.95, a goal 65 actions away is worth 0.95**65 x r_max, about 2, less than the
  step costs on the way: no learner would go for it.
- **Episodes to convergence**: the first episode at which the trailing 50-episode moving
  average of the return reaches ``R_fail + 0.9 (V_ref - R_fail)`` (nine tenths of the
  way from the worst return to the reference), the issue's own measure for the office
  ("the 50-episode moving average first turned positive at episode ~84"); a run that
  never gets there counts as not converged (``> episodes``). Not "stays above it to the
  end": episodes succeed or time out (returns ~300 apart at 1000 positions), so the
  average of a learner that has settled varies by +-20 and dips under any threshold
  near its level again and again (measured: under that rule DARLING at 300 positions
  "converged" at episodes 4764-4994 of 5000, whatever it did before).
- **Door-route plans** for DARLING and GDQ-code: tolerance 1.3 x as on the office, but
  the table holds every shortest plan plus the shortest plan through each door that a
  plan within 1.3 x can cross (:func:`gdq_pddl.abstraction.routes.route_plan_table`),
  not every plan within 1.3 x: at 300 positions one query for those takes seconds and
  returns thousands of plans, at 1000 about 100 s and 7000 plans, for each of ~1100
  learner states, and nearly all of them differ only inside rooms and corridors. The
  detour round the jammed door of the task is in the table; with shortest plans only,
  it is not, and neither method can learn it (measured before this choice: 0 of 2 runs
  of GDQ-code reached the goal once in 1000 episodes at 100 positions).
- **Memory**: a learner keeps, per (state, action) pair, its Q value and the model's
  visit and cost statistics (50 bytes), and GDQ and Dyna-Q ``max_successors`` slots of
  8 bytes for the transitions (the sparse model of :mod:`gdq_pddl.learners.core`; at
  1000 positions the compact model bounds a pair's distinct next states by 8). At 1000
  positions, 1250 states x 5000 actions, a learner allocates 0.3 GB (Q-learning,
  DARLING) or 0.7 GB (GDQ, Dyna-Q; ``table_mb``), of which only the pages of the pairs
  it tries are written: 160 MB or less after 200 episodes (measured). No size is
  skipped.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gdq_pddl.buildings import building_world, generate
from gdq_pddl.envs.compact import CompactEnv
from gdq_pddl.envs.solve_compact import reference_value
from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.folder import FolderLock, ResultsError, load_unit, read_config
from gdq_pddl.experiments.runner import RunInterrupted, atomic_write, save_unit, versions
from gdq_pddl.learners import make_learner, office_task_context
from gdq_pddl.learners.compact_runner import run_compact
from gdq_pddl.limits import check_count, check_memory
from gdq_pddl.outputs import output_folder

METHODS: dict[str, tuple[str, dict]] = {
    "GDQ": ("gdq", {}),
    "GDQ-literal": ("gdq", {"variant": "literal"}),
    "GDQ-code": ("gdq", {"variant": "code", "plan_tolerance": 0.3}),
    "DARLING": ("darling", {"tolerance": 0.3}),
    "Dyna-Q": ("dynaq", {}),
    "Q-learning": ("qlearning", {}),
}
WINDOW = 50
FRACTION = 0.9
TOLERANCE = 0.3


@dataclass
class SizeResult:
    """Everything measured at one building size."""

    positions: int
    doors: int
    n_states: int
    n_actions: int
    plan_length: int
    step_limit: int
    r_max: float
    v_ref: float
    """The task's reference value (a lower bound on V*)."""
    context_s: float
    returns: dict[str, np.ndarray] = field(default_factory=dict)  # runs x episodes
    success: dict[str, np.ndarray] = field(default_factory=dict)  # runs x episodes, bool
    steps_per_s: dict[str, float] = field(default_factory=dict)
    table_mb: dict[str, float] = field(default_factory=dict)
    """Memory one learner allocates (``TabularLearner.nbytes``), in MB."""
    skipped: dict[str, str] = field(default_factory=dict)
    """Methods not run, with why (none since the learners' model is sparse)."""

    @property
    def r_fail(self) -> float:
        """The worst return: a timeout."""
        return -self.r_max - (self.step_limit - 1)

    @property
    def threshold(self) -> float:
        """The moving average a converged run stays at or above."""
        return self.r_fail + FRACTION * (self.v_ref - self.r_fail)

    def converged(self, name: str) -> list[int | None]:
        """Episodes to convergence of each run of ``name``."""
        return [converged_at(r, self.threshold) for r in self.returns[name]]


def converged_at(returns: np.ndarray, threshold: float, window: int = WINDOW) -> int | None:
    """Episodes to convergence of one run (see the module docstring), or None."""
    if len(returns) < window:
        return None
    avg = np.convolve(returns, np.ones(window) / window, mode="valid")
    hit = np.flatnonzero(avg >= threshold)
    return int(hit[0] + window) if len(hit) else None


def size_context(positions: int, seed: int) -> tuple[dict, tuple]:
    """The building of ``positions`` positions, its task context and env (what a run
    needs), and the size's description: the first fields of :class:`SizeResult`, JSON-able.
    """
    world = building_world(positions, seed)
    t0 = time.perf_counter()
    ctx = office_task_context(world, "A", darling_tolerance=TOLERANCE, darling_kind="routes")
    context_s = time.perf_counter() - t0
    env = CompactEnv(task="A", world=world)
    header = {"positions": positions, "doors": len(world.doors), "n_states": int(ctx.n_states),
              "n_actions": int(ctx.n_actions), "plan_length": int(ctx.plans.length[ctx.s0]),
              "step_limit": int(world.step_limit), "r_max": float(world.r_max),
              "v_ref": float(reference_value(world, "A")), "context_s": context_s}
    return header, (world, ctx, env)


def describe(header: dict) -> str:
    """One line about a size (its building, learner tables and plans)."""
    return (f"{header['positions']} positions: {header['doors']} doors, {header['n_states']} "
            f"states x {header['n_actions']} actions, L = {header['plan_length']}, "
            f"V_ref = {header['v_ref']:.1f}, plans for every state in "
            f"{header['context_s']:.1f} s")


_WARMED: set[str] = set()
"""Methods whose compiled episode loop this process has already run once."""


def run_one(setting: tuple, name: str, key: tuple[int, int, int, int],
            episodes: int) -> dict[str, np.ndarray]:
    """One run of method ``name`` in ``setting`` (from :func:`size_context`), seeded by
    ``key = (seed, positions, method index, run)`` only: the arrays of a unit file."""
    world, ctx, env = setting
    method, config = METHODS[name]
    env_seed, learner_seed = np.random.SeedSequence(list(key)).generate_state(2)
    gamma = 1.0 - 1.0 / world.step_limit
    if name not in _WARMED:  # numba loads the compiled loop on first use: not timed
        run_compact(make_learner(method, ctx, gamma=gamma, **config), env, 1,
                    np.random.default_rng(0))
        _WARMED.add(name)
    learner = make_learner(method, ctx, gamma=gamma, **config)
    env.reset(seed=int(env_seed))  # after the warm-up: the results do not depend on it
    t1 = time.perf_counter()
    records = run_compact(learner, env, episodes, np.random.default_rng(learner_seed))
    wall = time.perf_counter() - t1
    return {"returns": np.asarray(records.returns, dtype=np.float64),
            "success": np.asarray(records.success, dtype=np.bool_),
            "steps": np.int64(records.steps.sum()), "wall_s": np.float64(wall),
            "table_mb": np.float64(learner.nbytes / 1e6)}


def assemble(header: dict, units: dict[tuple[str, int], dict], methods: list[str],
             runs: int) -> SizeResult:
    """A size's :class:`SizeResult` from its description and its (method, run) units;
    env steps/s of a method is its runs' steps over their wall time."""
    out = SizeResult(**header)
    for name in methods:
        done = [units[name, run] for run in range(runs)]
        out.returns[name] = np.stack([u["returns"] for u in done])
        out.success[name] = np.stack([u["success"] for u in done]).astype(np.bool_)
        steps = sum(int(u["steps"]) for u in done)
        wall = sum(float(u["wall_s"]) for u in done)
        out.steps_per_s[name] = steps / wall if wall > 0 else float("nan")
        out.table_mb[name] = float(done[-1]["table_mb"])
    return out


def summary(result: SizeResult) -> list[str]:
    """One line per method: env steps/s, table size, episodes to convergence."""
    return [f"  {name}: {result.steps_per_s[name]:,.0f} steps/s, tables "
            f"{result.table_mb[name]:,.0f} MB, converged at {result.converged(name)}"
            for name in result.returns]


def run_size(positions: int, runs: int, episodes: int, seed: int = 0,
             methods: list[str] | None = None, log=print) -> SizeResult:
    """Run every method at one size in memory (see the module docstring; nothing saved:
    :func:`run_scale` saves each run as it finishes)."""
    methods = list(methods or METHODS)
    header, setting = size_context(positions, seed)
    log(describe(header))
    units = {(name, run): run_one(setting, name, (seed, positions, mi, run), episodes)
             for mi, name in enumerate(methods) for run in range(runs)}
    result = assemble(header, units, methods, runs)
    for line in summary(result):
        log(line)
    return result


def save_size(result: SizeResult, path) -> None:
    """The raw returns and successes of every method at one size, with the size's
    figures (``numpy.load`` reads it; keys ``returns/<method>``, ``success/<method>``).
    Written atomically."""
    arrays = {f"returns/{k}": v for k, v in result.returns.items()}
    arrays |= {f"success/{k}": v for k, v in result.success.items()}

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, positions=result.positions, v_ref=result.v_ref,
                                r_fail=result.r_fail, threshold=result.threshold, **arrays)

    atomic_write(Path(path), write)


def run_scale(out: Path, sizes: list[int], runs: int, episodes: int, seed: int = 0,
              methods: list[str] | None = None, resume: bool = False, progress: bool = True,
              log: Callable[[str], None] | None = None,
              command: str | None = None) -> list[SizeResult]:
    """Run every size into ``out``, each (size, method, run) saved as it finishes; then
    ``size-N.npz``, ``scale.png/pdf`` and ``REPORT.md`` from the saved runs.

    ``resume=True`` checks that ``out/config.json`` holds the same configuration and
    runs only the missing units. On Ctrl-C raises :class:`RunInterrupted`, whose message
    says how to continue (``command``, the command line with ``--resume``).
    """
    from tqdm import tqdm

    log = log or tqdm.write  # clears the progress bar, writes, draws it again
    methods = list(methods or METHODS)
    _check(sizes, runs, episodes, seed, methods)
    out = output_folder(out)
    rerun = command or "the same command and --resume"
    with FolderLock(out):
        _prepare(out, {"sizes": list(sizes), "runs": runs, "episodes": episodes, "seed": seed,
                       "methods": methods}, resume)
        results = []
        try:
            for n in sizes:
                results.append(_size_into(out, n, runs, episodes, seed, methods, progress, log,
                                          rerun))
                save_size(results[-1], out / f"size-{n}.npz")
            from gdq_pddl.analysis.scale import figure, report

            figure(results, episodes, out)
            report(results, runs, episodes, seed, out)
        except KeyboardInterrupt:
            done = len(list((out / "units").glob("size-*/*.npz")))
            total = len(sizes) * len(methods) * runs
            raise RunInterrupted(f"interrupted: {done} of {total} runs are saved in {out}; "
                                 f"continue with: {rerun}") from None
        except Exception:
            if not resume and not any((out / "units").glob("size-*/*.npz")):
                (out / "config.json").unlink(missing_ok=True)  # nothing saved: no blocker
            raise
    return results


def _check(sizes: list[int], runs: int, episodes: int, seed: int, methods: list[str]) -> None:
    """Bad arguments fail before anything is written or run."""
    from gdq_pddl.experiments.checks import EPISODE_BYTES, UNIT_BYTES
    from gdq_pddl.learners.core import table_bytes

    check_count("runs", runs)
    check_count("episodes", episodes)
    check_count("seed", seed)
    if runs < 1 or episodes < 1:
        raise GdqError("--runs and --episodes must be at least 1")
    check_memory(episodes * EPISODE_BYTES, f"--episodes {episodes:,}", "give fewer --episodes")
    # a size's returns and successes of every run of every method are held together
    check_memory(len(methods) * runs * (episodes * 9 * 2 + UNIT_BYTES), f"--runs {runs:,} x "
                 f"--episodes {episodes:,} x {len(methods)} methods", "give fewer --runs")
    if not sizes or len(set(sizes)) != len(sizes):
        raise GdqError(f"--sizes must be one or more different sizes, got {list(sizes)}")
    unknown = [m for m in methods if m not in METHODS]
    if unknown or len(set(methods)) != len(methods):
        raise GdqError(f"methods must be different ones of {', '.join(METHODS)}, got {methods}")
    for n in sizes:
        # a learner's tables: about 1.25 n states x 5 n actions, 8 successor slots
        check_memory(table_bytes(n + n // 4, 5 * n, 8), f"--sizes {n}: a learner's tables "
                     f"at {n:,} positions", "give smaller --sizes")
        generate(n, seed)  # a WorldError says what is wrong with the size


def _prepare(out: Path, config: dict, resume: bool) -> None:
    """Refuse a folder that holds results (without --resume) or other results (with it);
    remove what a killed write left; write ``config.json``."""
    cfg_path = out / "config.json"
    held = cfg_path.exists() or (out / "units").exists() or any(out.glob("size-*.npz"))
    if held and not resume:
        raise ResultsError(f"{out} holds results: continue them with --resume, "
                           "or choose another --out")
    if resume and not held:
        raise ResultsError(f"--resume: {out} holds no run to continue (no config.json "
                           "there); to start one, give the same command without --resume")
    if held:
        if not cfg_path.exists():
            raise ResultsError(f"{out}: config.json is missing, cannot check what to resume")
        old = read_config(cfg_path)
        differ = [f"{k} {old.get(k)} there, {v} now" for k, v in config.items()
                  if old.get(k) != v]
        if differ:
            hint = ("; --resume cannot add or drop sizes: run other sizes into another --out"
                    if old.get("sizes") != config["sizes"] else "")
            raise ResultsError(f"{out} holds results of a different configuration "
                               f"({'; '.join(differ)}): --resume needs the same command "
                               f"line{hint}")
    # a run killed in the middle of a write leaves its temporary file (never a unit file:
    # those appear only by an atomic rename)
    for stale in out.glob("**/.*.tmp"):
        stale.unlink(missing_ok=True)
    if held:  # keep the record of the run being continued (its versions, its start)
        return
    config = config | {"versions": versions(), "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    atomic_write(cfg_path, lambda tmp: tmp.write_text(json.dumps(config, indent=2)))


def _read_header(path: Path, rerun: str) -> dict:
    """A size's ``size.json``; :class:`ResultsError` naming it if it is damaged."""
    header = read_config(path)
    missing = [k for k in ("positions", "doors", "n_states", "n_actions", "plan_length",
                           "step_limit", "r_max", "v_ref", "context_s") if k not in header]
    if missing:
        raise ResultsError(f"{path} is damaged (no {missing[0]!r}): delete it and run "
                           f"{rerun} to measure the size again")
    return header


def _size_into(out: Path, n: int, runs: int, episodes: int, seed: int, methods: list[str],
               progress: bool, log: Callable[[str], None], rerun: str) -> SizeResult:
    """Run the units of size ``n`` missing in ``out/units/size-N/``, then read them all."""
    from tqdm import tqdm

    folder = out / "units" / f"size-{n}"
    paths = {(name, run): folder / f"{name}-{run}.npz" for name in methods for run in range(runs)}
    missing = [key for key, path in paths.items() if not path.exists()]
    header_path = folder / "size.json"
    bar = tqdm(total=len(paths), initial=len(paths) - len(missing), unit="run",
               desc=f"{n} positions", dynamic_ncols=True,
               disable=not progress or not sys.stderr.isatty())
    try:
        header = _read_header(header_path, rerun) if header_path.exists() else None
        if missing or header is None:
            built, setting = size_context(n, seed)
            if header is None:  # the first measurement stays, so a resumed report is the same
                header = built
                atomic_write(header_path, lambda tmp: tmp.write_text(json.dumps(header)))
        log(describe(header))
        for name, run in missing:
            unit = run_one(setting, name, (seed, n, methods.index(name), run), episodes)
            save_unit(paths[name, run], unit)
            bar.update(1)
    finally:
        bar.close()
    expect = {"returns": episodes, "success": episodes, "steps": -1, "wall_s": -1,
              "table_mb": -1}
    units = {(name, run): load_unit(path, f"{name}, run {run} at {n} positions", expect, rerun)
             for (name, run), path in paths.items()}
    result = assemble(header, units, methods, runs)
    for line in summary(result):
        log(line)
    return result
