"""The Moving AI suites: registered and frozen, read from `--data DIR` like the MP suites (each file by sha256), their
maps windows of the real files (checked against a plain-Python reading of the `.map` text), the quick suite's maps
the full one's first of each file; a planner trained with corner cutting is flagged when run under their rule."""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np
import pytest

from tests.needs import public_data
from vinadv.bench.flags import raise_flags, trained_rules
from vinadv.bench.movingai_suites import QUICK_PER_FILE, MovingAISuite
from vinadv.bench.scoring import data_suite_maps, run_bench, suite_maps
from vinadv.bench.suites import FROZEN, AttackGroup, DataFile, get_suite, maps_sha256
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.interop import import_maps
from vinadv.interop.formats.movingai import write_map
from vinadv.planners.registry import load_planner

CITIES = ("Berlin_1_256.map", "Boston_0_256.map", "Milan_0_256.map", "Paris_1_256.map")
MAPF = ("random-64-64-10.map", "room-64-64-8.map", "room-64-64-16.map")


def plain_grid(path) -> list[str]:
    """The grid rows of a `.map` file, read as text: an independent oracle of the importer."""
    return path.read_text().splitlines()[4:]


def test_the_moving_ai_suites_are_registered_frozen_and_ask_for_their_files(capsys, tmp_path):
    full, quick = get_suite("movingai64-v1"), get_suite("movingai64-quick-v1")
    assert {"movingai64-v1", "movingai64-quick-v1"} <= set(FROZEN)
    assert [f.name for f in full.files] == [f.name for f in quick.files] == [*CITIES, *MAPF]
    assert [f.maps for f in full.files] == [50] * 4 + [25] * 3 and full.n == 275 == sum(full.draws)
    assert quick.n == 70 == QUICK_PER_FILE * 7 and quick.draws == full.draws  # the same draws: a prefix of each
    for suite in (full, quick):
        assert (suite.size, suite.movement(), suite.cuts_corners(), suite.crop) == (64, "octile", False, 64)
    assert get_suite("vin28-v1").cuts_corners() and get_suite("mpd32-v1").cuts_corners()
    assert "add:exhaustive" in full.attack_keys() and "add:exhaustive" not in quick.attack_keys()
    argv = ["bench", "run", "--suite", "movingai64-quick-v1", "--planner", "astar", "--out", str(tmp_path / "e.json")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--data" in err and "Berlin_1_256.map" in err


def tiny_suite(folder, draws=(3, 2), take=(2, 2)) -> MovingAISuite:
    """Windows of 8x8 drawn from a 16x16 and a 12x12 `.map` file written here; its maps' sha256 not frozen (zeros)."""
    rng = np.random.default_rng(5)
    files = []
    for name, side in (("a.map", 16), ("b.map", 12)):
        write_map(rng.random((side, side)) < 0.2, folder / name)
        files.append(name)
    suite = MovingAISuite(
        name="tiny-movingai",
        description="a test suite",
        n=sum(take),
        size=8,
        maps_seed=3,
        maps_sha256="0" * 64,
        attacks=(AttackGroup(("random", "key-points"), "add", 1),),
        budget=3,
        chunk=2,
        crop=8,
        files=tuple(DataFile(f, hashlib.sha256((folder / f).read_bytes()).hexdigest(), k) for f, k in zip(files, take)),
        draws=draws,
    )
    return suite


def test_a_moving_ai_suite_reads_windows_of_its_files(tmp_path):
    suite = tiny_suite(tmp_path)
    with pytest.raises(InputError, match="reader makes other maps"):
        suite_maps(suite, tmp_path)
    maps = data_suite_maps(suite, tmp_path)
    assert len(maps) == 4 and not maps.corner_cutting and maps.moves == "octile"
    for i in range(len(maps)):  # each map is the window of its file at its origin
        rows = plain_grid(tmp_path / str(maps.source[i]))
        r, c = (int(v) for v in maps.origin[i])
        window = np.array([[ch == "@" for ch in row[c : c + 8]] for row in rows[r : r + 8]])
        np.testing.assert_array_equal(maps.obstacles[i], window)
    assert list(maps.source) == ["a.map", "a.map", "b.map", "b.map"]
    for k, (name, draws, seed) in enumerate((("a.map", 3, 3), ("b.map", 2, 4))):  # maps_seed plus the file's place
        alone = import_maps(tmp_path / name, "movingai", crop=8, crops=draws, seed=seed)
        np.testing.assert_array_equal(maps.obstacles[2 * k : 2 * k + 2], alone.obstacles[:2])
        np.testing.assert_array_equal(maps.goals[2 * k : 2 * k + 2], alone.goals[:2])


@pytest.mark.slow
def test_a_moving_ai_suites_entry_plans_under_its_rule(tmp_path):
    suite = tiny_suite(tmp_path)
    maps = data_suite_maps(suite, tmp_path)
    suite = dataclasses.replace(suite, maps_sha256=maps_sha256(maps.obstacles, maps.starts[:, 0], maps.goals))
    entry = run_bench(suite, load_planner("astar", 8, corner_cutting=False), data=tmp_path)
    assert entry["clean"]["maps"] == 4 and entry["clean"]["percent_optimal"] == 1.0  # A*'s paths: the maps' rule
    assert "other_rules" not in entry["flags"]


def test_a_planner_trained_with_corner_cutting_is_flagged_under_the_moving_ai_rule():
    vin64 = load_planner("vin", 64, weights="vin64", corner_cutting=False)
    assert trained_rules(vin64) == {"corner_cutting": True, "moves": "octile"}
    assert trained_rules(load_planner("astar", 64)) is None  # no weights: no training rule
    checks = {"trained_rules": trained_rules(vin64), "gradient_masked": True}
    flags = raise_flags(get_suite("movingai64-quick-v1"), checks, 0.9, {})
    flag = flags["other_rules"]
    assert flag["raised"] and "with corner cutting" in flag["why"] and "without corner cutting" in flag["why"]
    assert "gradient is zero" in flags["gradient_masking"]["why"]  # each flag says its own why
    assert "other_rules" not in raise_flags(get_suite("vin28-quick-v1"), checks, 0.9, {})  # trained as it runs


@pytest.mark.slow
def test_the_moving_ai_suites_maps_are_windows_of_the_shared_files():
    """The seven real files (`skip_or_fail` without them): the frozen maps' sha256 (checked by `suite_maps`), every
    quick map the window of its file at its recorded origin, and the quick maps the full suite's first of each file."""
    paths = [public_data(f"movingai/{f.name}") for f in get_suite("movingai64-v1").files]
    folder = paths[0].parent
    full = suite_maps(get_suite("movingai64-v1"), folder)
    quick = suite_maps(get_suite("movingai64-quick-v1"), folder)
    assert (len(full), len(quick), quick.size, quick.corner_cutting) == (275, 70, 64, False)
    grids = {p.name: plain_grid(p) for p in paths}
    for i in range(len(quick)):
        rows = grids[str(quick.source[i])]
        r, c = (int(v) for v in quick.origin[i])
        window = np.array([[ch not in ".GS" for ch in row[c : c + 64]] for row in rows[r : r + 64]])
        np.testing.assert_array_equal(quick.obstacles[i], window)
        assert not window[tuple(quick.goals[i])] and not window[tuple(quick.starts[i, 0])]
    assert list(quick.source[::10]) == [*CITIES, *MAPF]
    take = np.concatenate([np.arange(first, first + 10) for first in (0, 50, 100, 150, 200, 225, 250)])
    np.testing.assert_array_equal(quick.obstacles, full.obstacles[take])
    np.testing.assert_array_equal(quick.starts, full.starts[take])
    np.testing.assert_array_equal(quick.goals, full.goals[take])
