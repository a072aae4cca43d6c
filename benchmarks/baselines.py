"""GDQ minus each other method, paired over runs, on many ``gdq-pddl run`` folders.

    python benchmarks/baselines.py results/run-A results/run-B ...          # Markdown
    python benchmarks/baselines.py FOLDERS --csv out.csv --reference GDQ

Each folder is the output of one ``gdq-pddl run`` (one problem or task; its methods ran
with the same seeds, so run ``i`` of every method saw the same env seed). Per folder,
experiment and task: each method's mean return per episode (the mean over runs of each
run's mean over its episodes), and for each other method the reference minus it, paired
by run: the mean of the per-run differences with its 95% t-interval (n - 1 degrees of
freedom), ``win`` when the interval lies above 0, ``loss`` below, ``tie`` otherwise (the
rule of ``gdq-pddl pairs``, :mod:`gdq_pddl.analysis.pairs`). The last row counts wins,
ties and losses over the rows. ``gdq-pddl run``'s own report tests GDQ against each
baseline with Welch's test on unpaired runs; ``gdq-pddl pairs`` pairs, but only on office
pairs: this script is the paired table for single problems. ``--last 0.1`` compares
over each run's last 10% of episodes instead of all of them. A ``gdq-pddl scale`` folder
(its ``building-N-sS.npz`` files) gives a row per building, with the building's
reference value V_ref (a lower bound on V*) in the V* column; a building folder of an
unfinished one (``units/building-N-sS``), a row per method on the runs it saved. A
``gdq-pddl run`` folder a limit stopped (``config.json`` and ``units/`` but no
``episodes.csv``) gives a row per method that saved a run, on the runs it shares with the
reference, the problem marked ``(unfinished)`` and a cell's run count when it is below the
reference's (such a comparison is left out of the wins / ties / losses row).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats as sps

from gdq_pddl.analysis.pairs import LEVEL, LOSS, TIE, WIN, over_runs
from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.writer import number


def per_run_means(study: Study, experiment: str, method: str, task: str,
                  last: float = 1.0) -> np.ndarray:
    """Each run's mean return per episode (runs ascending), over the last ``last`` share
    of its episodes (at least one)."""
    returns = study.returns(experiment, method, task)
    keep = max(1, int(round(returns.shape[1] * last)))
    return np.nanmean(returns[:, -keep:], axis=1)


def paired(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float, str]:
    """``a - b`` paired by run: mean, interval low and high, outcome."""
    d = a - b
    mean, se = over_runs(d)
    n = d.size
    half = float(sps.t.ppf((1 + LEVEL) / 2, n - 1) * se) if n > 1 else math.nan
    if n > 1 and se == 0:
        half = 0.0
    mean = float(mean)
    outcome = WIN if mean - half > 0 else LOSS if mean + half < 0 else TIE
    return mean, mean - half, mean + half, outcome


def rows(folders: list[Path], reference: str, last: float = 1.0) -> pd.DataFrame:
    """One row per (folder, experiment, task, method other than the reference)."""
    out = []
    for folder in folders:
        if not (folder / "episodes.csv").is_file() and any(folder.glob("building-*.npz")):
            out += building_rows(folder, reference, last)
            continue
        if folder.name.startswith("building-") and any(folder.glob("*-[0-9]*.npz")):
            out += unit_rows(folder, reference, last)
            continue
        if not (folder / "episodes.csv").is_file() and (folder / "units").is_dir():
            out += unfinished_rows(folder, reference, last)
            continue
        study = Study.open(folder)
        for exp in study.experiments:
            methods = study.methods(exp)
            if reference not in methods:
                continue
            for task in study.tasks(exp):
                ref = per_run_means(study, exp, reference, task, last)
                label = folder.name
                if len(study.experiments) > 1:
                    label += f":{exp}"
                if len(study.tasks(exp)) > 1:
                    label += f":{task}"
                for m in methods:
                    if m == reference:
                        continue
                    other = per_run_means(study, exp, m, task, last)
                    mean, low, high, outcome = paired(ref, other)
                    out.append({"problem": label, "v_star": study.v_star(exp, task),
                                "runs": ref.size, "reference": reference,
                                "reference_mean": float(ref.mean()), "method": m,
                                "method_mean": float(other.mean()), "diff": mean,
                                "low": low, "high": high, "outcome": outcome})
    return pd.DataFrame(out)


def building_rows(folder: Path, reference: str, last: float = 1.0) -> list[dict]:
    """The rows of a ``gdq-pddl scale`` folder: one per building (its
    ``building-N-sS.npz``), V* the building's reference value V_ref (a lower bound)."""
    out = []
    for path in sorted(folder.glob("building-*.npz"),
                       key=lambda p: tuple(int(x.lstrip("s")) for x in p.stem.split("-")[1:])):
        with np.load(path) as data:
            returns = {k.split("/", 1)[1]: data[k] for k in data.files
                       if k.startswith("returns/")}
            v_ref = float(data["v_ref"])
        if reference not in returns:
            continue
        keep = max(1, int(round(returns[reference].shape[1] * last)))
        means = {m: r[:, -keep:].mean(axis=1) for m, r in returns.items()}
        ref = means[reference]
        for m, other in means.items():
            if m == reference:
                continue
            mean, low, high, outcome = paired(ref, other)
            out.append({"problem": path.stem, "v_star": v_ref, "runs": ref.size,
                        "reference": reference, "reference_mean": float(ref.mean()),
                        "method": m, "method_mean": float(other.mean()), "diff": mean,
                        "low": low, "high": high, "outcome": outcome})
    return out


