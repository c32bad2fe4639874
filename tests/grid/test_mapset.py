import dataclasses
import json

import numpy as np
import pytest

from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import MapSet, generate_maps


@pytest.fixture(scope="module")
def maps():
    return generate_maps(20, 16, seed=2, n_starts=4)


def test_round_trip(tmp_path, maps):
    maps.save(tmp_path / "m.npz")
    back = MapSet.load(tmp_path / "m.npz")
    for field in ("obstacles", "goals", "starts", "expert_costs"):
        np.testing.assert_array_equal(getattr(back, field), getattr(maps, field))
    assert back.expert == maps.expert
    assert back.corner_cutting == maps.corner_cutting and back.seed == 2
    assert back.moves == "octile" and str(np.load(tmp_path / "m.npz")["format"]) == "vinadv.maps/3"


@pytest.mark.parametrize("moves", ["moore", "news"])
def test_round_trip_keeps_the_movement_model(tmp_path, moves):
    maps = generate_maps(10, 12, seed=3, n_starts=3, moves=moves)
    maps.save(tmp_path / "m.npz")
    back = MapSet.load(tmp_path / "m.npz")
    assert back.moves == moves
    np.testing.assert_array_equal(back.expert_costs, maps.expert_costs)
    assert back.expert == maps.expert


def test_version_1_files_read_as_octile_with_the_same_arrays(tmp_path, maps):
    """A file written before movement models (format vinadv.maps/1, no `moves` field) reads as octile, every array
    byte for byte what was written; a /1 file is still checked as octile (an 8-move path is no jump there)."""
    fields = dict(np.load(_saved(tmp_path, maps)))
    fields.pop("moves")
    fields["format"] = np.array("vinadv.maps/1")
    np.savez(tmp_path / "old.npz", **fields)
    old = MapSet.load(tmp_path / "old.npz")
    assert old.moves == "octile"
    for field in ("obstacles", "goals", "starts", "expert_costs"):
        assert getattr(old, field).tobytes() == getattr(maps, field).tobytes()
    assert old.expert.cells.tobytes() == maps.expert.cells.tobytes()
    old.save(tmp_path / "again.npz")
    assert str(np.load(tmp_path / "again.npz")["moves"]) == "octile"


@pytest.mark.parametrize(
    "change, message",
    [
        ({"moves": None}, "field 'moves' is missing"),
        ({"moves": np.array("hex")}, "field 'moves' is 'hex', expected one of octile, moore, news"),
        ({"moves": np.array("news"), "corner_cutting": np.array(False)}, "field 'moves' is 'news' .*corner_cutting"),
        ({"moves": np.array("news")}, "not 4-neighbours"),  # the octile expert paths move diagonally
    ],
)
def test_bad_movement_models_are_refused(tmp_path, maps, change, message):
    with pytest.raises(InputError, match=message):
        MapSet.load(_corrupt(tmp_path, maps, **change))


def test_news_without_corner_cutting_is_refused():
    with pytest.raises(InputError, match="'news' has no diagonal moves"):
        generate_maps(2, 10, moves="news", corner_cutting=False)


def _corrupt(tmp_path, maps, **changes):
    data = dict(np.load(_saved(tmp_path, maps)))
    for key, value in changes.items():
        if value is None:
            data.pop(key)
        else:
            data[key] = value
    path = tmp_path / "bad.npz"
    np.savez(path, **data)
    return path


def _saved(tmp_path, maps):
    path = tmp_path / "good.npz"
    maps.save(path)
    return path


@pytest.mark.parametrize(
    "change, message",
    [
        ({"format": np.array("vinadv.maps/9")}, "format 'vinadv.maps/9' is not supported"),
        ({"format": np.array("vinadv.pairs/1")}, "not a vinadv.maps file"),
        ({"format": None}, "'format' missing"),
        ({"obstacles": None}, "'obstacles' is missing"),
        ({"obstacles": np.zeros((20, 16, 16), dtype=np.float32)}, "'obstacles' has dtype float32"),
        ({"goals": np.zeros((19, 2), dtype=np.int64)}, "'goals' has shape"),
        ({"starts": np.full((20, 4, 2), 40, dtype=np.int64)}, "'starts' has a cell outside"),
        ({"expert_offsets": np.zeros(81, dtype=np.int64)}, "'expert_offsets' is not increasing"),
    ],
)
def test_corrupted_files_are_refused(tmp_path, maps, change, message):
    path = _corrupt(tmp_path, maps, **change)
    with pytest.raises(InputError, match=message):
        MapSet.load(path)


