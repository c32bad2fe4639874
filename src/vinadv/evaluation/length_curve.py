"""The success-by-path-length curve: rollout success against the optimal path's move count, the plot that the VIN
literature compares planners with (Highway VIN and DT-VIN plot success falling as paths grow long).

It is drawn from the `by_length` rows of an evaluation (`vinadv.evaluation.planner_metrics.rollout_metrics`: buckets of
`LENGTH_BUCKET` optimal moves), so a committed metrics file redraws it without planning anything. Each bucket is
labelled on the x axis by its move range; success is shown with its 95% Wilson score interval (a bucket of a few
rollouts is noisy, and the interval says how much), and a lower panel counts the rollouts per bucket on a log
scale, so a reader sees where the curve rests on few paths.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from vinadv.errors import InputError  # noqa: E402
from vinadv.intervals import wilson_interval  # noqa: E402
from vinadv.planners.records import LengthBucketMetrics  # noqa: E402
from vinadv.plot.files import save_figure, svg_text  # noqa: E402

__all__ = [
    "LengthCurve",
    "by_length_rows",
    "length_curve",
    "save_success_by_length",
    "success_by_length_figure",
    "svg_text",
]


@dataclass(frozen=True)
class LengthCurve:
    """One planner's success by optimal path length, one entry per non-empty bucket, in move order.

    Attributes:
        low, high: `(B,)` int, the bucket's optimal move counts, inclusive.
        rollouts: `(B,)` int, rollouts in the bucket.
        successes: `(B,)` int, those that reached the goal.
        rate: `(B,)` float, successes / rollouts.
        ci_low, ci_high: `(B,)` float, the 95% Wilson score interval of `rate`.
    """

    low: np.ndarray
    high: np.ndarray
    rollouts: np.ndarray
    successes: np.ndarray
    rate: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray


def length_curve(rows: Sequence[LengthBucketMetrics]) -> LengthCurve:
    """The curve of `by_length` rows (any order; empty buckets are absent from them). Success counts are recovered
    as `round(success_rate * rollouts)`, exact since the rate is that quotient. InputError for no rows."""
    rows = sorted(rows, key=lambda r: r["moves"][0])
    if not rows:
        raise InputError("by_length: no rollouts to draw")
    low = np.array([r["moves"][0] for r in rows], dtype=np.int64)
    high = np.array([r["moves"][1] for r in rows], dtype=np.int64)
    n = np.array([r["rollouts"] for r in rows], dtype=np.int64)
    k = np.rint(np.array([r["success_rate"] for r in rows], dtype=np.float64) * n).astype(np.int64)
    ci_low, ci_high = wilson_interval(k, n)
    return LengthCurve(low, high, n, k, k / n, ci_low, ci_high)


def by_length_rows(record: Mapping) -> list[LengthBucketMetrics]:
    """The `by_length` rows of an evaluation record: `vinadv vin eval`'s flat record, or `vinadv eval`'s with the
    figures under `"vinadv"`. InputError when it has none (another protocol, or a record without them)."""
    figures = record.get("vinadv", record)
    rows = figures.get("by_length") if isinstance(figures, Mapping) else None
    if not rows:
        raise InputError("the figures have no rollouts by optimal path length (the vinadv protocol records them)")
    return list(rows)


def success_by_length_figure(curves: Sequence[tuple[str, Sequence[LengthBucketMetrics]]], title: str | None = None):
    """A matplotlib Figure: rollout success (%) against the optimal path's move count, one line per `(label,
    by_length rows)` in `curves` with its 95% Wilson band, and below it the rollouts per bucket (log scale).

    Buckets are placed at their ranges (`low`..`high` moves), so curves of maps of different sizes (28x28 and
    64x64, whose paths run to different lengths) share one axis; every bucket present in a curve is labelled."""
    if not curves:
        raise InputError("no curves to draw")
    drawn = [(label, length_curve(rows)) for label, rows in curves]
    fig, (ax, ax_n) = plt.subplots(
        2, 1, figsize=(8, 5.2), sharex=True, gridspec_kw={"height_ratios": [3, 1.2]}, layout="constrained"
    )
    for i, (label, c) in enumerate(drawn):
        x = (c.low + c.high) / 2
        (line,) = ax.plot(x, 100 * c.rate, marker="o", markersize=3.5, linewidth=1.4, label=label)
        ax.fill_between(x, 100 * c.ci_low, 100 * c.ci_high, color=line.get_color(), alpha=0.18, linewidth=0)
        # the curves' bars side by side within each bucket (curves on the same maps have the same counts)
        span = (c.high - c.low + 1) * 0.9
        width = span / len(drawn)
        ax_n.bar(x - span / 2 + width * (i + 0.5), c.rollouts, width=width, color=line.get_color(), alpha=0.5)
    lows = np.unique(np.concatenate([c.low for _, c in drawn]))
    highs = {int(lo): int(hi) for _, c in drawn for lo, hi in zip(c.low, c.high, strict=True)}
    ax_n.set_xticks((lows + np.array([highs[int(lo)] for lo in lows])) / 2)
    ax_n.set_xticklabels([f"{lo}-{highs[int(lo)]}" for lo in lows], rotation=60, ha="right", fontsize=7)
    ax.set_ylabel("rollout success (%)")
    top = max(float(c.ci_low.min()) for _, c in drawn)
    ax.set_ylim(max(0.0, 100 * top - 5) if top > 0.5 else 0.0, 100.5)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax_n.set_yscale("log")
    ax_n.set_ylabel("rollouts")
    ax_n.set_xlabel("optimal path length (moves), buckets")
    ax_n.grid(True, alpha=0.3)
    if title:
        ax.set_title(title, fontsize=10)
    return fig


def save_success_by_length(
    curves: Sequence[tuple[str, Sequence[LengthBucketMetrics]]], path: str | os.PathLike, title: str | None = None
) -> None:
    """Draw `success_by_length_figure(curves, title)` to `path` (png, svg or pdf by its extension), atomically; an
    SVG keeps its text as text (searchable)."""
    with plt.rc_context({"svg.fonttype": "none"}):
        save_figure(success_by_length_figure(curves, title), path)
