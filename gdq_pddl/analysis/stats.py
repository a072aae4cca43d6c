"""Statistics for the hypotheses: per-run summaries, GDQ-vs-baseline tests, milestones.

Every comparison is between *runs* (the independent unit): one number per run for each
method, then Welch's t-test (unequal variances) and a percentile bootstrap 95% CI of the
difference in means (runs resampled with replacement within each method, a numpy
Generator with a fixed seed). A difference is *significant* when the CI excludes 0 and
the two-sided p-value is below ``alpha`` (when the t-test is undefined, e.g. two
constant samples, the CI alone decides).

Verdicts (:func:`verdict`) over the comparisons of GDQ with each baseline:

- ``holds``: GDQ is significantly better than every baseline;
- ``does not hold``: GDQ is significantly worse than at least one baseline, or
  significantly better than none;
- ``mixed``: better than some, indistinguishable from the others, worse than none.

Milestones on a return curve use a trailing moving average over *full* windows only:
the value at episode ``e`` (1-based) is the mean of episodes ``e - w + 1 .. e``, defined
from episode ``w`` on, so one lucky early episode cannot count as a milestone.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
from scipy import stats as sps

ALPHA = 0.05
N_BOOT = 10_000
SEED = 20240501

HOLDS, DOES_NOT_HOLD, MIXED = "holds", "does not hold", "mixed"


def run_means(matrix: np.ndarray, start: int = 0, stop: int | None = None) -> np.ndarray:
    """Per-run mean of ``matrix[runs, episodes]`` over episode columns ``start:stop``."""
    if matrix.size == 0:
        return np.empty(0)
    with _quiet():
        return np.nanmean(matrix[:, start:stop], axis=1)


@contextmanager
def _quiet() -> Iterator[None]:
    """Silence numpy's 'mean of empty slice' warnings (an empty slice gives NaN)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", category=RuntimeWarning)
        yield


