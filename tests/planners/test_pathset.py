"""The paths file: round trip, refusal of bad files, and `vinadv plan` end to end."""

import dataclasses
import json

import numpy as np
import pytest

from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.npzfile import save_npz
from vinadv.planners.pathset import PATHS_FORMAT, PathSet
from vinadv.planners.vin.engine import plan_maps
from vinadv.planners.vin.weights import save_vin
from vinadv.testing.planners import planning_vin


@pytest.fixture(scope="module")
def planned():
    maps = generate_maps(12, 16, seed=2, n_starts=3)
    result = plan_maps(maps.obstacles, maps.goals, maps.starts, planning_vin(16, seed=4))
    return maps, PathSet.from_result(result, 3, 16, True, model="test")


def fields(ps: PathSet) -> dict:
    return {
        "path_cells": ps.paths.cells,
        "path_offsets": ps.paths.offsets,
        "reached": ps.reached,
        "termination": ps.termination,
        "n_starts": np.array(ps.n_starts),
        "size": np.array(ps.size),
        "moves": np.array(ps.moves),
    }


def test_round_trip(planned, tmp_path):
    _, ps = planned
    ps.save(tmp_path / "p.npz")
    back = PathSet.load(tmp_path / "p.npz")
    assert back.paths == ps.paths
    for name in ("reached", "termination"):
        np.testing.assert_array_equal(getattr(back, name), getattr(ps, name))
    assert (back.n_starts, back.size, back.corner_cutting, back.model, back.n_maps) == (3, 16, True, "test", 12)
    np.testing.assert_array_equal(back.path(2, 1), ps.paths.cells[ps.paths.offsets[7] : ps.paths.offsets[8]])


def test_movement_model_round_trip_and_version_1_files(planned, tmp_path):
    """vinadv.paths/2 keeps the model; a vinadv.paths/1 file (no `moves`) reads as octile with the same arrays; the
    model is checked (a diagonal step is a jump on news)."""
    _, ps = planned
    moore = dataclasses.replace(ps, moves="moore")
    moore.save(tmp_path / "m.npz")
    assert PathSet.load(tmp_path / "m.npz").moves == "moore"
    assert str(np.load(tmp_path / "m.npz")["format"]) == "vinadv.paths/2"
    old = {k: v for k, v in np.load(tmp_path / "m.npz").items() if k not in ("format", "moves")}
    save_npz(tmp_path / "old.npz", "vinadv.paths/1", old)
    back = PathSet.load(tmp_path / "old.npz")
    assert back.moves == "octile" and back.paths.cells.tobytes() == ps.paths.cells.tobytes()
    dataclasses.replace(ps, moves="news").save(tmp_path / "n.npz")  # the octile paths move diagonally
    with pytest.raises(InputError, match="not 4-neighbours"):
        PathSet.load(tmp_path / "n.npz")
    f = fields(ps)
    f.pop("moves")
    save_npz(tmp_path / "none.npz", PATHS_FORMAT, f)
    with pytest.raises(InputError, match="field 'moves' is missing"):
        PathSet.load(tmp_path / "none.npz")


@pytest.mark.parametrize(
    "change, match",
    [
        (
            lambda f: f.update(termination=np.where(f["termination"] == "goal", "arrived", f["termination"])),
            "termination",
        ),
        (lambda f: f.update(reached=~f["reached"]), "reached"),
        (lambda f: f.update(path_offsets=f["path_offsets"][:-1]), "path_offsets"),
        (lambda f: f.update(path_cells=f["path_cells"] + 20), "path_cells"),
        (lambda f: f.update(path_cells=f["path_cells"][::-1].copy()), "path_cells"),
        (lambda f: f.update(n_starts=np.array(5)), "n_starts"),
        (lambda f: f.update(reached=f["reached"].astype(float)), "reached"),
        (lambda f: f.pop("size"), "size"),
    ],
)
def test_bad_files_refused(planned, tmp_path, change, match):
    _, ps = planned
    f = fields(ps)
    change(f)
    save_npz(tmp_path / "bad.npz", PATHS_FORMAT, f)
    with pytest.raises(InputError, match=match):
        PathSet.load(tmp_path / "bad.npz")


def test_wrong_format_and_garbage(planned, tmp_path):
    save_npz(tmp_path / "maps.npz", "vinadv.maps/1", {"x": np.zeros(1)})
    with pytest.raises(InputError, match="format"):
        PathSet.load(tmp_path / "maps.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(InputError):
        PathSet.load(tmp_path / "junk.npz")
    with pytest.raises(InputError, match="no such file"):
        PathSet.load(tmp_path / "missing.npz")


def test_cli_plan(planned, tmp_path, capsys):
    maps, ps = planned
    maps.save(tmp_path / "maps.npz")
    save_vin(planning_vin(16, seed=4), tmp_path / "w.pt")
    code = main(
        [
            "plan",
            "--maps",
            str(tmp_path / "maps.npz"),
            "--out",
            str(tmp_path / "paths.npz"),
            "--weights",
            str(tmp_path / "w.pt"),
            "--json",
        ]
    )
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["paths"] == 36
    back = PathSet.load(tmp_path / "paths.npz")
    assert back.paths == ps.paths
    np.testing.assert_array_equal(back.termination, ps.termination)


def test_cli_bad_input_exits_2(tmp_path, capsys):
    (tmp_path / "junk.npz").write_bytes(b"junk")
    assert main(["plan", "--maps", str(tmp_path / "junk.npz"), "--out", str(tmp_path / "o.npz"), "--quiet"]) == 2
    assert "vinadv: error:" in capsys.readouterr().err
    assert main(["plan", "--maps", str(tmp_path / "nothing.npz"), "--out", str(tmp_path / "o.npz")]) == 2
