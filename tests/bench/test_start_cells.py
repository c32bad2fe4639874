"""The one-cell cells the chains of a suite start from (`AttackGroup.start`), kept in each chunk (`start_cells`) and
in the entry (`per_map.start_cells`, optional): what they hold, their schema, and `bench verify`'s check of them."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.bench.test_reuse import reuse_suite
from tests.bench.two_maps import register, two_map_suite
from vinadv.attacks import strategies
from vinadv.bench.outcomes import cells_array, cells_json
from vinadv.bench.scoring import compute_chunk, entry_json, make_entry, planner_checks, run_bench, suite_maps
from vinadv.bench.validate import chunk_problem, entry_problem
from vinadv.bench.verify import pick_chunks, verify_entry
from vinadv.errors import InputError
from vinadv.planners.registry import load_planner
from vinadv.planners.vin.planner import as_planner
from vinadv.robustness import attack_settings, robustness
from vinadv.testing.planners import planning_vin

SIZE = 10


@pytest.fixture(scope="module")
def planner():
    return as_planner(planning_vin(SIZE, seed=1, noise=0.2), SIZE)


@pytest.fixture(scope="module")
def chunks(planner):
    suite = reuse_suite()
    maps = suite_maps(suite)
    return {c: compute_chunk(suite, planner, maps, c) for c in range(2)}


@pytest.fixture(scope="module")
def entry(planner, chunks):
    suite = reuse_suite()
    return make_entry(suite, planner, chunks, planner_checks(suite, planner, suite_maps(suite)), 1.0)


def _copy(value):
    return json.loads(json.dumps(value))


def test_the_entry_holds_the_cells_exhaustive_kept_on_each_map(entry, planner):
    suite = reuse_suite()
    alone = robustness(planner, suite_maps(suite), ["exhaustive"], 1, **attack_settings(suite))
    cells = alone.strategies["exhaustive"].cells[0]  # the whole suite at once: the oracle of the chunks' cells
    stored = entry["per_map"]["start_cells"]
    assert list(stored) == ["add:exhaustive"] and stored["add:exhaustive"] == cells_json(cells)
    labels = entry["per_map"]["attacks"]["add:exhaustive"][0]["label"]
    assert [c is None for c in stored["add:exhaustive"]] == [label == "" for label in labels]
    assert any(c is not None for c in stored["add:exhaustive"])
    np.testing.assert_array_equal(cells_array(stored["add:exhaustive"]), cells)
    assert cells_array(stored["add:exhaustive"]).dtype == cells.dtype
    assert f'"add:exhaustive": {json.dumps(stored["add:exhaustive"])}' in entry_json(entry)  # one line
    assert entry_problem(entry) is None


def test_an_entry_holds_them_only_where_every_chunk_does(planner, chunks):
    """A chunk stored before the field (resumed from a database) has none: the entry then has none, and reads."""
    old = {0: {k: v for k, v in chunks[0].items() if k != "start_cells"}, 1: chunks[1]}
    assert chunk_problem(old[0], reuse_suite(), 0) is None
    entry = make_entry(reuse_suite(), planner, old, {"gradient_masked": False, "non_deterministic": False}, 1.0)
    assert "start_cells" not in entry["per_map"] and entry_problem(entry) is None


def test_a_suite_without_chains_keeps_no_start_cells():
    suite = two_map_suite("no-chains")
    planner = load_planner("optimal", suite.size)
    assert suite.start_keys() == [] and reuse_suite().start_keys() == ["add:exhaustive"]
    assert "start_cells" not in compute_chunk(suite, planner, suite_maps(suite), 0)


@pytest.mark.parametrize(
    ("tamper", "message"),
    [
        (lambda p: p["start_cells"]["add:exhaustive"].__setitem__(0, [1]), ".add:exhaustive[0]' is [1], expected"),
        (lambda p: p["start_cells"]["add:exhaustive"].__setitem__(1, [1, -2]), ".add:exhaustive[1][1]' is -2"),
        (lambda p: p["start_cells"]["add:exhaustive"].pop(), ".add:exhaustive' holds 2 values, expected 3"),
        (lambda p: p["start_cells"].update({"add:nothing": [None] * 3}), ".add:nothing' is an attack the entry has"),
    ],
)
def test_the_entry_schema_names_a_bad_start_cell(entry, tamper, message):
    bad = _copy(entry)
    tamper(bad["per_map"])
    assert entry_problem(bad).startswith(f"field 'per_map.start_cells{message}")


def test_the_chunk_schema_names_a_bad_start_cell(chunks):
    suite = reuse_suite()
    bad = _copy(chunks[0])
    bad["start_cells"]["add:exhaustive"][0] = [0, SIZE]
    assert chunk_problem(bad, suite, 0).startswith(f"field 'start_cells.add:exhaustive[0][1]' is {SIZE}, expected")
    bad["start_cells"] = {"add:random": [None, None]}
    assert chunk_problem(bad, suite, 0).startswith(
        "field 'start_cells' holds ['add:random'], expected ['add:exhaustive']"
    )


def test_verify_names_a_tampered_start_cell_in_one_line(entry, planner, monkeypatch):
    register(monkeypatch, reuse_suite())
    assert verify_entry(entry, chunks=2, planner=planner)["differences"] == []
    old = _copy(entry)
    del old["per_map"]["start_cells"]  # an entry made before them (the committed ones): nothing to compare
    assert verify_entry(old, chunks=2, planner=planner)["differences"] == []
    bad = _copy(entry)
    cells = bad["per_map"]["start_cells"]["add:exhaustive"]
    cells[2] = [0, 0] if cells[2] != [0, 0] else [0, 1]  # map 2: chunk 1
    shown = json.dumps(entry["per_map"]["start_cells"]["add:exhaustive"][2])
    seed = next(s for s in range(100) if pick_chunks(2, 1, s) == [1])
    assert verify_entry(bad, chunks=1, seed=seed, planner=planner)["differences"] == [
        f"field 'per_map.start_cells.add:exhaustive[2]': {json.dumps(cells[2])} in the entry, {shown} from the "
        "recomputed chunk 1"
    ]
    assert verify_entry(bad)["differences"] == []  # the figures do not read them: only a recompute checks them


def test_reuse_refuses_start_cells_off_the_suites_maps(entry, planner, monkeypatch):
    bad = _copy(entry)
    bad["per_map"]["start_cells"]["add:exhaustive"][0] = [SIZE, 0]
    monkeypatch.setattr(strategies.STRATEGIES["random"], "revision", strategies.STRATEGIES["random"].revision + 1)
    with pytest.raises(InputError) as err:
        run_bench(reuse_suite(), planner, reuse=bad)
    assert str(err.value).startswith("reuse: field 'per_map.start_cells.add:exhaustive' is not cells of the suite")
