"""`draw_map` marks every start it is given; `vinadv maps show --all-starts` marks each start of the map (the
markers' positions against the maps file), and its legend names the markers."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest

from vinadv.cli import main
from vinadv.grid import MapSet
from vinadv.plot import files
from vinadv.plot import maps as draw


def _markers(fig, label: str) -> np.ndarray:
    """(row, col) of the points of the line labelled `label` in `fig`."""
    (ax,) = fig.axes
    lines = [line for line in ax.get_lines() if line.get_label() == label]
    assert len(lines) == 1, [line.get_label() for line in ax.get_lines()]
    x, y = lines[0].get_data()
    return np.stack([np.asarray(y), np.asarray(x)], axis=1)


@pytest.mark.parametrize("all_starts", [True, False])
def test_maps_show_marks_every_start_with_a_legend(tmp_path, monkeypatch, all_starts):
    maps_file = tmp_path / "m.npz"
    assert (
        main(
            [
                "maps",
                "generate",
                "--n",
                "3",
                "--size",
                "12",
                "--starts",
                "5",
                "--seed",
                "2",
                "--out",
                str(maps_file),
                "--quiet",
            ]
        )
        == 0
    )
    maps = MapSet.load(maps_file)
    shown = []
    monkeypatch.setattr(files, "save_figure", lambda fig, path: shown.append(fig))
    assert (
        main(
            ["maps", "show", str(maps_file), "--index", "1", "--out", str(tmp_path / "m.png")]
            + (["--all-starts"] if all_starts else [])
        )
        == 0
    )
    (fig,) = shown
    expected = maps.starts[1] if all_starts else maps.starts[1, :1]
    got = _markers(fig, "starts" if all_starts else "start")
    assert sorted(map(tuple, got.tolist())) == sorted(map(tuple, expected.tolist()))
    assert np.array_equal(_markers(fig, "goal"), maps.goals[1][None])
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert {"goal", "expert"} <= set(legend) and ("starts" if all_starts else "start") in legend
    expert = [line for line in fig.axes[0].get_lines() if line.get_label() == "expert"]
    assert len(expert) == (maps.n_starts if all_starts else 1)
    plt.close(fig)


def test_draw_map_takes_one_start_or_many():
    fig, ax = plt.subplots()
    obstacles = np.zeros((6, 6), bool)
    draw.draw_map(ax, obstacles, np.array([5, 5]), np.array([[0, 1], [2, 3], [4, 0]]))
    draw.draw_map(ax, obstacles, None, np.array([1, 2]))
    lines = {line.get_label(): line.get_data() for line in ax.get_lines()}
    assert np.array_equal(lines["starts"][0], [1, 3, 0]) and np.array_equal(lines["starts"][1], [0, 2, 4])
    assert np.array_equal(lines["start"][0], [2]) and np.array_equal(lines["start"][1], [1])
    plt.close(fig)


@pytest.mark.parametrize("added", [[3, 4], [[3, 4]], [[3, 4], [0, 0], [5, 1]]])
def test_draw_map_marks_every_added_obstacle_once_in_the_legend(added):
    fig, ax = plt.subplots()
    draw.draw_map(ax, np.zeros((6, 6), bool), goal=np.array([5, 5]), start=np.array([0, 1]), added=np.array(added))
    squares = [p for p in ax.patches if p.get_facecolor()[:3] == pytest.approx((1.0, 0x7F / 255, 0x0E / 255))]
    cells = sorted((round(p.get_y() + 0.5), round(p.get_x() + 0.5)) for p in squares)
    assert cells == sorted(map(tuple, np.reshape(added, (-1, 2)).tolist()))
    labels = [label for label in ax.get_legend_handles_labels()[1] if "added" in label]
    assert labels == ["added obstacle" if len(cells) == 1 else "added obstacles"]
    plt.close(fig)
