"""Statistics for the reports, one number per run and method: Welch's t-test and a
percentile bootstrap CI of the difference in means (significant when the CI excludes 0
and p < ``alpha``), verdicts, milestones, and the interquartile mean with a stratified
bootstrap CI over many tasks (Agarwal et al. 2021). docs/decisions.md says why."""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

ALPHA = 0.05
N_BOOT = 10_000
SEED = 20240501

HOLDS, DOES_NOT_HOLD, MIXED = "holds", "does not hold", "mixed"


def run_means(matrix: np.ndarray, start: int = 0, stop: int | None = None) -> np.ndarray:
    """Per-run mean of ``matrix[runs, episodes]`` over episodes ``start:stop`` (NaN-aware)."""
    return pd.DataFrame(matrix[:, start:stop]).mean(axis=1).to_numpy() if matrix.size \
        else np.empty(0)


def mean_se(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error (ddof=1; 0 with one sample) over axis 0, NaN-aware."""
    frame = pd.DataFrame(np.asarray(x, dtype=float).reshape(len(x), -1))
    mean, se = frame.mean().to_numpy(), frame.sem().fillna(0.0).to_numpy()
    return (mean[0], se[0]) if np.ndim(x) == 1 else (mean, se)


@dataclass(frozen=True)
class Comparison:
    """``a`` (GDQ) against ``b`` (a baseline): ``diff = mean(a) - mean(b)``;
    ``higher_is_better`` says which sign favours ``a``."""

    a: str
    b: str
    diff: float
    ci_low: float
    ci_high: float
    t: float
    p: float
    n_a: int
    n_b: int
    higher_is_better: bool = True

    @property
    def significant(self) -> bool:
        return (min(self.n_a, self.n_b) >= 2 and (self.ci_low > 0 or self.ci_high < 0)
                and (math.isnan(self.p) or self.p < ALPHA))

    @property
    def outcome(self) -> str:
        """``better``, ``worse`` or ``inconclusive`` for ``a``."""
        if not self.significant:
            return "inconclusive"
        good = self.diff > 0 if self.higher_is_better else self.diff < 0
        return "better" if good else "worse"

    def describe(self, unit: str = "") -> str:
        """One line: difference, CI, Welch's p, n."""
        p = "n/a" if math.isnan(self.p) else f"{self.p:.3g}"
        return (f"{self.a} - {self.b} = {self.diff:+.3g}{unit} "
                f"(95% CI [{self.ci_low:+.3g}, {self.ci_high:+.3g}], Welch p = {p}, "
                f"n = {self.n_a} vs {self.n_b} runs): {self.outcome}")


def _finite(x: np.ndarray) -> np.ndarray:
    return np.asarray(x, dtype=float)[~np.isnan(x)]


def compare(a: np.ndarray, b: np.ndarray, name_a: str, name_b: str,
            higher_is_better: bool = True, seed: int = SEED) -> Comparison:
    """Welch's t-test and the percentile bootstrap 95% CI of ``mean(a) - mean(b)`` over
    runs, NaN dropped: both NaN with fewer than 2 values a side; two constant samples
    have no t-test and their CI is the point difference."""
    a, b = _finite(a), _finite(b)
    ma, mb = (float(x.mean()) if x.size else math.nan for x in (a, b))
    low = high = t = p = math.nan
    if a.size >= 2 and b.size >= 2:
        if np.ptp(a) == 0 and np.ptp(b) == 0:  # nothing to resample: the CI is the point
            low = high = ma - mb
        else:
            from scipy import stats as sps  # start-up time: 0.6 s, for comparisons only

            ci = sps.bootstrap((a, b), lambda x, y, axis=-1: x.mean(axis) - y.mean(axis),
                               n_resamples=N_BOOT, method="percentile",
                               rng=np.random.default_rng(seed)).confidence_interval
            low, high = float(ci.low), float(ci.high)
            # nearly constant samples (a method failing alike in every run) make scipy
            # warn about precision; the statistic is still the one to report
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", "Precision loss occurred", RuntimeWarning)
                t, p = sps.ttest_ind(a, b, equal_var=False)
    return Comparison(name_a, name_b, ma - mb, low, high, float(t), float(p), a.size,
                      b.size, higher_is_better)


def verdict(comparisons: Sequence[Comparison]) -> str:
    """``holds`` / ``does not hold`` / ``mixed`` (see the module docstring)."""
    outcomes = [c.outcome for c in comparisons]
    if not outcomes:
        return "no baselines"
    if "worse" in outcomes or "better" not in outcomes:
        return DOES_NOT_HOLD
    return HOLDS if all(o == "better" for o in outcomes) else MIXED


def verdict_reason(comparisons: Sequence[Comparison]) -> str:
    """Which baselines GDQ beats, ties with and loses to, e.g. ``better than DARLING;
    no significant difference from Dyna-Q``."""
    groups = {"better": "better than", "inconclusive": "no significant difference from",
              "worse": "worse than"}
    parts = [f"{words} {', '.join(names)}" for outcome, words in groups.items()
             if (names := [c.b for c in comparisons if c.outcome == outcome])]
    return "; ".join(parts) or "no baselines"


def moving_average(x: np.ndarray, window: int, full_only: bool = True) -> np.ndarray:
    """Trailing moving average along the last axis of a 1-D or 2-D array (pandas
    ``rolling``); with ``full_only`` the first ``window - 1`` values are NaN, otherwise
    they average the episodes so far (the figures' smoothing)."""
    x = np.asarray(x, dtype=float)
    window = max(1, int(window))
    out = pd.DataFrame(np.atleast_2d(x).T).rolling(
        window, min_periods=window if full_only else 1).mean().to_numpy().T
    return out.reshape(x.shape)


@dataclass(frozen=True)
class Milestone:
    """When a method's return first turns positive: per run (NaN: never within the data)
    and on the mean curve over runs (what the learning curve shows)."""

    per_run: tuple[float, ...]
    on_mean_curve: float


def first_positive(matrix: np.ndarray, window: int = 50, threshold: float = 0.0) -> Milestone:
    """First episode whose ``window``-episode moving average of return exceeds
    ``threshold``, per run and on the mean curve over runs."""
    if matrix.size == 0:
        return Milestone((), math.nan)
    mean_curve = pd.DataFrame(matrix).mean().to_numpy()
    per_run = np.vstack([moving_average(matrix, window), moving_average(mean_curve, window)])
    first = [float(np.argmax(hits) + 1) if hits.any() else math.nan for hits in
             per_run > threshold]
    return Milestone(tuple(first[:-1]), first[-1])


def route_settles(visits: np.ndarray, success: np.ndarray, route_areas: Sequence[int],
                  areas: Sequence[int], window: int, share: float) -> list[float]:
    """Per run of ``visits[runs, episodes, n_areas]`` (areas in the order of ``areas``):
    the 1-based episode from which at least ``share`` of the trailing ``window`` episodes
    succeed visiting exactly the areas of ``route_areas``, to the end (NaN: never)."""
    on = np.isin(areas, route_areas)
    visited = visits > 0
    follows = visited[..., on].all(axis=-1) & ~visited[..., ~on].any(axis=-1) & (success > 0)
    if follows.shape[-1] < window:
        return [math.nan] * len(follows)
    out = []
    for ok in moving_average(follows.astype(float), window) >= share - 1e-12:
        bad = np.flatnonzero(~ok)
        out.append(math.nan if not ok[-1] else float(bad[-1] + 2) if bad.size else 1.0)
    return out


def iqm_ci(scores: Sequence[np.ndarray], seed: int = SEED) -> tuple[float, float, float]:
    """IQM of every run's score on every task (``scores``: an array of run scores per
    task) and its stratified percentile bootstrap CI (:func:`scipy.stats.bootstrap`, one
    sample per task: runs resampled within each task); NaN CI with < 2 runs on a task."""
    samples = [s for s in (_finite(s) for s in scores) if s.size]
    if not samples:
        return math.nan, math.nan, math.nan
    from scipy import stats as sps  # start-up time: 0.6 s, for several tasks only

    def iqm(*xs: np.ndarray, axis: int = -1) -> np.ndarray:  # the mean of the middle 50%
        return sps.trim_mean(np.concatenate(xs, axis=axis), 0.25, axis=axis)

    point = float(iqm(*samples))
    if min(s.size for s in samples) < 2:
        return point, math.nan, math.nan
    res = sps.bootstrap(samples, iqm, n_resamples=2000, method="percentile",
                        rng=np.random.default_rng(seed))
    return point, float(res.confidence_interval.low), float(res.confidence_interval.high)
