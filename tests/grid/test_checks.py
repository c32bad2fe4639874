"""Content validation (vinadv.grid.checks) through the loaders: a file that breaks DESIGN.md is refused, naming the
file, the field and the first bad map/path/pair; valid files, and maps without a border wall, load."""

from __future__ import annotations

import numpy as np
import pytest

from tests.fault_files import (
    read_npz,
    rewrite_npz,
    write_maps,
    write_pairs,
    write_paths,
)
from vinadv.attacks.pairs import PairSet
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.grid.checks import check_paths
from vinadv.grid.mapset import MapSet
from vinadv.grid.paths import PackedPaths
from vinadv.planners.pathset import PathSet


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("valid")
    return {
        "maps": write_maps(folder / "maps.npz"),
        "pairs": write_pairs(folder / "pairs.npz"),
        "paths": write_paths(folder / "paths.npz"),
    }


def _path(a: dict, side: str, i: int) -> np.ndarray:
    off = a[f"path_{side}_offsets"]
    return a[f"path_{side}_cells"][off[i] : off[i + 1]]


def _refused(loader, path, field: str, where: str):
    with pytest.raises(InputError) as err:
        loader(path)
    message = str(err.value)
    assert str(path) in message and f"field '{field}'" in message and f"({where})" in message, message
    assert "\n" not in message
    return message


def test_valid_files_load(files):
    assert len(MapSet.load(files["maps"])) == 12
    assert len(PairSet.load(files["pairs"])) > 0
    assert len(PathSet.load(files["paths"])) == 36


# ---------------------------------------------------------------------------------------------------- pairs


@pytest.mark.parametrize("k, onto", [(3, "start"), (1, "goal")])
def test_pairs_added_obstacle_on_the_start_or_goal(files, tmp_path, k, onto):
    a = read_npz(files["pairs"])
    added, obs_a = a["added"].copy(), a["obstacles_a"].copy()
    added[k] = a[f"{onto}s"][k]
    obs_a[k] = a["obstacles_o"][k]
    obs_a[k, added[k, 0], added[k, 1]] = True  # consistent with obstacles_o + added: only the place is wrong
    bad = rewrite_npz(files["pairs"], tmp_path / "bad.npz", added=added, obstacles_a=obs_a)
    assert f"is on the {onto}" in _refused(PairSet.load, bad, "added", f"pair {k}")


def _longest(a: dict, side: str) -> int:
    return int(np.argmax(np.diff(a[f"path_{side}_offsets"])))


def test_pairs_path_that_jumps(files, tmp_path):
    a = read_npz(files["pairs"])
    k = _longest(a, "o")
    cells = a["path_o_cells"].copy()
    at = a["path_o_offsets"][k] + 2
    cells[at] = cells[at - 1] + np.array([0, 5]) if cells[at - 1, 1] < 5 else cells[at - 1] - np.array([0, 5])
    bad = rewrite_npz(files["pairs"], tmp_path / "bad.npz", path_o_cells=cells)
    assert "8-neighbours" in _refused(PairSet.load, bad, "path_o_cells", f"pair {k}")


