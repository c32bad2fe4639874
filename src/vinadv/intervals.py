"""Intervals of vinadv's rates: the Wilson score interval at 95% (z = 1.96), over the maps (or rollouts) counted in
the rate's denominator.

Every rate vinadv reports is a count over a count: paper success, harmful and effort-harmful rate are maps over the
valid maps (`vinadv.robustness.Figures`), clean success and the share of optimal paths are maps over the maps. Its
interval is computed at read from those counts (`wilson_interval`, `rate_interval`), so what was stored before
intervals existed (robustness results, `vinadv.bench_entry/1` entries) gets them too. `interval_fields` names them
as every reader writes them: `{rate}_low` and `{rate}_high`, fractions in [0, 1] like the rate, None where the rate
is None. The Wilson interval, unlike the normal approximation, stays inside [0, 1] and is not empty at 0% or 100%:
with 100 maps a rate near one half is known to about +-10 points.

A mean over maps (a mean regret, and to come Exp and the cost and effort ratios) gets a seeded percentile bootstrap
interval instead (`bootstrap_mean_interval`): the maps are resampled with replacement `BOOTSTRAP_RESAMPLES` times,
and the interval is the 2.5th and 97.5th percentiles of the resamples' means. It needs the per-map values, so it is
computed where they exist (a robustness run's per-map outcomes); a record that holds only the mean has none. The
seed is fixed (`BOOTSTRAP_SEED`): the same values give the same interval, so an entry or a result reproduces.

This module knows only NumPy and the rates' names: the bench, the report, the robustness run, the analysis and the
evaluation all read it.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from vinadv.errors import InputError

__all__ = [
    "BOOTSTRAP_RESAMPLES",
    "BOOTSTRAP_SEED",
    "FIGURE_RATES",
    "Z95",
    "figure_intervals",
    "interval_fields",
    "rate_interval",
    "wilson_interval",
    "interval_columns",
    "bootstrap_mean_interval",
    "bootstrap_means",
]

#: resamples of a bootstrap interval, drawn in blocks of `BOOTSTRAP_BLOCK` (each from its own child stream of the
#: seed, so memory stays `BOOTSTRAP_BLOCK` x n whatever n, and the draws never depend on it)
BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_BLOCK = 250
#: the bootstrap's seed: fixed, so that the same values give the same interval
BOOTSTRAP_SEED = 0

#: z of the two-sided 95% interval
Z95 = 1.959963984540054

#: the rates of a robustness figure (`vinadv.robustness.Figures.to_dict`, an entry's `by_obstacles` and
#: `worst_case`): rate -> (its numerator's count, its denominator's count)
FIGURE_RATES = {
    "paper_success_rate": ("broken", "valid"),
    "harmful_rate": ("harmful", "valid"),
    # a search planner's figures only (`vinadv.classify.effort`): absent from the others' figures
    "effort_harmful_rate": ("effort_harmful", "valid"),
}
#: the rates a figure has only where its planner reports expansions: no interval where their count is absent
OPTIONAL_RATES = ("effort_harmful_rate",)


def wilson_interval(successes, n, z: float = Z95) -> tuple[np.ndarray, np.ndarray]:
    """The Wilson score interval of the proportions `successes / n` (arrays of counts, `n >= 1`): `(low, high)`,
    both in [0, 1]. Unlike the normal approximation it stays inside [0, 1] and is not empty at 0% or 100%."""
    k = np.asarray(successes, dtype=np.float64)
    n = np.asarray(n, dtype=np.float64)
    p = k / n
    z2 = z * z
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = z * np.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    # at 0 and at n the ends are exactly 0 and 1 (centre -/+ half cancels there but for rounding)
    low = np.where(k == 0, 0.0, np.clip(centre - half, 0.0, 1.0))
    high = np.where(k == n, 1.0, np.clip(centre + half, 0.0, 1.0))
    return low, high


def rate_interval(count, n) -> tuple[float | None, float | None]:
    """The 95% Wilson interval of the rate `count / n` as two floats; `(None, None)` where there is no rate (`n` 0 or
    None, `count` None) or the counts are not a rate (`count` outside [0, n])."""
    if count is None or n is None or isinstance(count, bool) or isinstance(n, bool):
        return None, None
    if not 0 <= count <= n or n <= 0:
        return None, None
    low, high = wilson_interval(count, n)
    return float(low), float(high)


def interval_fields(rate: str, count, n) -> dict[str, float | None]:
    """`{f"{rate}_low": ..., f"{rate}_high": ...}`: the rate's interval (`rate_interval`) named as readers write it."""
    low, high = rate_interval(count, n)
    return {f"{rate}_low": low, f"{rate}_high": high}


def figure_intervals(figures: Mapping) -> dict[str, float | None]:
    """The intervals of a robustness figure's rates (`FIGURE_RATES`), from its counts: `paper_success_rate_low`,
    `paper_success_rate_high`, `harmful_rate_low`, `harmful_rate_high` (None where a count is missing), and
    `effort_harmful_rate_low`, `effort_harmful_rate_high` where the figure has an `effort_harmful` count."""
    out: dict[str, float | None] = {}
    for rate, (count, n) in FIGURE_RATES.items():
        if rate in OPTIONAL_RATES and figures.get(count) is None:
            continue
        out.update(interval_fields(rate, figures.get(count), figures.get(n)))
    return out


def interval_columns(*rates: str) -> tuple[str, ...]:
    """Each rate's column followed by its interval's (`{rate}_low`, `{rate}_high`): the columns of a table or frame
    that shows the rates with their intervals."""
    return tuple(column for rate in rates for column in (rate, f"{rate}_low", f"{rate}_high"))


def bootstrap_means(values, resamples: int = BOOTSTRAP_RESAMPLES, seed: int = BOOTSTRAP_SEED) -> np.ndarray:
    """`(resamples,)` the means of `resamples` resamples with replacement of `values` (`(n,)`, n >= 1, finite).
    Resample block `b` (`BOOTSTRAP_BLOCK` resamples) draws its indices as
    `default_rng(SeedSequence(seed).spawn(blocks)[b]).integers(0, n, (size, n))`."""
    x = np.asarray(values, dtype=np.float64).reshape(-1)
    if len(x) == 0:
        raise InputError("values: no value to resample", "values")
    if resamples < 1:
        raise InputError(f"resamples must be >= 1, got {resamples}", "resamples")
    sizes = [min(BOOTSTRAP_BLOCK, resamples - lo) for lo in range(0, resamples, BOOTSTRAP_BLOCK)]
    children = np.random.SeedSequence(seed).spawn(len(sizes))
    means = [
        x[np.random.default_rng(c).integers(0, len(x), (size, len(x)))].mean(axis=1) for c, size in zip(children, sizes)
    ]
    return np.concatenate(means)


def bootstrap_mean_interval(
    values, level: float = 0.95, resamples: int = BOOTSTRAP_RESAMPLES, seed: int = BOOTSTRAP_SEED
) -> tuple[float | None, float | None]:
    """The percentile bootstrap interval of the mean of `values` (`(n,)`; NaN, a map without a value, left out):
    the `(1 - level) / 2` and `(1 + level) / 2` quantiles (linear interpolation) of `bootstrap_means`;
    `(None, None)` without a value."""
    x = np.asarray(values, dtype=np.float64).reshape(-1)
    x = x[~np.isnan(x)]
    if len(x) == 0:
        return None, None
    low, high = np.quantile(bootstrap_means(x, resamples, seed), [(1 - level) / 2, (1 + level) / 2])
    return float(low), float(high)
