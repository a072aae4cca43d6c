"""Every ordered (start, goal) pair of a world: ``gdq-pddl pairs``.

Each pair is one :class:`~gdq_pddl.experiments.protocol.Experiment` named ``pairs`` with
schedule ``(("p3->p13", episodes),)``, run by the runner with its own ``work`` and
``collect``::

    config.json   the experiments (one per pair), seeds and package versions
    units/*.npz   one (pair, method, run): ``returns`` (float64), ``success`` (bool)
    runs.csv      :data:`RUN_COLUMNS`: each run's mean return and success rate (``repr``)
    optimal.json  per pair: start, goal, shortest plan length, V*, its tuning task (A-D)
"""

from __future__ import annotations

import csv
import json
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.folder import read_unit
from gdq_pddl.experiments.protocol import Experiment, Unit
from gdq_pddl.experiments.results import load_config
from gdq_pddl.experiments.work import load_world_named, resolve_task, run_unit
from gdq_pddl.learners import registry
from gdq_pddl.outputs import atomic_write
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import WorldError
from gdq_pddl.world_types import World

PAIRS_EXPERIMENT = "pairs"
"""The name of every experiment of a pairs folder."""
TUNING_TASKS = ("A", "B", "C", "D")
"""The tasks every setting was chosen on; their pairs are marked in the table."""
RUN_COLUMNS = ("pair", "start", "goal", "method", "run", "episodes", "mean_return",
               "success_rate")


def pair_spec(start: str, goal: str) -> str:
    return f"{start}->{goal}"


def all_pairs(world: World) -> list[str]:
    """Every ordered pair of distinct positions, starts and goals in the world's order."""
    return [pair_spec(s, g) for s in world.positions for g in world.positions if s != g]


def parse_pairs(world: World, items: Sequence[str]) -> list[str]:
    """``--pairs`` items (``START->GOAL`` separated by spaces or commas) as canonical specs
    in :func:`all_pairs`'s order; GdqError naming a bad item."""
    found = set()
    for item in (w for text in items for w in re.split(r"[\s,]+", text) if w):
        start, sep, goal = item.partition("->")
        if not (sep and start and goal):
            raise GdqError(f"--pairs: {item!r} is not START->GOAL (e.g. p3->p13)")
        try:
            s, g = world.position(start), world.position(goal)
        except WorldError as exc:
            raise GdqError(f"--pairs: {item}: {exc}") from None
        if s == g:
            raise GdqError(f"--pairs: {item}: start and goal are the same position ({s})")
        found.add(pair_spec(s, g))
    if not found:
        raise GdqError("--pairs: no pair given")
    return [p for p in all_pairs(world) if p in found]


def sample_pairs(world: World, k: int, seed: int) -> list[str]:
    """``k`` pairs drawn without replacement (``default_rng(seed)``), in canonical order."""
    pairs = all_pairs(world)
    if not 1 <= k <= len(pairs):
        raise GdqError(f"--sample: {k} is not between 1 and {len(pairs)} (the ordered pairs "
                       f"of {world.source})")
    chosen = np.random.default_rng(seed).choice(len(pairs), size=k, replace=False)
    return [pairs[i] for i in np.sort(chosen)]


def pair_experiments(pairs: Sequence[str], episodes: int, **kw) -> list[Experiment]:
    """One experiment per pair (``kw``: the other :class:`Experiment` fields)."""
    return [Experiment(PAIRS_EXPERIMENT, ((p, episodes),), **kw) for p in pairs]


PAIR_ARRAYS = ("returns", "success")
"""What :func:`run_pair_unit` saves of a unit."""


def run_pair_unit(unit: Unit) -> dict[str, np.ndarray]:
    """:func:`~gdq_pddl.experiments.work.run_unit`, keeping only returns and successes."""
    result = run_unit(unit)
    return {k: result[k] for k in PAIR_ARRAYS}