def test_start_on_obstacle_is_refused(tmp_path, maps):
    obstacles = maps.obstacles.copy()
    obstacles[0, maps.starts[0, 0, 0], maps.starts[0, 0, 1]] = True
    with pytest.raises(InputError, match="'starts' has a start on an obstacle"):
        MapSet.load(_corrupt(tmp_path, maps, obstacles=obstacles))


def test_cli_generate_show_and_bad_files(tmp_path, capsys):
    out = tmp_path / "m.npz"
    assert main(["maps", "generate", "--n", "5", "--size", "12", "--seed", "1", "--out", str(out), "--quiet"]) == 0
    assert len(MapSet.load(out)) == 5
    png = tmp_path / "m.png"
    assert main(["maps", "show", str(out), "--index", "2", "--out", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert main(["maps", "show", str(out), "--index", "9", "--out", str(png)]) == 2
    assert "out of range" in capsys.readouterr().err
    (tmp_path / "junk.npz").write_text("not a zip")
    assert main(["maps", "show", str(tmp_path / "junk.npz"), "--out", str(png)]) == 2
    assert "junk.npz: not an .npz file" in capsys.readouterr().err
    assert main(["maps", "generate", "--n", "5", "--size", "4", "--out", str(out)]) == 2
    assert "vinadv: error: --size must be >= 8, got 4" in capsys.readouterr().err


def test_cli_generate_moves(tmp_path, capsys):
    out = tmp_path / "m.npz"
    argv = ["maps", "generate", "--n", "4", "--size", "10", "--out", str(out)]
    assert main([*argv, "--moves", "moore", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["moves"] == "moore" and summary["corner_cutting"] is True
    assert MapSet.load(out).moves == "moore"
    assert main([*argv, "--moves", "news"]) == 0
    assert "news moves" in capsys.readouterr().out and MapSet.load(out).moves == "news"
    assert main([*argv, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["moves"] == "octile"
    assert main([*argv, "--moves", "news", "--no-corner-cutting"]) == 2
    err = capsys.readouterr().err
    assert "vinadv: error: --moves 'news' has no diagonal moves, so it is refused without corner cutting" in err
    assert main([*argv, "--moves", "hex"]) == 2
    assert "vinadv: error: --moves 'hex': expected one of octile, moore, news" in capsys.readouterr().err


def test_concat_keeps_every_map_in_order_and_refuses_unlike_sets(tmp_path, capsys):
    a = generate_maps(3, 8, seed=1, n_starts=2, moves="moore")
    b = generate_maps(2, 8, seed=2, n_starts=2, moves="moore")
    a.save(tmp_path / "a.npz")
    b.save(tmp_path / "b.npz")
    assert (
        main(["maps", "concat", str(tmp_path / "a.npz"), str(tmp_path / "b.npz"), "--out", str(tmp_path / "c.npz")])
        == 0
    )
    both = MapSet.load(tmp_path / "c.npz")
    assert len(both) == 5 and both.moves == "moore" and both.seed == -1  # two seeds: unknown
    for i, (part, j) in enumerate([(a, 0), (a, 1), (a, 2), (b, 0), (b, 1)]):  # map by map, against the parts
        np.testing.assert_array_equal(both.obstacles[i], part.obstacles[j])
        np.testing.assert_array_equal(both.starts[i], part.starts[j])
        np.testing.assert_array_equal(both.expert_costs[i], part.expert_costs[j])
        for s in range(2):
            np.testing.assert_array_equal(both.expert_path(i, s), part.expert_path(j, s))
    generate_maps(2, 8, seed=2, n_starts=2).save(tmp_path / "octile.npz")
    capsys.readouterr()
    assert (
        main(
            ["maps", "concat", str(tmp_path / "a.npz"), str(tmp_path / "octile.npz"), "--out", str(tmp_path / "d.npz")]
        )
        == 2
    )
    err = capsys.readouterr().err.strip()
    assert "octile.npz: moves is 'octile'" in err and "'moore'" in err and len(err.splitlines()) == 1


def test_concat_of_parts_gives_the_whole_and_refuses_mismatched_parts(maps):
    whole = MapSet.concat([maps.take(np.arange(0, 2)), maps.take(np.arange(2, len(maps)))])
    for name in ("obstacles", "goals", "starts", "expert_costs"):
        np.testing.assert_array_equal(getattr(whole, name), getattr(maps, name))
    assert whole.expert == maps.expert and whole.moves == maps.moves and whole.start_counts is None
    other = generate_maps(2, maps.size, seed=1, n_starts=maps.n_starts, moves="moore")
    with pytest.raises(InputError, match="part 1: moves is 'moore', part 0's is 'octile'"):
        MapSet.concat([maps, other])
    padded = dataclasses.replace(maps.take(np.arange(2)), start_counts=np.array([4, 2]))
    assert MapSet.concat([padded, maps.take(np.arange(2, 4))]).start_counts.tolist() == [4, 2, 4, 4]


def _masked(maps):
    """`maps` with a frozen mask and provenance (vinadv.maps/3's optional fields)."""
    n = len(maps)
    frozen = np.zeros(maps.obstacles.shape, dtype=bool)
    frozen[:, -1, :] = True
    frozen[::2, :, -2:] = True
    return dataclasses.replace(
        maps,
        frozen=frozen,
        source=np.array([f"m{i}.map" for i in range(n)]),
        source_sha256=np.array(["ab" * 32 if i % 2 else "" for i in range(n)]),
        origin=np.stack([np.arange(n), 2 * np.arange(n)], axis=1),
    )


def test_frozen_cells_and_provenance_round_trip(tmp_path, maps):
    masked = _masked(maps)
    masked.save(tmp_path / "m.npz")
    back = MapSet.load(tmp_path / "m.npz")
    for field in ("frozen", "source", "source_sha256", "origin"):
        np.testing.assert_array_equal(getattr(back, field), getattr(masked, field))
    assert back.frozen.dtype == bool and back.origin.dtype == np.int64


def test_version_2_files_read_with_no_frozen_cells(tmp_path, maps):
    fields = dict(np.load(_saved(tmp_path, maps)))
    assert "frozen" not in fields and "source" not in fields  # a set without them writes neither
    fields["format"] = np.array("vinadv.maps/2")
    np.savez(tmp_path / "old.npz", **fields)
    old = MapSet.load(tmp_path / "old.npz")
    assert old.frozen is None and old.source is None and old.origin is None
    assert not old.frozen_or_none().any()
    assert old.obstacles.tobytes() == maps.obstacles.tobytes()


def test_take_and_concat_keep_frozen_cells_and_provenance(maps):
    masked = _masked(maps)
    idx = np.array([5, 0, 3])
    part = masked.take(idx)
    for field in ("frozen", "source", "source_sha256", "origin"):
        np.testing.assert_array_equal(getattr(part, field), getattr(masked, field)[idx])
    whole = MapSet.concat([masked.take(np.arange(8)), masked.take(np.arange(8, 20))])
    for field in ("frozen", "source", "source_sha256", "origin"):
        np.testing.assert_array_equal(getattr(whole, field), getattr(masked, field))
    # a part without them: its maps have no frozen cell and an unknown source
    mixed = MapSet.concat([masked.take(np.arange(2)), maps.take(np.arange(2))])
    assert mixed.frozen[:2].any() and not mixed.frozen[2:].any()
    assert list(mixed.source) == ["m0.map", "m1.map", "", ""] and (mixed.origin[2:] == 0).all()
    assert MapSet.concat([maps.take(np.arange(2))] * 2).frozen is None


@pytest.mark.parametrize(
    "change, message",
    [
        ({"frozen": np.zeros((20, 16, 15), dtype=bool)}, "'frozen' has shape"),
        ({"frozen": np.zeros((20, 16, 16), dtype=np.int64)}, "'frozen' has dtype"),
        ({"origin": None}, "'origin' is missing"),
        ({"origin": np.full((20, 2), -1)}, "'origin' has a negative"),
        ({"source_sha256": np.array(["xyz"] * 20)}, "'source_sha256' has 'xyz'"),
        ({"source": np.zeros(20)}, "'source' has dtype"),
    ],
)
def test_bad_frozen_cells_and_provenance_are_refused(tmp_path, maps, change, message):
    path = tmp_path / "m.npz"
    _masked(maps).save(path)
    data = dict(np.load(path))
    for k, v in change.items():
        if v is None:
            del data[k]
        else:
            data[k] = v
    np.savez(path, **data)
    with pytest.raises(InputError, match=message):
        MapSet.load(path)
