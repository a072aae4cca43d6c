"""benchmarks/baselines.py on a ``gdq-pddl run`` folder a time limit stopped: the rows come
from the runs it saved, paired on the runs both methods saved, and a comparison on fewer
runs than the reference's is shown but left out of the wins / ties / losses."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest

from tests.helpers import REPO_ROOT


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("baselines_bench",
                                                  REPO_ROOT / "benchmarks" / "baselines.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def unfinished(tmp_path, returns: dict[str, list[list[float]]]):
    folder = tmp_path / "pg-x"
    (folder / "units").mkdir(parents=True)
    (folder / "config.json").write_text(json.dumps(
        {"experiments": [{"name": "run", "methods": ["GDQ", "B", "C", "D"]}]}))
    for method, runs in returns.items():
        for i, r in enumerate(runs):
            np.savez(folder / "units" / f"run__t__{method}__run{i}.npz", returns=np.array(r))
    return folder


def test_unfinished_folder_pairs_saved_runs_and_keeps_partial_out_of_counts(bench, tmp_path):
    folder = unfinished(tmp_path, {
        "GDQ": [[1.0, 3.0], [2.0, 2.0], [4.0, 4.0]],   # run means 2, 2, 4
        "C": [[0.0, 0.0]],                              # run 0 only: mean 0
        "B": [[1.0, 1.0], [1.0, 1.0], [3.0, 3.0]],     # 1, 1, 3: differences 1, 1, 1
    })
    df = bench.rows([folder], "GDQ")
    assert list(df["method"]) == ["B", "C"]  # the config's order; D saved nothing
    b = df.set_index("method").loc["B"]
    assert b["diff"] == pytest.approx(1.0) and b.outcome == "win" and b.runs == 3 and b.note == ""
    assert b.reference_mean == pytest.approx(8 / 3) and np.isnan(b.v_star)
    c = df.set_index("method").loc["C"]
    assert c["diff"] == pytest.approx(2.0) and c.runs == 1 and c.note == "1 of 3 runs"
    text = bench.markdown(df)
    assert "pg-x (unfinished)" in text and "(1 of 3 runs)" in text
    assert text.splitlines()[-1] == "| **wins / ties / losses** | | | 1 / 0 / 0 | 0 / 0 / 0 |"
