"""The Wilson 95% interval of every rate (`vinadv.intervals`): against values worked by hand, against the score
test's acceptance region scanned without the closed form, and its properties (it holds the rate, lies in [0, 1],
narrows as n grows)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vinadv.errors import InputError
from vinadv.intervals import (
    BOOTSTRAP_BLOCK,
    Z95,
    bootstrap_mean_interval,
    bootstrap_means,
    figure_intervals,
    interval_fields,
    rate_interval,
    wilson_interval,
)


def hand_wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The textbook formula, written out: centre (k + z^2/2) / (n + z^2), half-width
    z sqrt(n) / (n + z^2) * sqrt(p (1 - p) + z^2 / (4 n)), p = k / n."""
    p = k / n
    centre = (k + z * z / 2) / (n + z * z)
    half = z * math.sqrt(n) / (n + z * z) * math.sqrt(p * (1 - p) + z * z / (4 * n))
    return centre - half, centre + half


def scanned_wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson interval by its definition: the p in [0, 1] whose score test does not reject k of n,
    |k - n p| <= z sqrt(n p (1 - p)), found on a fine grid of p (no closed form used)."""
    p = np.linspace(0.0, 1.0, 400_001)
    keep = np.abs(k - n * p) <= z * np.sqrt(n * p * (1 - p))
    return float(p[keep].min()), float(p[keep].max())


@pytest.mark.parametrize(
    ("k", "n", "low", "high"),
    [
        # worked by hand with z = 1.96 (centre (k + 1.9208) / (n + 3.8416)), to 4 decimals
        (5, 10, 0.2366, 0.7634),  # symmetric about one half
        (0, 10, 0.0, 0.2775),  # z^2 / (n + z^2) = 3.8416 / 13.8416
        (10, 10, 0.7225, 1.0),
        (50, 100, 0.4038, 0.5962),  # about +-10 points at 100 maps
        (71, 100, 0.6146, 0.7899),
    ],
)
def test_the_interval_is_the_hand_worked_one(k, n, low, high):
    got = rate_interval(k, n)
    assert got[0] == pytest.approx(low, abs=2e-4) and got[1] == pytest.approx(high, abs=2e-4)
    want = hand_wilson(k, n, Z95)
    assert got[0] == pytest.approx(max(want[0], 0.0), abs=1e-12) and got[1] == pytest.approx(min(want[1], 1), abs=1e-12)


@pytest.mark.parametrize(("k", "n"), [(0, 1), (1, 1), (0, 12), (12, 12), (3, 7), (95, 100), (1, 2000), (1999, 2000)])
def test_the_interval_is_the_score_tests_acceptance_region(k, n):
    low, high = wilson_interval([k], [n])
    want_low, want_high = scanned_wilson(k, n)
    assert low[0] == pytest.approx(want_low, abs=5e-6) and high[0] == pytest.approx(want_high, abs=5e-6)


def test_the_interval_holds_the_rate_lies_in_0_1_and_narrows_as_n_grows():
    rng = np.random.default_rng(46)
    for _ in range(300):
        n = int(rng.integers(1, 5000))
        k = int(rng.integers(0, n + 1))
        low, high = rate_interval(k, n)
        assert 0.0 <= low <= k / n <= high <= 1.0
        assert low < high  # never empty, at 0% and 100% too
        # the same rate on ten times the maps: a narrower interval
        low10, high10 = rate_interval(10 * k, 10 * n)
        assert high10 - low10 < high - low
    widths = [np.subtract(*wilson_interval(n // 2, n)[::-1]) for n in (2, 10, 100, 1000, 10_000)]
    assert all(a > b for a, b in zip(widths, widths[1:]))


def test_no_rate_has_no_interval():
    assert rate_interval(0, 0) == (None, None)  # no valid map
    assert rate_interval(None, 10) == (None, None) and rate_interval(3, None) == (None, None)
    assert rate_interval(11, 10) == (None, None) and rate_interval(-1, 10) == (None, None)  # not a rate


def test_the_fields_are_named_as_every_reader_writes_them():
    assert interval_fields("success_rate", 5, 10) == {
        "success_rate_low": pytest.approx(0.2366, abs=2e-4),
        "success_rate_high": pytest.approx(0.7634, abs=2e-4),
    }
    figures = {"k": 1, "valid": 10, "broken": 0, "harmful": 10, "paper_success_rate": 0.0, "harmful_rate": 1.0}
    got = figure_intervals(figures)
    assert set(got) == {"paper_success_rate_low", "paper_success_rate_high", "harmful_rate_low", "harmful_rate_high"}
    assert got["paper_success_rate_low"] == 0.0 and got["harmful_rate_high"] == 1.0
    assert figure_intervals({"valid": 0, "broken": 0, "harmful": 0})["harmful_rate_low"] is None


def _reference_bootstrap(values, level, resamples, seed):
    """The percentile bootstrap in plain Python: the same index draws as the definition, each resample's mean by
    a loop, the quantiles by sorting and interpolating between order statistics."""
    x = [v for v in values if v == v]  # NaN left out
    blocks = [min(BOOTSTRAP_BLOCK, resamples - lo) for lo in range(0, resamples, BOOTSTRAP_BLOCK)]
    means = []
    for child, size in zip(np.random.SeedSequence(seed).spawn(len(blocks)), blocks):
        for row in np.random.default_rng(child).integers(0, len(x), (size, len(x))).tolist():
            means.append(sum(x[i] for i in row) / len(x))
    means.sort()

    def quantile(q):
        h = (len(means) - 1) * q
        lo = int(h)
        return means[lo] + (h - lo) * (means[min(lo + 1, len(means) - 1)] - means[lo])

    return quantile((1 - level) / 2), quantile((1 + level) / 2)


@given(
    st.lists(st.floats(-100, 100, allow_nan=False), min_size=1, max_size=12),
    st.sampled_from([1, 7, 260]),
    st.integers(0, 3),
)
@settings(max_examples=25, deadline=None)
def test_the_bootstrap_interval_is_the_plain_python_one(values, resamples, seed):
    got = bootstrap_mean_interval(values + [float("nan")], 0.9, resamples, seed)
    assert got == pytest.approx(_reference_bootstrap(values, 0.9, resamples, seed), abs=1e-9)


def test_the_bootstrap_interval_holds_the_mean_and_is_seeded():
    rng = np.random.default_rng(5)
    values = rng.exponential(2.0, 200)
    low, high = bootstrap_mean_interval(values)
    assert low < values.mean() < high and high - low < 1.5  # about 4 standard errors of 0.14
    assert bootstrap_mean_interval(values) == (low, high)  # the same values, the same interval
    assert bootstrap_mean_interval([3.0, 3.0]) == (3.0, 3.0)
    assert bootstrap_mean_interval([float("nan")]) == (None, None)
    with pytest.raises(InputError, match="resamples"):
        bootstrap_means([1.0], resamples=0)