def unit_rows(folder: Path, reference: str, last: float = 1.0) -> list[dict]:
    """The rows of one building of an unfinished ``gdq-pddl scale`` run, from the runs
    it saved (``units/building-N-sS/METHOD-RUN.npz``): each method against the reference
    on the runs both finished; V* unknown (NaN: the building's V_ref is written at its
    end)."""
    runs: dict[str, dict[int, np.ndarray]] = {}
    for path in folder.glob("*-[0-9]*.npz"):
        method, run = path.stem.rsplit("-", 1)
        with np.load(path) as data:
            returns = data["returns"]
        keep = max(1, int(round(returns.size * last)))
        runs.setdefault(method, {})[int(run)] = returns[-keep:].mean()
    if reference not in runs:
        return []
    out = []
    for m, by_run in sorted(runs.items()):
        if m == reference:
            continue
        common = sorted(set(by_run) & set(runs[reference]))
        ref = np.array([runs[reference][r] for r in common])
        other = np.array([by_run[r] for r in common])
        mean, low, high, outcome = paired(ref, other) if common else (math.nan,) * 3 + (TIE,)
        out.append({"problem": f"{folder.name} ({len(common)} runs)", "v_star": math.nan,
                    "runs": len(common), "reference": reference,
                    "reference_mean": float(ref.mean()) if common else math.nan,
                    "method": m, "method_mean": float(other.mean()) if common else math.nan,
                    "diff": mean, "low": low, "high": high, "outcome": outcome})
    return out


def unfinished_rows(folder: Path, reference: str, last: float = 1.0) -> list[dict]:
    """The rows of a ``gdq-pddl run`` folder stopped before its end, from the runs it saved
    (``units/EXPERIMENT__TASK__METHOD__runI.npz``, the schedule's one task each): each
    method against the reference on the runs both saved; V* unknown (NaN: ``optimal.json``
    is written at the end)."""
    means: dict[tuple[str, str], dict[str, dict[int, float]]] = {}
    for path in (folder / "units").glob("*__run[0-9]*.npz"):
        exp, task, method, run = path.stem.split("__")
        with np.load(path) as data:
            returns = data["returns"]
        keep = max(1, int(round(returns.size * last)))
        means.setdefault((exp, task), {}).setdefault(method, {})[int(run[3:])] = float(
            returns[-keep:].mean())
    order = [m for e in json.loads((folder / "config.json").read_text())["experiments"]
             for m in e["methods"]] if (folder / "config.json").is_file() else []
    out = []
    for (exp, task), runs in sorted(means.items()):
        if reference not in runs:
            continue
        label = f"{folder.name} (unfinished)"
        if len(means) > 1:
            label += f":{exp}:{task}"
        full = len(runs[reference])
        for m in sorted(runs, key=lambda m: (m not in order, order.index(m) if m in order
                                             else 0, m)):
            by_run = runs[m]
            common = sorted(set(by_run) & set(runs[reference]))
            if m == reference or not common:
                continue
            ref = np.array([runs[reference][r] for r in common])
            other = np.array([by_run[r] for r in common])
            mean, low, high, outcome = paired(ref, other)
            out.append({"problem": label, "v_star": math.nan, "runs": len(common),
                        "reference": reference,
                        "reference_mean": float(np.mean(list(runs[reference].values()))),
                        "method": m, "method_mean": float(other.mean()), "diff": mean,
                        "low": low, "high": high, "outcome": outcome,
                        "note": f"{len(common)} of {full} runs" if len(common) < full else ""})
    return out


def markdown(df: pd.DataFrame) -> str:
    """Problems down, methods across: each cell the method's mean, then the reference
    minus it with its 95% interval and outcome; a last row of wins / ties / losses."""
    methods = list(dict.fromkeys(df["method"]))
    reference = df["reference"].iloc[0]
    head = ["problem", "V*", reference, *(f"{reference} - {m}" for m in methods)]
    lines = ["| " + " | ".join(head) + " |", "|---|--:|--:|" + "--:|" * len(methods)]
    for problem, g in df.groupby("problem", sort=False):
        g = g.set_index("method")
        first = g.iloc[0]
        cells = [problem, number(first.v_star), number(first.reference_mean)]
        for m in methods:
            if m not in g.index:
                cells.append("")
                continue
            r = g.loc[m]
            cells.append(f"{number(r['diff'], sign=True)} [{number(r.low, sign=True)}, "
                         f"{number(r.high, sign=True)}] {r.outcome} ({number(r.method_mean)})"
                         + (f" ({r.note})" if isinstance(r.get("note"), str) and r.note else ""))
        lines.append("| " + " | ".join(cells) + " |")
    counts = []
    for m in methods:
        partial = df["note"].fillna("").astype(bool) if "note" in df else False
        o = df.loc[(df["method"] == m) & ~partial, "outcome"]
        counts.append(f"{(o == WIN).sum()} / {(o == TIE).sum()} / {(o == LOSS).sum()}")
    lines.append("| **wins / ties / losses** | | | " + " | ".join(counts) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--reference", default="GDQ")
    parser.add_argument("--last", type=float, default=1.0,
                        help="compare over this share of each run's last episodes "
                             "(default 1: all; 0.1: the last 10%%)")
    parser.add_argument("--csv", type=Path, help="also write every digit here")
    args = parser.parse_args()
    df = rows(args.folders, args.reference, args.last)
    if args.csv:
        df.to_csv(args.csv, index=False)
    print(markdown(df), end="")


if __name__ == "__main__":
    main()
