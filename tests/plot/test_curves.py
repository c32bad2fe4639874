"""The k curve: one line per planner in the palette's colours and markers, its points the rates in percent, its
intervals as bands or (dodged) error bars."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_hex  # noqa: E402

from vinadv.plot.curves import k_curve  # noqa: E402
from vinadv.plot.files import save_figure, svg_text  # noqa: E402
from vinadv.plot.palette import PALETTE  # noqa: E402


def _points(rates, lows, highs):
    return [
        {"k": k, "harmful_rate": r, "harmful_rate_low": lo, "harmful_rate_high": hi}
        for k, (r, lo, hi) in enumerate(zip(rates, lows, highs), start=1)
    ]


SERIES = [
    ("a", _points([0.1, 0.2], [0.05, 0.1], [0.2, 0.3])),
    ("b", _points([0.5, 0.4], [0.4, 0.3], [0.6, 0.5])),
]


def test_each_line_has_the_palettes_colour_and_marker_and_the_rates_in_percent():
    fig = k_curve(SERIES)
    lines = [line for line in fig.axes[0].lines if line.get_label() in ("a", "b")]
    for i, line in enumerate(lines):
        assert to_hex(line.get_color()) == PALETTE.series[i].colour
        assert line.get_marker() == PALETTE.series[i].marker
        np.testing.assert_allclose(line.get_ydata(), [100 * p["harmful_rate"] for p in SERIES[i][1]])
        np.testing.assert_allclose(line.get_xdata(), [1, 2])
    plt.close(fig)


def test_the_legend_names_every_line_beside_the_axes_never_over_a_point():
    fig = k_curve(SERIES * 4)  # eight lines: an inner legend would cover some
    fig.canvas.draw()
    ax = fig.axes[0]
    legend = ax.get_legend()
    assert [t.get_text() for t in legend.get_texts()] == [name for name, _ in SERIES * 4]
    assert legend.get_window_extent().x0 >= ax.get_window_extent().x1
    plt.close(fig)


def test_dodged_lines_move_apart_along_k_and_draw_their_intervals_as_bars():
    fig = k_curve(SERIES, dodge=0.1)
    ax = fig.axes[0]
    xs = [line.get_xdata() for line in ax.lines if line.get_label() in ("a", "b")]
    np.testing.assert_allclose(xs, [[0.95, 1.95], [1.05, 2.05]])
    # each error bar spans the interval: its segments' ends are the lows and highs in percent
    segments = [seg for coll in ax.collections for seg in coll.get_segments()]
    ends = sorted((round(s[0][1], 6), round(s[1][1], 6)) for s in segments)
    expected = sorted((100 * p["harmful_rate_low"], 100 * p["harmful_rate_high"]) for _, ps in SERIES for p in ps)
    np.testing.assert_allclose(ends, expected)
    plt.close(fig)


@pytest.mark.slow  # two SVG renderings: about a second each on a loaded 2-core machine
def test_an_svg_has_the_same_bytes_for_the_same_figure(tmp_path):
    save_figure(k_curve(SERIES), tmp_path / "a.svg")
    written = (tmp_path / "a.svg").read_text(encoding="utf-8")
    assert svg_text(k_curve(SERIES)) == written and "<dc:date>" not in written
