"""Turn the per-unit files of an output folder into its CSV and JSON results:
``episodes.csv`` (:data:`EPISODE_COLUMNS`, then ``area_1 .. area_K`` for a problem with
areas) and ``policies.csv`` (each run's final greedy action per learner state, up to
:data:`MAX_POLICY_ROWS` rows), text quoted as the ``csv`` module quotes it."""

from __future__ import annotations

import csv
import io
import json
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from gdq_pddl.experiments.folder import read_unit
from gdq_pddl.experiments.protocol import Experiment
from gdq_pddl.experiments.work import instance_of
from gdq_pddl.outputs import atomic_write

EPISODE_COLUMNS = ("experiment", "method", "task", "run", "episode", "return", "steps",
                   "success")
POLICY_COLUMNS = ("experiment", "method", "task", "run", "state", "action", "state_name",
                  "action_name")
MAX_POLICY_ROWS = 5_000_000
"""The most rows ``policies.csv`` is written with (one per learner state and run, with the
state's name: on a PDDL problem of millions of states, gigabytes of text that took longer
to write than the runs took); past it the file is left out, and each run's greedy
policy stays in its unit file (``units/<key>.npz``, array ``policy``)."""


def csv_field(text: str) -> str:
    """``text`` as one CSV field, quoted as :mod:`csv` quotes it (only where needed)."""
    buffer = io.StringIO()  # "\n" as the terminator, so that a line break gets quoted too
    csv.writer(buffer, lineterminator="\n").writerow([text])
    return buffer.getvalue().removesuffix("\n")


def collect(out: Path, experiments: list[Experiment],
            online_facts: Mapping[str, Any] | None = None) -> None:
    """Write episodes.csv, policies.csv and optimal.json from ``out/units``;
    ``online_facts`` join the optimal.json entry of every problem explored online (why
    it was: what the command line knows, no worker does)."""
    units = [u for e in experiments for u in e.units()]
    n_areas = max(int(instance_of(e, spec).model.area_of_pos.max())
                  for e in experiments for spec, _ in e.schedule)
    header = ",".join((*EPISODE_COLUMNS, *(f"area_{k}" for k in range(1, n_areas + 1))))

    def write_episodes(tmp: Path) -> None:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(header + "\n")
            for unit in units:
                data = read_unit(out, unit)
                for chunk in _episode_rows(unit.experiment.name, unit.method, unit.run, data,
                                           n_areas):  # names quoted in _episode_rows
                    fh.write(chunk)

    def write_policies(tmp: Path) -> None:
        namers: dict[tuple, tuple[Callable[[int], str], Callable[[int], str]]] = {}
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            writer = csv.writer(fh, lineterminator="\n")
            writer.writerow(POLICY_COLUMNS)
            for unit in units:
                exp = unit.experiment
                key = (exp.world, exp.pddl)
                if key not in namers:  # learner indices named in exp's world or problem
                    instance = instance_of(exp, exp.schedule[0][0])
                    namers[key] = instance.state_name, instance.action_name
                state_name, action_name = namers[key]
                data = read_unit(out, unit)
                task = str(data["tasks"][-1])
                writer.writerows((exp.name, unit.method, task, unit.run, s, a, state_name(s),
                                  action_name(a))
                                 for s, a in enumerate(data["policy"].tolist()))

    atomic_write(out / "episodes.csv", write_episodes)
    online = any(e.pddl is not None and e.pddl.online for e in experiments)
    rows = 0 if online else sum(len(e.units()) * instance_of(e, e.schedule[-1][0]).n_states
                                for e in experiments)  # a policy: an action per state
    if online:  # each run numbered the states it found in its own order
        (out / "policies.csv").unlink(missing_ok=True)
    elif rows <= MAX_POLICY_ROWS:
        atomic_write(out / "policies.csv", write_policies)
    else:
        (out / "policies.csv").unlink(missing_ok=True)  # not one of another configuration
        warnings.warn(f"policies.csv left out: {len(units):,} runs x their learner states "
                      f"make {rows:,} rows, more than {MAX_POLICY_ROWS:,} "
                      "(gdq_pddl.experiments.collect.MAX_POLICY_ROWS); each run's greedy "
                      f"policy is in its unit file, {out / 'units'}/*.npz (array 'policy')",
                      stacklevel=2)
    optimal = optimal_summary(experiments, online_facts)
    atomic_write(out / "optimal.json", lambda tmp: tmp.write_text(json.dumps(optimal, indent=2)))


CHUNK = 50_000
"""Episodes formatted at once (a unit's CSV is written in pieces of bounded memory)."""


def _episode_rows(experiment: str, method: str, run: int, data, n_areas: int):
    """CSV rows of one unit with ``n_areas`` area columns, in pieces of at most
    :data:`CHUNK` rows (plain string formatting: 7 times faster than numpy's)."""
    n = len(data["returns"])
    tasks = np.repeat([csv_field(str(t)) for t in data["tasks"].tolist()], data["counts"])
    k = min(n_areas, data["areas"].shape[1])
    head = f"{csv_field(experiment)},{csv_field(method)},"
    for lo in range(0, n, CHUNK):
        hi = min(n, lo + CHUNK)
        areas = np.zeros((hi - lo, n_areas), dtype=np.int64)
        areas[:, :k] = data["areas"][lo:hi, :k]  # column k - 1 counts steps ending in area k
        area_text = [",".join(map(str, row)) for row in areas.tolist()] if n_areas else \
            None
        rows = []
        for i, (task, ret, steps, success) in enumerate(zip(
                tasks[lo:hi].tolist(), data["returns"][lo:hi].tolist(),
                data["steps"][lo:hi].tolist(), data["success"][lo:hi].tolist(), strict=True)):
            row = f"{head}{task},{run},{lo + i + 1},{ret:.10g},{steps},{int(success)}"
            rows.append(f"{row},{area_text[i]}" if area_text is not None else row)
        yield "\n".join(rows) + "\n"


def optimal_summary(experiments: list[Experiment],
                    online_facts: Mapping[str, Any] | None = None) -> dict:
    """Each task's ground truth (its instance's ``optimal()``, and ``online_facts`` for a
    problem explored online), keyed ``<task>`` (the office), ``<task>@<world>`` or
    ``<task>@<problem file>``."""
    out: dict = {}
    for exp in experiments:
        files = {} if exp.pddl is None else \
            dict(zip(("domain", "problem", "dynamics"), exp.pddl.files, strict=True))
        for spec, _ in exp.schedule:
            instance = instance_of(exp, spec)
            place = files.get("problem", exp.world)
            key = instance.name if place == "office" else f"{instance.name}@{place}"
            if key not in out:
                out[key] = {"world": exp.world, **files, **instance.optimal()}
                if out[key].get("explored") == "online":
                    out[key].update(online_facts or {})
    return out
