"""Statistics for the reports: GDQ-vs-baseline tests, verdicts, milestones, the IQM.

Every comparison is between *runs* (the independent unit): one number per run for each
method, then Welch's t-test (unequal variances, :func:`scipy.stats.ttest_ind`) and a
percentile bootstrap 95% CI of the difference in means (:func:`scipy.stats.bootstrap`,
runs resampled within each method, a numpy Generator with a fixed seed). A difference is
*significant* when the CI excludes 0 and the two-sided p-value is below ``alpha`` (when
the t-test is undefined, e.g. two constant samples, the CI alone decides).

Verdicts (:func:`verdict`) over the comparisons of GDQ with each baseline: ``holds`` when
GDQ is significantly better than every baseline; ``does not hold`` when it is
significantly worse than at least one, or better than none; ``mixed`` otherwise.

Milestones use a trailing moving average (pandas ``rolling``) over *full* windows only:
the value at episode ``e`` is the mean of episodes ``e - w + 1 .. e``, defined from
episode ``w`` on, so one lucky early episode cannot count as a milestone.

Over many tasks (:func:`iqm_ci`): the interquartile mean of every run's score on every
task, with a stratified bootstrap CI (runs resampled within each task), as Agarwal et al.
(2021) recommend for results over many tasks and few runs.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats as sps

ALPHA = 0.05
N_BOOT = 10_000
SEED = 20240501

HOLDS, DOES_NOT_HOLD, MIXED = "holds", "does not hold", "mixed"


def run_means(matrix: np.ndarray, start: int = 0, stop: int | None = None) -> np.ndarray:
    """Per-run mean of ``matrix[runs, episodes]`` over episode columns ``start:stop``
    (NaN for a run without episodes there)."""
    if matrix.size == 0:
        return np.empty(0)
    return pd.DataFrame(matrix[:, start:stop]).mean(axis=1).to_numpy()


def mean_se(x: np.ndarray, axis: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error (ddof=1; 0 with a single sample) along ``axis``, NaN-aware."""
    frame = pd.DataFrame(np.moveaxis(np.asarray(x, dtype=float), axis, 0).reshape(
        np.shape(x)[axis], -1))
    shape = np.delete(np.shape(x), axis)
    mean, se = frame.mean().to_numpy(), frame.sem().fillna(0.0).to_numpy()
    return mean.reshape(shape), se.reshape(shape)


@dataclass(frozen=True)
class Comparison:
    """``a`` (GDQ) against ``b`` (a baseline): difference ``mean(a) - mean(b)``;
    ``higher_is_better`` says which sign favours ``a``."""

    a: str
    b: str
    mean_a: float
    mean_b: float
    diff: float
    ci_low: float
    ci_high: float
    t: float
    p: float
    n_a: int
    n_b: int
    higher_is_better: bool = True
    alpha: float = ALPHA

    @property
    def significant(self) -> bool:
        if self.n_a < 2 or self.n_b < 2:
            return False
        excludes_zero = self.ci_low > 0 or self.ci_high < 0
        return excludes_zero and (math.isnan(self.p) or self.p < self.alpha)

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
    x = np.asarray(x, dtype=float)
    return x[~np.isnan(x)]