def collect_pairs(out: Path, experiments: list[Experiment]) -> None:
    """Write ``runs.csv`` and ``optimal.json`` of a pairs folder from ``out/units``."""
    def write_runs(tmp: Path) -> None:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            writer = csv.writer(fh, lineterminator="\n")
            writer.writerow(RUN_COLUMNS)
            for exp in experiments:
                pair = exp.schedule[0][0]
                start, goal = pair.split("->")
                for unit in exp.units():
                    data = read_unit(out, unit, PAIR_ARRAYS)
                    returns, success = data["returns"], data["success"]
                    writer.writerow((pair, start, goal, unit.method, unit.run, len(returns),
                                     repr(float(np.mean(returns))),
                                     repr(float(np.mean(success)))))

    atomic_write(out / "runs.csv", write_runs)
    facts = pair_facts(experiments)
    atomic_write(out / "optimal.json", lambda tmp: tmp.write_text(json.dumps(facts, indent=2)))


@dataclass(frozen=True)
class PairRuns:
    """A pairs folder's results: ``means[pair, method, run]`` (NaN: no such run), methods
    in the report's order; ``facts``: ``optimal.json`` (start, goal, shortest_plan, v_star,
    tuning per pair); ``positions``: the world's, in its order (the heatmap's axes)."""

    pairs: tuple[str, ...]
    methods: tuple[str, ...]
    means: np.ndarray
    facts: dict[str, dict]
    config: dict
    positions: tuple[str, ...]

    @property
    def reference(self) -> str:
        """The method the others are compared with: GDQ if it ran, else the first."""
        ref = registry.REFERENCE
        return ref if ref in self.methods else self.methods[0]

    @property
    def baselines(self) -> tuple[str, ...]:
        return tuple(m for m in self.methods if m != self.reference)

    def tuning(self) -> np.ndarray:
        """bool[pairs]: the pair is one of the tuning tasks A-D."""
        return np.array([bool(self.facts[p].get("tuning")) for p in self.pairs])

    def label(self, i: int) -> str:
        """Pair ``i``'s name, with ``(task X)`` when it is a tuning task."""
        tuning = self.facts[self.pairs[i]].get("tuning")
        return self.pairs[i] + (f" (task {tuning})" if tuning else "")


def load_pair_runs(out: Path) -> PairRuns:
    """Read ``runs.csv``, ``optimal.json`` and ``config.json`` of a pairs folder."""
    if not (out / "runs.csv").exists():
        raise GdqError(f"{out} has no runs.csv: the pairs run has not finished "
                       "(continue it with --resume)")
    facts = json.loads((out / "optimal.json").read_text(encoding="utf-8"))
    runs = pd.read_csv(out / "runs.csv", dtype={"pair": str, "method": str},
                       keep_default_na=False)
    config = load_config(out).raw
    exp = config["experiments"][0]
    pairs, methods = tuple(facts), tuple(registry.order(exp["methods"]))
    grid = pd.MultiIndex.from_product([pairs, methods, range(int(exp["runs"]))])
    means = runs.set_index(["pair", "method", "run"])["mean_return"].reindex(grid)
    return PairRuns(pairs, methods, means.to_numpy().reshape(len(pairs), len(methods), -1),
                    facts, config, load_world_named(exp["world"]).positions)


def pair_facts(experiments: list[Experiment]) -> dict[str, dict]:
    """Per pair (all in one world): start, goal, shortest plan length, V*, tuning task."""
    # start-up time: the model, solver and plan tables import numba and networkx
    from gdq_pddl.envs.model import compile_model, full_state
    from gdq_pddl.envs.office import office_plan_table  # start-up time, as above
    from gdq_pddl.envs.solve import solve  # start-up time, as above

    if not experiments:
        return {}
    world = load_world_named(experiments[0].world)
    tuning = {(t.start, t.goal): name for name, t in world.tasks.items() if name in TUNING_TASKS}
    spaces, model = LearnerSpaces(world), compile_model(world)
    tasks = [resolve_task(world, e.schedule[0][0]) for e in experiments]
    out: dict[str, dict] = {}
    for goal in dict.fromkeys(t.goal for t in tasks):  # one value iteration per goal
        v = solve(model, world.index[goal]).V[0]
        table = office_plan_table(world, goal, experiments[0].planner)
        for t in (t for t in tasks if t.goal == goal):
            out[pair_spec(t.start, t.goal)] = {
                "start": t.start, "goal": t.goal,
                "shortest_plan": int(table.length[spaces.state(t.start)]),
                "v_star": float(v[full_state(world, t.start)]),
                "tuning": tuning.get((t.start, t.goal)),
            }
    return {p: out[p] for p in (pair_spec(t.start, t.goal) for t in tasks)}
