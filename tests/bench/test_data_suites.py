"""Data suites (the MP suites' kind): maps read from public files checked by sha256, each file's first maps imported
with the MP start rule and joined; a search planner's entry carries Opt / Exp joined over the chunks; the one-line
refusals. On tiny synthetic MP-layout files (`export_maps`), not the six real ones."""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np
import pytest

from tests.needs import public_data
from vinadv.bench.scoring import deterministic_part, entry_json, run_bench, suite_maps
from vinadv.bench.suites import AttackGroup, DataFile, DataSuite, get_suite, maps_sha256
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.evaluation.search_metrics import evaluate_search
from vinadv.grid import generate_maps
from vinadv.interop import export_maps, import_maps
from vinadv.planners.registry import load_planner

SIZE = 10


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    """Two MP-layout files of `moore` maps (the test split: 4 and 3 maps)."""
    folder = tmp_path_factory.mktemp("mpd")
    for name, n, seed in (("a_010_moore_c8.npz", 4, 1), ("b_010_moore_c8.npz", 3, 2)):
        export_maps(generate_maps(n, SIZE, seed=seed, n_starts=1, moves="moore"), folder / name, "mpd")
    return folder


def sha(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def tiny_data_suite(folder, chunk: int = 2) -> DataSuite:
    """The first 3 maps of a, then the first 2 of b: their sha256 by hand, from independent imports."""
    a = import_maps(folder / "a_010_moore_c8.npz", "mpd", split="test", starts=1, seed=0).take(np.arange(3))
    b = import_maps(folder / "b_010_moore_c8.npz", "mpd", split="test", starts=1, seed=0).take(np.arange(2))
    digest = maps_sha256(
        np.concatenate([a.obstacles, b.obstacles]),
        np.concatenate([a.starts[:, 0], b.starts[:, 0]]),
        np.concatenate([a.goals, b.goals]),
    )
    return DataSuite(
        name="tiny-mpd",
        description="a test data suite",
        n=5,
        size=SIZE,
        maps_seed=0,
        maps_sha256=digest,
        attacks=(AttackGroup(("random", "key-points"), "add", 1), AttackGroup(("random",), "remove", 1)),
        budget=3,
        chunk=chunk,
        files=(
            DataFile("a_010_moore_c8.npz", sha(folder / "a_010_moore_c8.npz"), 3),
            DataFile("b_010_moore_c8.npz", sha(folder / "b_010_moore_c8.npz"), 2),
        ),
    )


def test_a_data_suite_reads_its_files_first_maps_in_order(data_dir):
    suite = tiny_data_suite(data_dir)
    maps = suite_maps(suite, data_dir)  # refused unless the join is the independent imports' (sha256 above)
    assert len(maps) == 5 and maps.moves == "moore" and maps.corner_cutting and maps.n_starts == 1
    assert suite.checksum != dataclasses.replace(suite, files=suite.files[:1]).checksum  # the files are in the spec


def test_a_changed_or_missing_file_and_a_missing_folder_are_one_line(data_dir, tmp_path):
    suite = tiny_data_suite(data_dir)
    other = dataclasses.replace(suite, files=(dataclasses.replace(suite.files[0], sha256="0" * 64), suite.files[1]))
    with pytest.raises(InputError) as err:
        suite_maps(other, data_dir)
    assert "0" * 64 in str(err.value) and suite.files[0].sha256 in str(err.value) and "a_010" in str(err.value)
    with pytest.raises(InputError, match="b_010_moore_c8.npz: no such file"):
        (tmp_path / "a_010_moore_c8.npz").write_bytes((data_dir / "a_010_moore_c8.npz").read_bytes())
        suite_maps(suite, tmp_path)
    with pytest.raises(InputError, match="reads public files: give data"):
        suite_maps(suite)
    with pytest.raises(InputError, match="makes its maps"):
        suite_maps(get_suite("vin28-quick-v1"), data_dir)


def test_the_mp_suites_are_registered_on_moore_and_the_command_asks_for_data(capsys, tmp_path):
    full, quick = get_suite("mpd32-v1"), get_suite("mpd32-quick-v1")
    assert full.movement() == quick.movement() == "moore" and get_suite("vin28-v1").movement() == "octile"
    assert (full.n, sum(f.maps for f in full.files), quick.n, sum(f.maps for f in quick.files)) == (600, 600, 100, 100)
    assert [f.name for f in full.files] == [f.name for f in quick.files] and len(full.files) == 6
    assert "add:exhaustive" in full.attack_keys() and "add:exhaustive" not in quick.attack_keys()
    argv = ["bench", "run", "--suite", "mpd32-quick-v1", "--planner", "astar", "--out", str(tmp_path / "e.json")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--data" in err and "mazes_032_moore_c8.npz" in err


@pytest.mark.slow
def test_a_search_planners_entry_joins_opt_and_exp_over_chunks_and_repeats_byte_for_byte(data_dir):
    suite = tiny_data_suite(data_dir, chunk=2)
    planner = load_planner("wastar:w=2", SIZE, moves="moore")
    first = run_bench(suite, planner, data=data_dir)
    whole = evaluate_search(planner, suite_maps(suite, data_dir))  # one pass over all five maps: the oracle
    got = first["clean"]["search"]
    for key in ("rows", "opt", "exp", "success", "hmean", "expansions", "astar_expansions", "cost_ratio"):
        assert got[key] == pytest.approx(whole[key], rel=1e-12), key
    assert first["clean"]["gppn"] is None and first["planner"]["config"]["moves"] == "moore"
    second = run_bench(suite, planner, data=data_dir)
    assert entry_json(deterministic_part(first)) == entry_json(deterministic_part(second))


@pytest.mark.slow
def test_the_mp_suites_maps_are_the_frozen_ones_from_the_shared_files():
    """The six real files (`skip_or_fail` without them): their sha256 and the joined maps' sha256 are the frozen
    ones, and the quick suite's maps are the full suite's first maps of each family."""
    files = [public_data(f"mpd/{f.name}") for f in get_suite("mpd32-v1").files]  # names the first one missing
    folder = files[0].parent
    full = suite_maps(get_suite("mpd32-v1"), folder)
    quick = suite_maps(get_suite("mpd32-quick-v1"), folder)
    assert (len(full), len(quick), full.size, full.moves) == (600, 100, 32, "moore")
    take = np.concatenate([np.arange(100 * i, 100 * i + (17 if i < 4 else 16)) for i in range(6)])
    np.testing.assert_array_equal(quick.obstacles, full.obstacles[take])
    np.testing.assert_array_equal(quick.starts, full.starts[take])