def mean_se(x: np.ndarray, axis: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error (ddof=1; 0 with a single sample) along ``axis``, NaN-aware."""
    x = np.asarray(x, dtype=float)
    with _quiet():
        mean = np.nanmean(x, axis=axis)
        n = np.sum(~np.isnan(x), axis=axis)
        sd = np.nanstd(x, axis=axis, ddof=1) if x.shape[axis] > 1 else np.zeros_like(mean)
    se = np.where(n > 1, sd / np.sqrt(np.maximum(n, 1)), 0.0)
    return mean, se


@dataclass(frozen=True)
class Comparison:
    """``a`` (GDQ) against ``b`` (a baseline): difference ``mean(a) - mean(b)``.

    ``higher_is_better`` says which sign favours ``a``; :attr:`outcome` is ``better``,
    ``worse`` or ``inconclusive`` for ``a``.
    """

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


def bootstrap_ci(a: np.ndarray, b: np.ndarray, n_boot: int = N_BOOT, seed: int = SEED,
                 level: float = 0.95) -> tuple[float, float]:
    """Percentile bootstrap CI of ``mean(a) - mean(b)`` (each resampled with replacement)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    a, b = a[~np.isnan(a)], b[~np.isnan(b)]
    if a.size == 0 or b.size == 0:
        return math.nan, math.nan
    rng = np.random.default_rng(seed)
    ma = a[rng.integers(0, a.size, size=(n_boot, a.size))].mean(axis=1)
    mb = b[rng.integers(0, b.size, size=(n_boot, b.size))].mean(axis=1)
    lo, hi = np.quantile(ma - mb, [(1 - level) / 2, (1 + level) / 2])
    return float(lo), float(hi)


def welch(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Welch's t statistic and two-sided p-value (NaN when undefined)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    a, b = a[~np.isnan(a)], b[~np.isnan(b)]
    if a.size < 2 or b.size < 2 or (np.ptp(a) == 0 and np.ptp(b) == 0):
        return math.nan, math.nan
    # nearly constant samples (a method that fails identically in every run) make scipy
    # warn about precision; the statistic it returns is still the right one to report
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "Precision loss occurred", RuntimeWarning)
        res = sps.ttest_ind(a, b, equal_var=False)
    return float(res.statistic), float(res.pvalue)


def compare(a: np.ndarray, b: np.ndarray, name_a: str = "GDQ", name_b: str = "baseline",
            higher_is_better: bool = True, seed: int = SEED, alpha: float = ALPHA) -> Comparison:
    """Welch's t-test and bootstrap CI of ``mean(a) - mean(b)`` over runs."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    t, p = welch(a, b)
    lo, hi = bootstrap_ci(a, b, seed=seed)
    with _quiet():
        ma, mb = float(np.nanmean(a)), float(np.nanmean(b))
    return Comparison(name_a, name_b, ma, mb, ma - mb, lo, hi, t, p,
                      int(np.sum(~np.isnan(a))), int(np.sum(~np.isnan(b))),
                      higher_is_better, alpha)


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
    parts = []
    for outcome, words in groups.items():
        names = [c.b for c in comparisons if c.outcome == outcome]
        if names:
            parts.append(f"{words} {', '.join(names)}")
    return "; ".join(parts) or "no baselines"


def moving_average(x: np.ndarray, window: int, full_only: bool = True) -> np.ndarray:
    """Trailing moving average along the last axis.

    With ``full_only`` the first ``window - 1`` values are NaN; otherwise they average the
    episodes seen so far (the figures' smoothing, so curves start at episode 1).
    NaNs in ``x`` propagate.
    """
    x = np.asarray(x, dtype=float)
    window = max(1, int(window))
    n = x.shape[-1]
    pad = np.zeros((*x.shape[:-1], 1))
    c = np.concatenate([pad, np.cumsum(x, axis=-1)], axis=-1)
    idx = np.arange(1, n + 1)
    lo = np.maximum(idx - window, 0)
    out = (c[..., idx] - c[..., lo]) / (idx - lo)
    if full_only:
        out[..., : min(window - 1, n)] = np.nan
    return out


def first_crossing(curve: np.ndarray, window: int = 50, threshold: float = 0.0) -> float:
    """1-based episode at which the full-window moving average of ``curve`` first exceeds
    ``threshold`` (NaN if never)."""
    ma = moving_average(curve, window)
    hits = np.flatnonzero(ma > threshold)
    return float(hits[0] + 1) if hits.size else math.nan


@dataclass(frozen=True)
class Milestone:
    """When a method's return first turns positive (see :func:`first_positive`)."""

    per_run: tuple[float, ...]
    """Per run (NaN: never within the data)."""
    on_mean_curve: float
    """On the mean curve over runs (the headline figure: what the learning curve shows)."""

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
    per_run = tuple(first_crossing(row, window, threshold) for row in matrix)
    with _quiet():
        mean_curve = np.nanmean(matrix, axis=0)
    return Milestone(per_run, first_crossing(mean_curve, window, threshold))


def settles(indicator: np.ndarray, window: int, share: float) -> float:
    """1-based episode from which the trailing ``window``-episode share of ``indicator``
    stays at or above ``share`` to the end of the data (NaN if it never does)."""
    ind = np.asarray(indicator, dtype=float)
    if ind.size < window:
        return math.nan
    ma = moving_average(ind, window)
    ok = ma >= share - 1e-12
    ok[: window - 1] = False
    if not ok[-1]:
        return math.nan
    bad = np.flatnonzero(~ok)
    return float(bad[-1] + 2) if bad.size else 1.0


def route_indicator(visits: np.ndarray, success: np.ndarray, route_areas: Sequence[int],
                    areas: Sequence[int]) -> np.ndarray:
    """Per episode: succeeded and visited exactly the areas of ``route_areas``.

    ``visits`` is ``[..., n_areas]`` (areas in the order of ``areas``). For Task C the
    area sets tell the three candidate routes apart: {1,2,6} (d0), {1,3,6} (d2) and
    {1,2,3,6} (d1 and d3). Slips that wander into an extra area count as off-route.
    """
    on = np.array([a in set(route_areas) for a in areas])
    visited = visits > 0
    exact = np.all(visited[..., on], axis=-1) & ~np.any(visited[..., ~on], axis=-1)
    return exact & (success > 0)


def convergence_episode(visits: np.ndarray, success: np.ndarray, route_areas: Sequence[int],
                        areas: Sequence[int], window: int = 50,
                        share: float = 0.5) -> tuple[float, ...]:
    """Per run: the episode from which at least ``share`` of the last ``window`` episodes
    follow ``route_areas`` successfully, to the end of the run (NaN: not converged).

    The CSV has no per-episode policies, so convergence is read off behaviour: the
    episode's area visits (see :func:`route_indicator`).
    """
    ind = route_indicator(visits, success, route_areas, areas)
    return tuple(settles(row, window, share) for row in ind)
