"""Drawn maps from files (`--format ascii` and `--format png`): a map drawn by hand that `plan`, `attack` and the
viewer (`serve`) use, the options that go with them, and mutated files (loaded or one line, never anything else)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from tests.byte_mutations import refused_mutations
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.interop import export_maps, import_maps
from vinadv.store import Store
from vinadv.viewer.app import create_app

DRAWING = "##########\n#S...#...#\n#.##.#.#.#\n#..#...#G#\n##########\n"


def write_png(path, grey: np.ndarray) -> None:
    Image.fromarray(grey.astype(np.uint8)).save(path)


@pytest.mark.slow  # about 5 s: five commands and the viewer
def test_a_drawn_map_is_planned_attacked_and_served(tmp_path, capsys):
    """The chain a user follows: import the drawing (padded for a planner of size 12), plan, attack, identify into
    a database and look at the pair in the viewer."""
    (tmp_path / "d.txt").write_text(DRAWING)
    maps, paths, pairs, db = (str(tmp_path / n) for n in ("d.npz", "p.npz", "a.npz", "v.db"))
    assert main(["maps", "import", "--format", "ascii", str(tmp_path / "d.txt"), "--pad-to", "12", "--out", maps]) == 0
    assert main(["plan", "--maps", maps, "--planner", "optimal", "--out", paths, "--quiet"]) == 0
    assert (
        main(["attack", "--maps", maps, "--strategy", "random", "--planner", "optimal", "--out", pairs, "--quiet"]) == 0
    )
    assert main(["identify", "--pairs", pairs, "--db", db, "--name", "drawn", "--json"]) == 0
    capsys.readouterr()
    with Store.open(f"sqlite:///{db}", create=False) as store:
        app = create_app(store, secret_key="test")
        app.config["TESTING"] = True
        client = app.test_client()
        run_id = store.list_runs()[0]["id"]
        page = client.get(f"/pairs/{run_id}/0")
        assert page.status_code == 200 and f"/img/{run_id}/0/original.png" in page.get_data(as_text=True)
        assert client.get(f"/img/{run_id}/0/original.png").status_code == 200


def test_png_pixels_darker_than_half_grey_are_obstacles(tmp_path, capsys):
    grey = np.full((6, 8), 255)
    grey[2, 1:6] = 127  # darker than half grey: obstacles
    grey[4, 1:6] = 128  # not darker
    write_png(tmp_path / "d.png", grey)
    maps = import_maps(tmp_path / "d.png", "png", start="1,1", goal=(3, 2), pad_to=10, moves="news")
    assert maps.size == 10 and maps.moves == "news"
    np.testing.assert_array_equal(maps.obstacles[0, :6, :8], grey < 128)
    assert maps.obstacles[0, 6:].all() and maps.obstacles[0, :, 8:].all()
    assert tuple(maps.starts[0, 0]) == (1, 1) and tuple(maps.goals[0]) == (3, 2)
    line = ["maps", "import", "--format", "png", str(tmp_path / "d.png"), "--out", str(tmp_path / "m.npz")]
    assert main([*line, "--start", "1,1", "--goal", "3,2", "--no-corner-cutting", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["corner_cutting"] is False
    for extra, message in (
        ([], "give --start and --goal (ROW,COL)"),
        (["--start", "1;1", "--goal", "3,2"], "--start '1;1': expected ROW,COL"),
        (["--start", "2,2", "--goal", "3,2"], "start (2, 2) is on an obstacle"),
        (["--start", "1,1", "--goal", "9,2"], "goal (9, 2) is outside the 6x8 map"),
        (["--start", "1,1", "--goal", "3,2", "--pad-to", "5"], "--pad-to 5"),
        (["--start", "1,1", "--goal", "3,2", "--scen", "x.scen"], "--scen is not an option of format png"),
    ):
        assert main([*line, *extra]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err


def test_ascii_options_and_what_export_refuses(tmp_path, capsys):
    (tmp_path / "d.txt").write_text(DRAWING)
    maps = import_maps(tmp_path / "d.txt", "ascii", moves="moore", corner_cutting=False)
    assert (maps.size, maps.moves, maps.corner_cutting) == (10, "moore", False)
    with pytest.raises(InputError, match="format ascii is read only"):
        export_maps(maps, tmp_path / "x.txt", "ascii")
    with pytest.raises(InputError, match="starts cannot be set"):
        import_maps(tmp_path / "d.txt", "ascii", starts=2)
    (tmp_path / "u.txt").write_bytes("S.é\n..G\n".encode())
    with pytest.raises(InputError, match="not an ASCII text file"):
        import_maps(tmp_path / "u.txt", "ascii")


@pytest.mark.parametrize("fmt", ["ascii", "png"])
def test_byte_mutations_load_or_give_one_line(tmp_path, fmt):
    target = tmp_path / f"d.{'txt' if fmt == 'ascii' else 'png'}"
    if fmt == "ascii":
        target.write_text(DRAWING)
    else:
        grey = np.full((8, 8), 255)
        grey[3, 1:6] = 0
        write_png(target, grey)
    options = {} if fmt == "ascii" else {"start": "1,1", "goal": "6,6"}
    assert refused_mutations(target, lambda: import_maps(target, fmt, **options), examples=25)
