"""The pairs file's movement model (vinadv.pairs/2, /3): kept on a round trip, read as octile from a vinadv.pairs/1
file with the same arrays, checked against the paths, and refused by the database (`vinadv identify`)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.fault_files import read_npz, write_pairs
from vinadv.attacks.pairs import PairSet
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.npzfile import save_npz
from vinadv.store import Store


@pytest.fixture(scope="module")
def pairs_file(tmp_path_factory):
    return write_pairs(tmp_path_factory.mktemp("pairs") / "pairs.npz")


def test_round_trip_and_version_1(pairs_file, tmp_path):
    pairs = PairSet.load(pairs_file)
    assert pairs.moves == "octile" and str(np.load(pairs_file)["format"]) == "vinadv.pairs/4"
    dataclasses.replace(pairs, moves="moore").save(tmp_path / "m.npz")
    assert PairSet.load(tmp_path / "m.npz").moves == "moore"
    old = {k: v for k, v in read_npz(pairs_file).items() if k not in ("format", "moves")}
    save_npz(tmp_path / "old.npz", "vinadv.pairs/1", old)
    back = PairSet.load(tmp_path / "old.npz")
    assert back.moves == "octile"
    for name in ("obstacles_o", "obstacles_a", "starts", "goals", "added", "map_index"):
        assert getattr(back, name).tobytes() == getattr(pairs, name).tobytes(), name
    assert back.path_o == pairs.path_o and back.path_a == pairs.path_a


def test_moves_are_checked(pairs_file, tmp_path):
    pairs = PairSet.load(pairs_file)
    fields = {k: v for k, v in read_npz(pairs_file).items() if k != "format"}
    save_npz(tmp_path / "bad.npz", "vinadv.pairs/3", {**fields, "moves": np.array("hex")})
    with pytest.raises(InputError, match="field 'moves' is 'hex'"):
        PairSet.load(tmp_path / "bad.npz")
    assert any(np.abs(np.diff(p, axis=0)).sum(axis=1).max(initial=0) == 2 for p in pairs.path_o.unpack())
    dataclasses.replace(pairs, moves="news").save(tmp_path / "news.npz")  # the paths move diagonally
    with pytest.raises(InputError, match="not 4-neighbours"):
        PairSet.load(tmp_path / "news.npz")


def test_identify_stores_the_pairs_movement_model(pairs_file, tmp_path, capsys):
    dataclasses.replace(PairSet.load(pairs_file), moves="moore").save(tmp_path / "m.npz")
    db = f"sqlite:///{tmp_path / 'x.db'}"
    assert main(["identify", "--pairs", str(tmp_path / "m.npz"), "--db", db, "--quiet"]) == 0
    with Store.open(db) as store:
        assert [r["moves"] for r in store.list_runs()] == ["moore"]  # the database records the run's model