def compare(a: np.ndarray, b: np.ndarray, name_a: str = "GDQ", name_b: str = "baseline",
            higher_is_better: bool = True, seed: int = SEED, alpha: float = ALPHA) -> Comparison:
    """Welch's t-test (``scipy.stats.ttest_ind(equal_var=False)``) and the percentile
    bootstrap 95% CI (``scipy.stats.bootstrap``) of ``mean(a) - mean(b)`` over runs, NaN
    values dropped. Both are NaN with fewer than 2 values a side; two constant samples
    have no t-test and their CI is the point difference."""
    a, b = _finite(a), _finite(b)
    ma, mb = (float(x.mean()) if x.size else math.nan for x in (a, b))
    ci = t = p = math.nan
    if a.size >= 2 and b.size >= 2:
        if np.ptp(a) == 0 and np.ptp(b) == 0:  # nothing to resample: the CI is the point
            ci = (ma - mb, ma - mb)
        else:
            ci = sps.bootstrap((a, b), lambda x, y, axis=-1: x.mean(axis) - y.mean(axis),
                               n_resamples=N_BOOT, method="percentile",
                               rng=np.random.default_rng(seed)).confidence_interval
            # nearly constant samples (a method that fails identically in every run) make
            # scipy warn about precision; the statistic is still the one to report
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", "Precision loss occurred", RuntimeWarning)
                t, p = sps.ttest_ind(a, b, equal_var=False)
    low, high = (math.nan, math.nan) if ci is math.nan else map(float, ci)
    return Comparison(name_a, name_b, ma, mb, ma - mb, low, high, float(t), float(p), a.size,
                      b.size, higher_is_better, alpha)


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
    ``rolling``). With ``full_only`` the first ``window - 1`` values are NaN; otherwise
    they average the episodes seen so far (the figures' smoothing)."""
    x = np.asarray(x, dtype=float)
    window = max(1, int(window))
    frame = pd.DataFrame(np.atleast_2d(x).T)
    out = frame.rolling(window, min_periods=window if full_only else 1).mean().to_numpy().T
    return out.reshape(x.shape)


def _first(hits: np.ndarray) -> float:
    """1-based index of the first True (NaN if none)."""
    idx = np.flatnonzero(hits)
    return float(idx[0] + 1) if idx.size else math.nan


@dataclass(frozen=True)
class Milestone:
    """When a method's return first turns positive (see :func:`first_positive`)."""

    per_run: tuple[float, ...]
    """Per run (NaN: never within the data)."""
    on_mean_curve: float
    """On the mean curve over runs (what the learning curve shows)."""

    @property
    def reached(self) -> int:
        return int(sum(not math.isnan(v) for v in self.per_run))

    @property
    def mean_of_reached(self) -> float:
        vals = [v for v in self.per_run if not math.isnan(v)]
        return float(np.mean(vals)) if vals else math.nan


def first_positive(matrix: np.ndarray, window: int = 50, threshold: float = 0.0) -> Milestone:
    """First episode whose ``window``-episode moving average of return exceeds ``threshold``,
    per run and on the mean curve over runs."""
    if matrix.size == 0:
        return Milestone((), math.nan)
    per_run = tuple(_first(row) for row in moving_average(matrix, window) > threshold)
    mean_curve = pd.DataFrame(matrix).mean().to_numpy()
    return Milestone(per_run, _first(moving_average(mean_curve, window) > threshold))


def settles(indicator: np.ndarray, window: int, share: float) -> float:
    """1-based episode from which the trailing ``window``-episode share of ``indicator``
    stays at or above ``share`` to the end of the data (NaN if it never does)."""
    ind = np.asarray(indicator, dtype=float)
    if ind.size < window:
        return math.nan
    ok = moving_average(ind, window) >= share - 1e-12
    if not ok[-1]:
        return math.nan
    bad = np.flatnonzero(~ok)
    return float(bad[-1] + 2) if bad.size else 1.0


def route_indicator(visits: np.ndarray, success: np.ndarray, route_areas: Sequence[int],
                    areas: Sequence[int]) -> np.ndarray:
    """Per episode: succeeded and visited exactly the areas of ``route_areas``
    (``visits[..., n_areas]``, areas in the order of ``areas``)."""
    on = np.array([a in set(route_areas) for a in areas])
    visited = visits > 0
    exact = np.all(visited[..., on], axis=-1) & ~np.any(visited[..., ~on], axis=-1)
    return exact & (success > 0)


def convergence_episode(visits: np.ndarray, success: np.ndarray, route_areas: Sequence[int],
                        areas: Sequence[int], window: int = 50,
                        share: float = 0.5) -> tuple[float, ...]:
    """Per run: the episode from which at least ``share`` of the last ``window`` episodes
    follow ``route_areas`` successfully, to the end of the run (NaN: not converged)."""
    ind = route_indicator(visits, success, route_areas, areas)
    return tuple(settles(row, window, share) for row in ind)


def iqm(x: np.ndarray, axis: int | None = None) -> np.ndarray:
    """Interquartile mean: the mean of the middle 50% of the values."""
    return sps.trim_mean(x, 0.25, axis=axis)


def iqm_ci(scores: Sequence[np.ndarray], seed: int = SEED, level: float = 0.95,
           n_resamples: int = 2000) -> tuple[float, float, float]:
    """IQM of every run's score on every task (``scores``: one array of run scores per
    task) and its stratified percentile bootstrap CI: :func:`scipy.stats.bootstrap` with
    one sample per task resamples runs within each task. The CI is NaN when a task has
    fewer than 2 runs."""
    samples = [s for s in (_finite(s) for s in scores) if s.size]
    if not samples:
        return math.nan, math.nan, math.nan
    point = float(iqm(np.concatenate(samples)))
    if min(s.size for s in samples) < 2:
        return point, math.nan, math.nan

    def statistic(*xs: np.ndarray, axis: int = -1) -> np.ndarray:
        return iqm(np.concatenate(xs, axis=axis), axis=axis)

    res = sps.bootstrap(samples, statistic, n_resamples=n_resamples, confidence_level=level,
                        method="percentile", rng=np.random.default_rng(seed))
    return point, float(res.confidence_interval.low), float(res.confidence_interval.high)
