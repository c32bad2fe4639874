"""`vinadv.plot.pair` draws a stored pair from a row of `vinadv.open(...).pairs()` (the same pair as the records the
row was made of), from a pairs file and an index, and `vinadv maps show` draws pairs and paths files."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest

import vinadv.plot
from vinadv.analysis import pairs_table, to_frame
from vinadv.attacks.pairs import PairSet
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import MapSet
from vinadv.plot import files, maps
from vinadv.testing.store import random_records


def lines(fig) -> dict[str, list[np.ndarray]]:
    """{label: [(row, col) points of each line so labelled]} of the figure's axes."""
    found: dict = {}
    for ax in fig.axes:
        for line in ax.get_lines():
            x, y = line.get_data()
            found.setdefault(line.get_label(), []).append(np.stack([np.asarray(y), np.asarray(x)], axis=1))
    return found


def test_a_dataframe_row_draws_the_stored_pair():
    records = random_records(6, size=7, seed=4, n_added=2, removes=0.5, max_path=9)
    records.no = np.arange(1, 7)  # as read back from a store
    frame = to_frame(pairs_table(records, run_id=1))
    for i in range(len(records)):
        drawn, stored = maps.as_pair(frame.iloc[i]), maps.as_pair(records, i)
        for field in ("obstacles_o", "obstacles_a", "start", "goal", "added", "path_o", "path_a"):
            assert np.array_equal(getattr(drawn, field), getattr(stored, field)), field
        assert (drawn.removed, drawn.pair_index, drawn.label, drawn.harm) == (
            stored.removed,
            stored.pair_index,
            stored.label,
            None if records.harm[i] is None else stored.harm,
        )
        assert np.array_equal(maps.as_pair(frame, i).path_a, drawn.path_a)  # the DataFrame and a row number
    i = int(np.flatnonzero((np.diff(records.path_o.offsets) > 0) & (np.diff(records.path_a.offsets) > 0))[0])
    fig = vinadv.plot.pair(frame.iloc[i], expanded_a=np.array([[1, 1], [2, 2]]))
    drawn = lines(fig)
    assert np.array_equal(drawn["adversarial"][0], records.path_a[i])
    assert all(np.array_equal(p, records.path_o[i]) for p in drawn["original"]) and len(drawn["original"]) == 2
    assert fig.axes[1].get_images()[1].get_array()[2, 2, 3] in (0, 1)  # the tint is drawn on the adversarial map
    assert [t.get_text() for t in fig.legends[0].get_texts()][-1] in {"added obstacles", "removed obstacles"}
    plt.close(fig)


def test_pair_refuses_what_it_cannot_draw():
    records = random_records(2, size=5)
    with pytest.raises(InputError, match="index"):
        maps.as_pair(records)
    with pytest.raises(InputError, match="out of range"):
        maps.as_pair(records, 2)
    with pytest.raises(InputError, match="map_o"):
        maps.as_pair({"path_o": []})


@pytest.fixture(scope="module")
def files_made(tmp_path_factory):
    """A maps file, the optimal planner's paths file and a two-obstacle pairs file of it (10x10, 3 maps)."""
    folder = tmp_path_factory.mktemp("show")
    m, p, a = (str(folder / f"{name}.npz") for name in ("m", "p", "a"))
    assert main(["maps", "generate", "--n", "3", "--size", "10", "--starts", "2", "--out", m, "--quiet"]) == 0
    assert main(["plan", "--maps", m, "--planner", "optimal", "--out", p, "--quiet"]) == 0
    common = ["--maps", m, "--planner", "optimal", "--strategy", "random", "--obstacles", "2", "--quiet"]
    assert main(["attack", *common, "--out", a]) == 0
    return folder, m, p, a


def test_maps_show_draws_a_pair_of_a_pairs_file(files_made, monkeypatch):
    folder, _, _, a = files_made
    shown = []
    monkeypatch.setattr(files, "save_figure", lambda fig, path: shown.append(fig))
    assert main(["maps", "show", a, "--index", "1", "--out", str(folder / "x.png")]) == 0
    (fig,) = shown
    pairs = PairSet.load(a)
    drawn = lines(fig)
    assert np.array_equal(drawn["adversarial"][0], pairs.path_a[1])
    added = [p for p in fig.axes[1].patches if p.get_label() != "expanded cells"]
    cells = sorted((round(p.get_y() + 0.5), round(p.get_x() + 0.5)) for p in added)
    assert cells == sorted(map(tuple, pairs.added[1].tolist()))
    plt.close(fig)


def test_maps_show_draws_the_planned_paths_of_a_paths_file(files_made, monkeypatch, capsys):
    folder, m, p, _ = files_made
    shown = []
    monkeypatch.setattr(files, "save_figure", lambda fig, path: shown.append(fig))
    assert main(["maps", "show", p, "--maps", m, "--index", "2", "--all-starts", "--out", str(folder / "y.png")]) == 0
    (fig,) = shown
    maps_file = MapSet.load(m)
    planned = lines(fig)["planned"]
    assert len(planned) == 2 and np.array_equal(planned[1][-1], maps_file.goals[2])
    plt.close(fig)
    assert main(["maps", "show", p, "--out", str(folder / "z.png")]) == 2
    assert "--maps" in capsys.readouterr().err


def test_maps_show_on_a_real_file_writes_an_image(files_made):
    folder, _, _, a = files_made
    out = folder / "pair.png"
    assert main(["maps", "show", a, "--index", "0", "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
