"""The report of an experiment no paper section covers (``gdq-pddl run``): the methods
section with numbers recomputed from the CSV, each GDQ variant against each baseline,
a folder without GDQ, and a short real run with its learning curves."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from gdq_pddl.analysis import make_all, write_report
from gdq_pddl.analysis.stats import compare
from tests.analysis.synthetic import (
    HEADER,
    PAPER_IRR,
    QUALITY,
    RELEVANT,
    V_STAR,
    _episode,
)

# --- an experiment no paper section covers (gdq-pddl run) ---------------------------

RUN_METHODS = ("Q-learning", "DARLING-code", "GDQ", "Dyna-Q", "DARLING", "GDQ-code")
RUN_QUALITY = {**QUALITY, "DARLING-code": 0.5}
RUN_RUNS, RUN_EPISODES = 3, 120


def write_run_output(out: Path, methods: tuple[str, ...] = RUN_METHODS) -> Path:
    """A synthetic ``gdq-pddl run --task C`` folder (experiment ``run``), laid out as the
    runner writes it."""
    rng = np.random.default_rng(11)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for method in methods:
        for run in range(RUN_RUNS):
            for e in range(1, RUN_EPISODES + 1):
                ret, steps, success, areas = _episode(rng, RUN_QUALITY[method], e, "C",
                                                      V_STAR["C"], 20.0, 10**6)
                rows.append(["run", method, "C", run, e, f"{ret:.3f}", steps, success,
                             *areas])
    with (out / "episodes.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(HEADER)
        w.writerows(rows)
    (out / "optimal.json").write_text(json.dumps(
        {"C": {"world": "office", "start": "p0", "goal": "p17", "v_star": V_STAR["C"],
               "relevant_areas": RELEVANT["C"], "irrelevant_areas_paper": PAPER_IRR["C"]}}))
    (out / "config.json").write_text(json.dumps(
        {"experiments": [{"name": "run", "schedule": [["C", RUN_EPISODES]],
                          "methods": list(methods), "runs": RUN_RUNS, "world": "office",
                          "seed": 0}], "versions": {"gdq_pddl": "test"}}))
    return out


def _methods_section(text: str) -> str:
    start = text.index("## Methods compared")
    end = text.find("\n## ", start + 1)
    return text[start:end if end >= 0 else None]


def _expected_row(returns: np.ndarray, success: np.ndarray, window: int = 50) -> str:
    """The section's table cells of one method, computed here with plain numpy."""
    runs, n = returns.shape
    tail = max(1, n // 10)
    means, lasts = returns.mean(axis=1), returns[:, n - tail:].mean(axis=1)

    def se(x: np.ndarray) -> float:
        return x.std(ddof=1) / np.sqrt(x.size)

    curve = returns.mean(axis=0)
    ma = np.convolve(curve, np.ones(window) / window, mode="valid")  # ends at episode k+w
    hits = np.flatnonzero(ma > 0)
    per_run = [np.flatnonzero(np.convolve(r, np.ones(window) / window, "valid") > 0)
               for r in returns]
    reached = [h[0] + window for h in per_run if h.size]
    milestone = (f"{hits[0] + window} ({np.mean(reached):.4g}; {len(reached)}/{runs})"
                 if hits.size else f"n/a (n/a; 0/{runs})")
    return (f"{runs} | {means.mean():.2f} ({se(means):.2f}) | {lasts.mean():.2f} "
            f"({se(lasts):.2f}) | {success.mean():.1%} | {milestone} |")


def _read_matrices(out: Path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Method -> (returns, success) as ``[runs, episodes]``, straight from the CSV."""
    cells: dict[str, dict[tuple[int, int], tuple[float, float]]] = {}
    with (out / "episodes.csv").open(newline="") as f:
        for r in csv.DictReader(f):
            cells.setdefault(r["method"], {})[(int(r["run"]), int(r["episode"]))] = (
                float(r["return"]), float(r["success"]))
    out_m = {}
    for method, c in cells.items():
        runs = sorted({k[0] for k in c})
        eps = sorted({k[1] for k in c})
        arr = np.array([[c[(r, e)] for e in eps] for r in runs])
        out_m[method] = (arr[..., 0], arr[..., 1])
    return out_m


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    out = write_run_output(tmp_path_factory.mktemp("run"))
    return out, write_report(out).read_text()


def test_run_experiment_gets_a_methods_section_with_numbers_from_the_csv(run_folder):
    out, text = run_folder
    section = _methods_section(text)
    assert "### run: task C" in section
    assert f"V* = {V_STAR['C']:.2f}" in section
    rows = re.findall(r"^\| (\*\*)?([A-Za-z-]+)(?:\*\*)? \| (\d+ \|.*)$", section, re.M)
    names = [name for _, name, _ in rows]
    # a row per method, in the registry's order (DARLING-code after DARLING)
    assert names == ["GDQ", "GDQ-code", "DARLING", "DARLING-code", "Dyna-Q", "Q-learning"]
    data = _read_matrices(out)
    for _, method, cells in rows:
        assert cells == _expected_row(*data[method]), method
    best = max(data, key=lambda m: data[m][0].mean(axis=1).mean())
    assert [name for b, name, _ in rows if b] == [best]


def test_methods_section_compares_each_gdq_variant_with_each_baseline(run_folder):
    out, text = run_folder
    section = _methods_section(text)
    data = _read_matrices(out)
    for variant in ("GDQ", "GDQ-code"):
        assert f"- **{variant}**, all episodes: {variant} " in section
        assert f"- **{variant}**, last 10% of episodes: {variant} " in section
        for baseline in ("DARLING", "DARLING-code", "Dyna-Q", "Q-learning"):
            for tail, expect in ((0, "all episodes"), (RUN_EPISODES - RUN_EPISODES // 10,
                                                      "last 10%")):
                a = data[variant][0][:, tail:].mean(axis=1)
                b = data[baseline][0][:, tail:].mean(axis=1)
                c = compare(a, b, variant, baseline)
                assert f"  - {c.describe()}" in section, (variant, baseline, expect)
    # the fake GDQ-code is far better than Q-learning; baselines are never tested as "a"
    assert re.search(r"GDQ-code - Q-learning = \+[\d.]+ .*: better", section)
    assert not any(f"{b} - " in section for b in ("DARLING", "Dyna-Q", "Q-learning"))


def test_a_folder_without_paper_experiments_gets_the_run_report(run_folder):
    _, text = run_folder
    assert text.startswith("# Run report\n")
    assert "no GDQ runs in the data" not in text and "**Summary.**" not in text
    assert "Welch's t-test (two-sided) and a percentile bootstrap 95% CI" in text
    assert "planner `?`; world `office`" in text  # what produced it, from config.json


def test_methods_section_without_gdq_says_so(tmp_path):
    out = write_run_output(tmp_path, methods=("DARLING", "DARLING-code", "Q-learning"))
    text = write_report(out).read_text()
    section = _methods_section(text)
    assert "No GDQ variant ran on this task: nothing to compare." in section
    assert re.findall(r"^\| (?:\*\*)?(DARLING-code|DARLING|Q-learning)", section, re.M) == [
        "DARLING", "DARLING-code", "Q-learning"]


@pytest.fixture(scope="module")
def real_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short real run (one for the tests below: each reads it, make_all rewrites it)."""
    from gdq_pddl.experiments import Experiment, run_experiments

    exp = Experiment("run", (("C", 60),), runs=2, methods=("GDQ-code", "Q-learning"))
    return run_experiments([exp], tmp_path_factory.mktemp("real"), jobs=1, progress=False)


def test_methods_section_on_a_real_run(real_run):
    out = real_run
    section = _methods_section(write_report(out).read_text())
    v_star = json.loads((out / "optimal.json").read_text())["C"]["v_star"]
    assert f"V* = {v_star:.2f}" in section
    assert "| **GDQ-code** | 2 |" in section or "| GDQ-code | 2 |" in section
    assert "  - GDQ-code - Q-learning = " in section


def test_a_run_experiment_gets_its_learning_curves_linked_from_the_report(real_run):
    out = real_run
    paths = make_all(out)
    assert out / "figures" / "learning_curves_run.png" in paths
    assert "![learning curves, run](figures/learning_curves_run.png)" in (
        out / "REPORT.md").read_text()
