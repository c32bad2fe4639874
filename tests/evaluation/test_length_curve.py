"""The success-by-path-length curve: the curve's points against the `by_length` rows it is drawn from (its Wilson
intervals: tests/test_intervals.py), and `vinadv eval --figure` / `vin eval --figure` end to end."""

import json
import math

import pytest

from tests.cli_files import generated_maps_file
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.evaluation.length_curve import (
    by_length_rows,
    length_curve,
    success_by_length_figure,
    svg_text,
)

SIZE = 10


def rows_of(counts: dict[int, tuple[int, int]]) -> list[dict]:
    """`by_length` rows from {bucket start: (successes, rollouts)}, buckets of 5 moves, in reverse order."""
    return [
        {"moves": [lo, lo + 4], "rollouts": n, "success_rate": k / n, "optimal_rate": k / n, "terminations": {}}
        for lo, (k, n) in sorted(counts.items(), reverse=True)
    ]


def test_the_curve_is_the_rows_in_move_order_with_their_counts():
    curve = length_curve(rows_of({0: (7, 7), 10: (2, 3), 5: (29, 31)}))  # bucket 15-19 empty: absent
    assert curve.low.tolist() == [0, 5, 10] and curve.high.tolist() == [4, 9, 14]
    assert curve.rollouts.tolist() == [7, 31, 3] and curve.successes.tolist() == [7, 29, 2]
    assert curve.rate.tolist() == [1.0, 29 / 31, 2 / 3]
    with pytest.raises(InputError, match="no rollouts"):
        length_curve([])


@pytest.mark.slow  # matplotlib's first figure: about a second
def test_the_figure_plots_each_bucket_at_its_range_with_its_label():
    a = rows_of({0: (7, 7), 5: (29, 31), 10: (2, 3)})
    b = rows_of({0: (4, 4), 20: (1, 2)})
    fig = success_by_length_figure([("a", a), ("b", b)], "t")
    ax, ax_n = fig.axes
    lines = {line.get_label(): line for line in ax.get_lines()}
    assert lines["a"].get_xdata().tolist() == [2, 7, 12]
    assert lines["a"].get_ydata().tolist() == pytest.approx([100, 100 * 29 / 31, 100 * 2 / 3])
    assert lines["b"].get_xdata().tolist() == [2, 22] and lines["b"].get_ydata().tolist() == [100, 50]
    # every bucket of either curve is labelled, once, at its middle
    assert [t.get_text() for t in ax_n.get_xticklabels()] == ["0-4", "5-9", "10-14", "20-24"]
    assert ax_n.get_xticks().tolist() == [2, 7, 12, 22]
    assert sorted(bar.get_height() for bar in ax_n.patches) == [2, 3, 4, 7, 31]
    svg = svg_text(fig)
    assert svg == svg_text(success_by_length_figure([("a", a), ("b", b)], "t"))  # same data, same bytes
    assert "20-24" in svg and "<text" in svg  # text kept as text


def test_by_length_rows_reads_both_record_layouts():
    rows = rows_of({0: (1, 1)})
    assert by_length_rows({"by_length": rows}) == rows  # `vin eval`
    assert by_length_rows({"planner": {}, "vinadv": {"by_length": rows}}) == rows  # `vinadv eval`
    with pytest.raises(InputError, match="vinadv protocol"):
        by_length_rows({"gppn": {"percent_success": 1.0}})


@pytest.fixture(scope="module")
def maps_file(tmp_path_factory):
    return generated_maps_file(tmp_path_factory.mktemp("curve"), 6, SIZE, seed=4, n_starts=3)


@pytest.mark.slow  # an evaluation and a figure
def test_eval_draws_the_curve_of_its_figures(maps_file, tmp_path):
    out, figure = tmp_path / "m.json", tmp_path / "c.svg"
    argv = ["eval", "--planner", "optimal", "--data", maps_file, "--protocol", "vinadv"]
    assert main([*argv, "--out", str(out), "--figure", str(figure), "--quiet"]) == 0
    rows = json.loads(out.read_text())["vinadv"]["by_length"]
    svg = figure.read_text()
    assert svg.lstrip().startswith("<?xml") and "optimal" in svg  # the legend names the planner
    for row in rows:  # text kept as text: each bucket's label is in the file
        assert f"{row['moves'][0]}-{row['moves'][1]}" in svg
    assert math.isclose(sum(r["rollouts"] for r in rows), 18)


@pytest.mark.parametrize(
    ("extra", "why"),
    [
        (["--figure", "c.txt"], "no image file name"),
        (["--figure", "c.png", "--protocol", "gppn"], "needs the vinadv protocol"),
    ],
)
def test_eval_refuses_a_figure_it_cannot_draw_before_the_work(tmp_path, monkeypatch, capsys, extra, why):
    monkeypatch.chdir(tmp_path)  # no maps file either: the figure is refused before the maps are read
    assert main(["eval", "--planner", "optimal", "--data", "maps.npz", *extra, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert why in err and "--figure" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())
