"""The k curve: a rate (by default the harmful rate) against the number of edited cells k, one line per planner,
with its interval as a band where one is given."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from vinadv.errors import InputError
from vinadv.plot.maps import figure_for
from vinadv.plot.palette import PALETTE

#: the strategy name of a benchmark's worst case over its strategies (`vinadv.robustness.WORST_CASE`)
WORST_CASE = "worst case"


def k_series(data, rate: str = "harmful_rate", strategy: str = WORST_CASE) -> list[tuple[str, list[dict]]]:
    """`[(name, points)]`, one per line, each point a dict with `k`, `rate` and, where present, `rate_low` and
    `rate_high` (its interval, fractions).

    `data`: `vinadv.open(...).robustness()` (a DataFrame: the rows of `strategy`, one line per benchmark, named by
    planner, or by planner and benchmark where a planner has several), a mapping `{name: points}`, or a sequence of
    `(name, points)`; points are dicts (or rows) with `k` and `rate` (`vinadv.robustness.Figures.to_dict`)."""
    if hasattr(data, "columns"):  # the robustness DataFrame
        if "strategy" in data.columns:
            data = data[data["strategy"] == strategy]
        if not len(data):
            raise InputError(f"k_curve: no rows of strategy {strategy!r} to draw", "data")
        key = "benchmark" if "benchmark" in data.columns else "planner"
        groups = list(data.groupby(key, sort=False))
        counts: dict = {}
        for _, rows in groups:
            counts[rows["planner"].iloc[0]] = counts.get(rows["planner"].iloc[0], 0) + 1
        series = []
        for bench, rows in groups:
            planner = rows["planner"].iloc[0]
            name = planner if counts[planner] == 1 else f"{planner} (#{bench})"
            series.append((str(name), rows.sort_values("k").to_dict("records")))
        return series
    items = list(data.items()) if isinstance(data, Mapping) else list(data)
    return [(str(name), [dict(p) for p in points]) for name, points in items]


def draw_k_curve(
    ax,
    data,
    rate: str = "harmful_rate",
    strategy: str = WORST_CASE,
    intervals: bool = True,
    xlabel: str = "obstacles added (k)",
    dodge: float = 0.0,
) -> None:
    """The k curve on `ax` (see `k_series` for `data`): `rate` in % against k, one line per series in the palette's
    chart lines (`PALETTE.line(i)`: a colour and a marker each), each point's interval (`{rate}_low`, `{rate}_high`)
    a band where given and `intervals`. A missing value (None) leaves a gap. `dodge`: each line shifted along k by
    this much from the next (centred on k), its intervals then drawn as error bars: lines that coincide (several
    planners at 0%) stay apart."""
    series = k_series(data, rate, strategy)
    for i, (name, points) in enumerate(series):
        shift = dodge * (i - (len(series) - 1) / 2)
        ks = np.array([p["k"] for p in points], dtype=np.float64) + shift
        values = np.array([np.nan if p.get(rate) is None else 100.0 * p[rate] for p in points])
        style = PALETTE.line(i)
        colour = style.colour
        ax.plot(ks, values, marker=style.marker, ls=style.line, color=colour, mec=PALETTE.edge.colour, label=name)
        low, high = (f"{rate}_low", f"{rate}_high")
        if intervals and all(p.get(low) is not None and p.get(high) is not None for p in points) and points:
            lows = np.array([100.0 * p[low] for p in points])
            highs = np.array([100.0 * p[high] for p in points])
            if dodge:
                ax.errorbar(ks, values, yerr=[values - lows, highs - values], fmt="none", ecolor=colour, capsize=2)
            else:
                ax.fill_between(ks, lows, highs, color=colour, alpha=0.18, linewidth=0)
    top = max([1] + [int(p["k"]) for _, points in series for p in points])
    ax.set_xticks(range(1, top + 1))
    ax.set_xlabel(xlabel)
    ax.grid(alpha=0.3)


def k_curve(
    data,
    rate: str = "harmful_rate",
    *,
    strategy: str = WORST_CASE,
    intervals: bool = True,
    ax=None,
    title: str | None = None,
    xlabel: str = "obstacles added (k)",
    dodge: float = 0.0,
):
    """Draw the k curve (`draw_k_curve`): `rate` (`harmful_rate`, `paper_success_rate`, any rate column) against k,
    one line per planner, on `ax` or a new figure (`xlabel`, `dodge`: as `draw_k_curve`), its legend beside the axes;
    returns the figure.

        with vinadv.open("results.db") as results:
            vinadv.plot.k_curve(results.robustness())
    """
    fig, ax = figure_for(ax, (5, 3.6))
    draw_k_curve(ax, data, rate, strategy, intervals, xlabel, dodge)
    ax.set_ylabel(f"{rate.replace('_', ' ')} (% of valid maps)")
    ax.set_ylim(-2, 102)  # a point at 0% or 100% drawn whole
    ax.set_title(title or rate.replace("_", " "), fontsize=9)
    # beside the axes, not on them: with several planners an inner legend hides points (a saved figure's tight
    # bounding box takes it in)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    return fig
