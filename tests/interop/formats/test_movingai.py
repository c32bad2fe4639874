"""The Moving AI layout (`.map` and `.scen`): the shared `.scen` file's optimal lengths against vinadv's, crops
against their windows of the file, padding of a map that is not square, export then import, what is refused, and
byte mutations of both files (loaded or one line, never anything else)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.byte_mutations import refused_mutations
from tests.grid.oracle import brute_distances
from tests.needs import public_data
from vinadv.attacks.strategies import make_attack
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import MapSet, generate_maps
from vinadv.grid.shortest_paths import shortest_distances
from vinadv.interop import export_maps, import_maps, read_maps
from vinadv.interop.formats.movingai import read_grid, read_problems
from vinadv.planners.classical.optimal import OptimalPlanner

SCEN = "movingai/random-32-32-20-random-1.scen"
MAP = "movingai/random-32-32-20.map"

SMALL_MAP = "type octile\nheight 4\nwidth 5\nmap\n.....\n.@@T.\n..S.G\nWO...\n"
SMALL_SCEN = (
    "version 1\n"
    "0\tsmall.map\t5\t4\t0\t0\t4\t3\t6.41421356\n"
    "0\tsmall.map\t5\t4\t4\t0\t0\t2\t6.00000000\r\n"
    "1\tsmall.map\t5\t4\t0\t2\t4\t0\t6.00000000\n"
)


@pytest.fixture
def small(tmp_path):
    (tmp_path / "small.map").write_text(SMALL_MAP)
    (tmp_path / "small.scen").write_text(SMALL_SCEN)
    return tmp_path / "small.map", tmp_path / "small.scen"


def test_the_shared_scen_files_409_optimal_lengths_equal_vinadvs():
    scen = public_data(SCEN)
    maps, info = read_maps(public_data(MAP), "movingai", scen=scen)
    lengths = np.array([p[8] for _, p in read_problems(scen)])
    assert len(maps) == info["lengths_checked"] == len(lengths) == 409
    assert (maps.moves, maps.corner_cutting, maps.size, maps.n_starts) == ("octile", False, 32, 1)
    np.testing.assert_allclose(maps.expert_costs[:, 0], lengths, rtol=0, atol=1e-6)
    # a problem is a row of its own, in the file's order: (x, y) is (col, row)
    first = read_problems(scen)[0][1]
    assert tuple(maps.starts[0, 0]) == (first[5], first[4]) and tuple(maps.goals[0]) == (first[7], first[6])
    grid = read_grid(public_data(MAP))
    assert (maps.obstacles == grid).all()


def test_the_small_files_lengths_and_what_the_characters_mean(small):
    grid = read_grid(small[0])
    assert grid.tolist() == [
        [False] * 5,
        [False, True, True, True, False],
        [False] * 5,
        [True, True, False, False, False],
    ]
    maps = import_maps(small[0], "movingai", scen=small[1])
    assert len(maps) == 3
    for i in range(3):  # a plain Bellman-Ford's lengths, no corner cutting
        best = brute_distances(maps.obstacles[i].tolist(), tuple(maps.goals[i]), corner_cutting=False)
        assert best[tuple(maps.starts[i, 0])][0] == pytest.approx(maps.expert_costs[i, 0], abs=1e-12)
    maps = import_maps(small[0], "movingai", scen=small[1], bucket="1")
    assert len(maps) == 1 and tuple(maps.starts[0, 0]) == (2, 0)


def test_a_length_that_differs_is_one_line_naming_file_line_and_both_lengths(small):
    small[1].write_text(SMALL_SCEN.replace("6.00000000\r", "4.5\r"))
    with pytest.raises(InputError) as err:
        import_maps(small[0], "movingai", scen=small[1])
    message = str(err.value)
    assert "\n" not in message and str(small[1]) in message and "line 3" in message
    assert "4.50000000" in message and "6.00000000" in message


@pytest.mark.parametrize(
    "text, expected",
    [
        ("type tile\nheight 1\nwidth 1\nmap\n.\n", "line 1"),
        ("type octile\nheight 2\nwidth 2\nmap\n..\n", "has 1 grid rows"),
        ("type octile\nheight 1\nwidth 2\nmap\n.x\n", "line 5 column 2 is 'x'"),
        ("type octile\nheight 1\nwidth 3\nmap\n..\n", "line 5 has 2 characters"),
        ("type octile\nheight 99999\nwidth 3\nmap\n..\n", "outside 1..4096"),
        ("type octile\nheight 1\nwidth 1\nmap\n.\n@\n", "line 6 follows"),
    ],
)
def test_a_malformed_map_is_one_line_naming_the_line(tmp_path, text, expected):
    (tmp_path / "m.map").write_text(text)
    with pytest.raises(InputError, match=expected):
        read_grid(tmp_path / "m.map")


@pytest.mark.parametrize(
    "row, expected",
    [
        ("0\tsmall.map\t5\t4\t0\t0\t4\t3", "has 8 fields"),
        ("0\tsmall.map\t5\t4\t9\t0\t4\t3\t1.0", "start \\(9, 0\\) is outside"),
        ("0\tsmall.map\t5\t4\t1\t1\t4\t3\t1.0", "start \\(1, 1\\) is on an obstacle"),
        ("0\tsmall.map\t6\t4\t0\t0\t4\t3\t1.0", "map size 6x4"),
        ("0\tsmall.map\t5\t4\t-1\t0\t4\t3\t1.0", "start x '-1' is not an integer"),
        ("0\tsmall.map\t5\t4\t0\t0\t4\t3\tnan", "is not a length"),
        ("0\tother.map\t5\t4\t0\t0\t4\t3\t1.0", "no problem names the map small.map"),
    ],
)
def test_a_malformed_scen_is_one_line_naming_the_line(small, row, expected):
    small[1].write_text(f"version 1\n{row}\n")
    with pytest.raises(InputError, match=expected):
        import_maps(small[0], "movingai", scen=small[1])


def test_a_crops_obstacles_equal_its_window_of_the_file():
    path = public_data("movingai/Berlin_1_256.map")
    maps, info = read_maps(path, "movingai", crop=64, crops=6, seed=3, starts=2)
    grid = read_grid(path)
    assert len(maps) == 6 and maps.size == 64 and not maps.corner_cutting
    assert maps.frozen is None  # a window holds no padding
    for i, crop in enumerate(info["crops"]):
        r, c = crop["origin"]
        assert crop["source"] == str(path) and len(crop["sha256"]) == 64
        # the maps file keeps the same provenance
        assert (maps.source[i], maps.source_sha256[i]) == ("Berlin_1_256.map", crop["sha256"])
        assert maps.origin[i].tolist() == [r, c]
        np.testing.assert_array_equal(maps.obstacles[i], grid[r : r + 64, c : c + 64])
        assert (~maps.obstacles[i]).mean() >= 0.5
    # lengths recomputed in the window: the expert costs are the window's own shortest paths
    dist, _ = shortest_distances(maps.obstacles, maps.goals, False, "octile")
    costs = dist[np.arange(6)[:, None], maps.starts[..., 0], maps.starts[..., 1]]
    np.testing.assert_array_equal(maps.expert_costs, costs)
    assert np.isfinite(costs).all() and (costs > 0).all()
    again, _ = read_maps(path, "movingai", crop=64, crops=6, seed=3, starts=2)
    np.testing.assert_array_equal(again.starts, maps.starts)  # seeded


def test_a_map_that_is_not_square_is_padded_with_obstacles(tmp_path):
    path = public_data("movingai/den312d.map")
    maps, info = read_maps(path, "movingai", seed=1)
    grid = read_grid(path)
    assert grid.shape == (81, 65) and maps.size == 81 and info["padding"] == {"rows": 0, "cols": 16}
    assert (maps.obstacles[0, :, :65] == grid).all() and maps.obstacles[0, :, 65:].all()
    # the padding is frozen (no attack edits it), and the file keeps it and where the map came from
    padding = np.zeros((81, 81), dtype=bool)
    padding[:, 65:] = True
    np.testing.assert_array_equal(maps.frozen[0], padding)
    maps.save(tmp_path / "den.npz")
    back = MapSet.load(tmp_path / "den.npz")
    np.testing.assert_array_equal(back.frozen, maps.frozen)
    assert list(back.source) == ["den312d.map"] and back.source_sha256[0] == info["sha256"]
    assert back.origin.tolist() == [[0, 0]]


def test_a_removal_attack_never_frees_the_padding():
    maps, _ = read_maps(public_data("movingai/den312d.map"), "movingai", seed=1)
    attack = make_attack("random", per_map=200, seed=0, edit="remove")
    result = attack.attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, OptimalPlanner(81, False, "octile"), False, frozen=maps.frozen
    )
    cols = result.pairs.added[:, 0, 1]
    assert len(cols) == 200 and (cols < 65).all()
    unmasked = attack.attack(maps.obstacles, maps.starts[:, 0], maps.goals, OptimalPlanner(81, False, "octile"), False)
    assert (unmasked.pairs.added[:, 0, 1] >= 65).any()  # without the mask the padding would be freed


def test_export_of_a_padded_map_gives_back_the_original_grid(tmp_path):
    path = public_data("movingai/den312d.map")
    maps, _ = read_maps(path, "movingai", seed=1, starts=3)
    summary = export_maps(maps, tmp_path / "den.scen", "movingai")
    assert summary["problems"] == 3
    grid = read_grid(tmp_path / "den.map")
    assert grid.shape == (81, 65) and (grid == read_grid(path)).all()
    back = import_maps(tmp_path / "den.map", "movingai", scen=tmp_path / "den.scen")
    for name in ("obstacles", "goals", "frozen"):
        np.testing.assert_array_equal(getattr(back, name), getattr(maps, name)[[0, 0, 0]])
    np.testing.assert_array_equal(back.starts[:, 0], maps.starts[0])
    np.testing.assert_allclose(back.expert_costs[:, 0], maps.expert_costs[0], atol=1e-8)


def test_export_then_import_is_the_identity(tmp_path):
    scen = public_data(SCEN)
    maps = import_maps(public_data(MAP), "movingai", scen=scen, bucket="0-2")
    summary = export_maps(maps, tmp_path / "out.scen", "movingai")
    assert summary["map_files"] == [str(tmp_path / "out.map")] and summary["problems"] == len(maps)
    back = import_maps(tmp_path / "out.map", "movingai", scen=tmp_path / "out.scen")
    for name in ("obstacles", "goals", "starts", "expert_costs"):
        np.testing.assert_array_equal(getattr(back, name), getattr(maps, name))
    assert back.expert == maps.expert and (back.moves, back.corner_cutting) == (maps.moves, maps.corner_cutting)
    # and the grid text itself: the map's characters are only . and @ (and one T, an obstacle)
    assert (read_grid(tmp_path / "out.map") == read_grid(public_data(MAP))).all()


def test_export_of_several_grids_writes_one_map_each(tmp_path):
    maps, info = read_maps(public_data("movingai/Paris_1_256.map"), "movingai", crop=32, crops=3, seed=0)
    export_maps(maps, tmp_path / "c.scen", "movingai")
    for i in range(3):
        back = import_maps(tmp_path / f"c-{i:04d}.map", "movingai", scen=tmp_path / "c.scen")
        np.testing.assert_array_equal(back.obstacles[0], maps.obstacles[i])


@pytest.mark.parametrize("moves, cut", [("octile", True), ("moore", False), ("news", True)])
def test_export_refuses_rules_the_format_cannot_say(tmp_path, moves, cut):
    maps = generate_maps(2, 10, seed=1, corner_cutting=cut, moves=moves)
    with pytest.raises(InputError):
        export_maps(maps, tmp_path / "x.scen", "movingai")


def test_the_command_imports_and_refuses_in_one_line(small, tmp_path, capsys):
    out = tmp_path / "m.npz"
    line = ["maps", "import", "--format", "movingai", str(small[0]), "--out", str(out)]
    assert main([*line, "--scen", str(small[1]), "--bucket", "0", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["maps"] == 2
    assert main(["maps", "export", str(out), "--format", "movingai", "--out", str(tmp_path / "e.scen")]) == 0
    capsys.readouterr()
    for extra, message in (
        (["--moves", "moore"], "format movingai holds octile maps"),
        (["--no-corner-cutting"], None),
        (["--crop", "9"], "--crop 9: a window side must be in 3..4"),
        (["--crops", "2"], "--crops and --min-free go with --crop"),
        (["--scen", str(small[1]), "--crop", "3"], "--scen and --bucket go without --crop"),
        (["--bucket", "x", "--scen", str(small[1])], "--bucket 'x'"),
        (["--bucket", "1"], "--bucket filters the problems of a .scen file: give --scen too"),
    ):
        code = main([*line, *extra])
        err = capsys.readouterr().err
        if message is None:
            assert code == 0, err
        else:
            assert code == 2 and message in err and err.count("\n") == 1, err
    assert main(["maps", "import", "--format", "mpd", str(small[0]), "--crop", "3", "--out", str(out)]) == 2
    assert "--crop is not an option of format mpd" in capsys.readouterr().err


@pytest.mark.parametrize("which", ["map", "scen"])
def test_byte_mutations_load_or_give_one_line(small, which):
    """Bytes cut, flipped or inserted in either file: the import loads or raises InputError in one line."""
    target = small[0] if which == "map" else small[1]
    # some mutations are refused: a loader that accepts everything fails
    assert refused_mutations(target, lambda: import_maps(small[0], "movingai", scen=small[1]))