def test_pairs_path_through_an_obstacle_or_the_border(files, tmp_path):
    a = read_npz(files["pairs"])
    k = _longest(a, "a")
    path = _path(a, "a", k)
    cell = path[len(path) // 2]
    obs_o, obs_a = a["obstacles_o"].copy(), a["obstacles_a"].copy()
    obs_o[k, cell[0], cell[1]] = obs_a[k, cell[0], cell[1]] = True
    bad = rewrite_npz(files["pairs"], tmp_path / "bad.npz", obstacles_o=obs_o, obstacles_a=obs_a)
    assert "on an obstacle" in _refused(
        PairSet.load,
        bad,
        "path_" + ("o" if any((c == cell).all() for c in _path(a, "o", k)) else "a") + "_cells",
        f"pair {k}",
    )
    # a path along the border wall: the first pair's original path moved onto row 0 (a wall on these maps)
    cells = a["path_o_cells"].copy()
    start = a["path_o_offsets"][0]
    cells[start + 1] = [0, cells[start + 1, 1]] if cells[start, 0] == 1 else cells[start + 1]
    if cells[start, 0] == 1:
        bad = rewrite_npz(files["pairs"], tmp_path / "border.npz", path_o_cells=cells)
        _refused(PairSet.load, bad, "path_o_cells", "pair 0")


def test_pairs_path_not_starting_at_the_start(files, tmp_path):
    a = read_npz(files["pairs"])
    k = 2
    starts = a["starts"].copy()
    free = np.argwhere(~a["obstacles_a"][k])
    taken = {tuple(a["goals"][k]), tuple(a["added"][k]), tuple(starts[k])}
    starts[k] = next(c for c in free if tuple(c) not in taken)
    bad = rewrite_npz(files["pairs"], tmp_path / "bad.npz", starts=starts)
    assert "does not start at its start" in _refused(PairSet.load, bad, "path_o_cells", f"pair {k}")


def test_pairs_termination_must_agree_with_the_last_cell(files, tmp_path):
    a = read_npz(files["pairs"])
    k = 0
    term = a["term_a"].copy()
    term[k] = "loop" if term[k] == "goal" else "goal"
    bad = rewrite_npz(files["pairs"], tmp_path / "bad.npz", term_a=term)
    assert "termination" in _refused(PairSet.load, bad, "path_a_cells", f"pair {k}")


def test_bad_pairs_file_is_not_stored(files, tmp_path, capsys):
    a = read_npz(files["pairs"])
    added, obs_a = a["added"].copy(), a["obstacles_a"].copy()
    added[0] = a["starts"][0]
    obs_a[0] = a["obstacles_o"][0]
    obs_a[0, added[0, 0], added[0, 1]] = True
    bad = rewrite_npz(files["pairs"], tmp_path / "bad.npz", added=added, obstacles_a=obs_a)
    db = tmp_path / "x.db"
    assert main(["identify", "--pairs", str(bad), "--db", str(db), "--quiet"]) == 2
    assert "field 'added'" in capsys.readouterr().err
    assert not db.exists()


# ----------------------------------------------------------------------------------------------------- maps


def test_maps_duplicate_starts(files, tmp_path):
    a = read_npz(files["maps"])
    starts = a["starts"].copy()
    starts[2, 1] = starts[2, 0]
    bad = rewrite_npz(files["maps"], tmp_path / "bad.npz", starts=starts)
    assert "same start twice" in _refused(MapSet.load, bad, "starts", "map 2")


def test_maps_start_on_the_goal(files, tmp_path):
    a = read_npz(files["maps"])
    starts = a["starts"].copy()
    starts[4, 0] = a["goals"][4]
    bad = rewrite_npz(files["maps"], tmp_path / "bad.npz", starts=starts)
    assert "on the goal" in _refused(MapSet.load, bad, "starts", "map 4")


def test_maps_expert_path_not_starting_at_its_start(files, tmp_path):
    a = read_npz(files["maps"])
    starts = a["starts"].copy()
    starts[5, [0, 1]] = starts[5, [1, 0]]  # the starts swapped, the expert paths not
    bad = rewrite_npz(files["maps"], tmp_path / "bad.npz", starts=starts)
    assert "does not start at its start" in _refused(MapSet.load, bad, "expert_cells", "path 15")


def test_maps_expert_path_through_an_obstacle(files, tmp_path):
    a = read_npz(files["maps"])
    off = a["expert_offsets"]
    k = int(np.argmax(np.diff(off)))
    cell = a["expert_cells"][(off[k] + off[k + 1]) // 2]
    obstacles = a["obstacles"].copy()
    obstacles[k // 3, cell[0], cell[1]] = True
    bad = rewrite_npz(files["maps"], tmp_path / "bad.npz", obstacles=obstacles)
    assert "on an obstacle" in _refused(MapSet.load, bad, "expert_cells", f"path {k}")


def test_maps_without_a_border_wall_are_legitimate(files, tmp_path):
    a = read_npz(files["maps"])
    obstacles = a["obstacles"].copy()
    obstacles[:, 0, :] = obstacles[:, -1, :] = obstacles[:, :, 0] = obstacles[:, :, -1] = False
    ok = rewrite_npz(files["maps"], tmp_path / "open.npz", obstacles=obstacles)
    assert not MapSet.load(ok).obstacles[:, 0, :].any()


def test_maps_without_corner_cutting_refuse_a_squeezing_diagonal(tmp_path):
    """An expert path of a no-corner-cutting file may not pass diagonally between an obstacle and a cell."""
    maps = generate_maps(20, 10, seed=1, n_starts=2, corner_cutting=True)
    maps.save(tmp_path / "cc.npz")
    a = read_npz(tmp_path / "cc.npz")
    cells, off = a["expert_cells"].astype(int), a["expert_offsets"]
    step = np.diff(cells, axis=0)
    paths = np.repeat(np.arange(len(off) - 1), np.diff(off))
    obstacles = a["obstacles"]
    squeeze = [
        j
        for j in range(len(step))
        if paths[j] == paths[j + 1]
        and abs(step[j]).sum() == 2
        and (
            obstacles[paths[j] // 2, cells[j, 0] + step[j, 0], cells[j, 1]]
            or obstacles[paths[j] // 2, cells[j, 0], cells[j, 1] + step[j, 1]]
        )
    ]
    assert squeeze, "no corner-cutting move in these maps; pick another seed"
    bad = rewrite_npz(tmp_path / "cc.npz", tmp_path / "nocc.npz", corner_cutting=np.array(False))
    assert "between obstacles" in _refused(MapSet.load, bad, "expert_cells", f"path {paths[squeeze[0]]}")


# ---------------------------------------------------------------------------------------------------- paths


def test_paths_jump(files, tmp_path):
    a = read_npz(files["paths"])
    off = a["path_offsets"]
    k = int(np.argmax(np.diff(off)))
    cells = a["path_cells"].copy()
    cells[off[k] + 1] = [cells[off[k], 0], (cells[off[k], 1] + 4) % 10]
    bad = rewrite_npz(files["paths"], tmp_path / "bad.npz", path_cells=cells)
    with pytest.raises(InputError, match="path_cells"):
        PathSet.load(bad)


def test_news_paths_may_not_move_diagonally():
    diagonal = PackedPaths.pack([np.array([[1, 1], [2, 2]])])
    check_paths("f.npz", "path_cells", diagonal, 4, moves="moore")
    with pytest.raises(InputError, match="not 4-neighbours .*'news' moves"):
        check_paths("f.npz", "path_cells", diagonal, 4, moves="news")
    check_paths("f.npz", "path_cells", PackedPaths.pack([np.array([[1, 1], [2, 1], [2, 2]])]), 4, moves="news")
