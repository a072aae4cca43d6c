"""The statistics of benchmarks/deep_rl.py (IQM, bootstrap interval, steps to a success
threshold, censoring): numpy only, no torch needed."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest
from scipy.stats import trim_mean

from tests.helpers import REPO_ROOT


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("deep_rl", REPO_ROOT / "benchmarks" /
                                                  "deep_rl.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["deep_rl"] = module  # its dataclass looks its module up
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.modules.pop("deep_rl", None)


def test_iqm_is_scipys_trimmed_mean_where_quarters_are_whole(bench):
    rng = np.random.default_rng(3)
    for n in (4, 8, 20):
        x = rng.normal(size=n)
        assert bench.iqm(x) == pytest.approx(trim_mean(x, 0.25))


def test_iqm_weights_the_partial_ends_and_ignores_an_outlier(bench):
    # n = 5: the middle half is [1.25, 3.75): 0.75 of 2, all of 3, 0.75 of 4
    assert bench.iqm([100, 1, 3, 2, 4]) == pytest.approx(3.0)
    assert bench.iqm([7.0]) == 7.0
    assert np.isnan(bench.iqm([]))


def test_bootstrap_interval_holds_the_iqm_and_is_a_point_for_equal_runs(bench):
    assert bench.bootstrap_ci([0.5] * 5) == (0.5, 0.5)
    x = [0.0, 0.2, 0.6, 0.9, 1.0]
    low, high = bench.bootstrap_ci(x, rng=np.random.default_rng(1))
    assert 0.0 <= low < bench.iqm(x) < high <= 1.0
    assert bench.bootstrap_ci(x, rng=np.random.default_rng(1)) == (low, high)
    narrow = bench.bootstrap_ci(x, level=0.5, rng=np.random.default_rng(1))
    assert low <= narrow[0] <= narrow[1] <= high


def test_steps_to_threshold_is_the_first_checkpoint_at_or_above_it(bench):
    steps = [0, 512, 1024, 1536]
    assert bench.steps_to_threshold(steps, [0.0, 0.95, 0.5, 1.0], 0.9) == 512
    assert bench.steps_to_threshold(steps, [0.0, 0.5, 0.9, 1.0], 0.9) == 1024
    assert bench.steps_to_threshold(steps, [0.0, 0.5, 0.8, 0.89], 0.9) is None


def test_success_at_a_budget_takes_the_last_checkpoint_within_it(bench):
    steps = np.array([0, 2048, 4096, 6144])
    success = np.array([0.0, 0.4, 0.7, 1.0])
    assert bench.success_at(steps, success, 4096) == 0.7
    assert bench.success_at(steps, success, 5000) == 0.7
    assert bench.success_at(steps[1:], success[1:], 100) == 0.4  # all past it: the first


def test_summary_censors_unreached_runs_at_the_budget(bench):
    grid = np.array([0, 1000, 2000])
    curves = {("p", "A", r): (grid, np.array([0.0, 1.0, 1.0])) for r in range(4)}
    curves |= {("p", "B", r): (grid, np.array([0.0, 0.5, 0.5 + 0.2 * (r == 0)]))
               for r in range(4)}
    by = {s.method: s for s in bench.summarise(curves, 0.9, 2000, n_boot=200)}
    assert (by["A"].reached, by["A"].steps_iqm, by["A"].final_iqm) == (4, 1000, 1.0)
    assert (by["B"].reached, by["B"].steps_iqm) == (0, 2000)
    assert by["B"].final_iqm == pytest.approx(0.5)  # the middle half: three 0.5s
    text = bench.table(list(by.values()), 0.9, 2000)
    assert "| p | B | ≥2,000 [2,000, 2,000] | 0/4 |" in text
    assert "| p | A | 1,000 [1,000, 1,000] | 4/4 | 1.00 [1.00, 1.00] |" in text
    assert text.index("| p | A |") < text.index("| p | B |")


def test_a_censored_run_counts_as_its_last_checkpoint_and_marks_a_lower_bound(bench):
    reach = (np.array([0, 500, 1000]), np.array([0.0, 1.0, 1.0]))
    never = (np.array([0, 500, 1040]), np.array([0.0, 0.0, 0.0]))  # an episode past 1000
    one = {("p", "GDQ", 0): never} | {("p", "GDQ", r): reach for r in (1, 2, 3)}
    two = {("p", "PPO", r): never for r in (0, 1)} | {("p", "PPO", r): reach for r in (2, 3)}
    by = {s.method: s for s in bench.summarise(one | two, 0.9, 1000, n_boot=100)}
    assert by["GDQ"].reached == 3 and by["GDQ"].steps_iqm == 500  # the 1040 is trimmed
    assert by["PPO"].steps_iqm == pytest.approx((500 + 1040) / 2)
    text = bench.table([by["GDQ"], by["PPO"]], 0.9, 1000)
    assert "| p | GDQ | 500 " in text and "| p | PPO | ≥770 " in text
    assert text.index("| p | GDQ |") < text.index("| p | PPO |")  # METHODS' order


def test_band_of_equal_runs_is_their_curve(bench):
    curve = (np.array([0, 10, 20]), np.array([0.0, 0.5, 1.0]))
    mid, low, high = bench.band([curve] * 3, np.array([0, 5, 10, 25]), n_boot=50)
    assert list(mid) == list(low) == list(high) == [0.0, 0.0, 0.5, 1.0]
