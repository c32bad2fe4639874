"""`vinadv bench run --reuse ENTRY` (`vinadv.bench.reuse`): the attacks of an older entry whose strategies did not
change are taken from it, the others computed; the entry is a full recompute's (deterministic part), and only the
changed strategies run, each in its group (and a changed chain's start, where the entry holds no start cells)."""

from __future__ import annotations

import hashlib
import json

import pytest

from tests.bench.test_entry2 import COMMITTED
from tests.bench.two_maps import heldout_suite, register
from vinadv.attacks import strategies
from vinadv.bench import scoring
from vinadv.bench.reuse import ReusedEntry, plan_reuse, recorded_computation
from vinadv.bench.scoring import compute_chunk, deterministic_part, entry_json, run_bench, suite_maps
from vinadv.bench.suites import AttackGroup, get_suite
from vinadv.bench.validate import entry_problem
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.planners.registry import load_planner
from vinadv.planners.vin.planner import as_planner
from vinadv.testing.planners import planning_vin

SIZE = 10
GROUPS = (
    AttackGroup(("near-path", "random"), "add", 2),
    AttackGroup(("exhaustive",), "add", 1),
    AttackGroup(("random", "near-path"), "add", 3, start="exhaustive"),
    AttackGroup(("key-points",), "remove", 1),
)


def reuse_suite(name: str = "reuse2"):
    """Three 10x10 maps in two chunks; groups of two strategies; chains started from exhaustive's one-cell optimum."""
    return heldout_suite(name, 3, SIZE, GROUPS, "a test suite of definitions 2", budget=3, chunk=2, definitions=2)


@pytest.fixture(scope="module")
def planner():
    return as_planner(planning_vin(SIZE, seed=1, noise=0.2), SIZE)


@pytest.fixture(scope="module")
def entry(planner):
    return run_bench(reuse_suite(), planner)


@pytest.fixture
def runs(monkeypatch):
    """The strategies of each group `compute_chunk` runs (one tuple per chunk and group), and how many chunks'
    clean parts it computes."""
    ran = {"groups": [], "clean": 0}
    robustness, clean = scoring.robustness, scoring._clean_part

    def spy(planner, maps, names, *args, **kwargs):
        ran["groups"].append(tuple(names))
        return robustness(planner, maps, names, *args, **kwargs)

    def spy_clean(*args):
        ran["clean"] += 1
        return clean(*args)

    monkeypatch.setattr(scoring, "robustness", spy)
    monkeypatch.setattr(scoring, "_clean_part", spy_clean)
    return ran


def test_an_entry_records_the_revisions_it_was_computed_with(entry):
    assert entry["computed_with"] == {
        "results_format": 1,  # a VIN reports no expansions
        "strategies": {"exhaustive": 1, "key-points": 2, "near-path": 1, "random": 1},
    }
    assert entry_problem(entry) is None
    bad = {**entry, "computed_with": {"results_format": 0, "strategies": {}}}
    assert entry_problem(bad).startswith("field 'computed_with.results_format' is 0")
    bad = {**entry, "computed_with": {"results_format": 1, "strategies": {"random": "1"}}}
    assert entry_problem(bad).startswith("field 'computed_with.strategies.random' is a string")
    old = {k: v for k, v in entry.items() if k != "computed_with"}
    assert entry_problem(old) is None  # optional: entries made before it have none


def _without_start_cells(entry: dict) -> dict:
    """`entry` as made before entries held the chains' start cells."""
    return {**entry, "per_map": {k: v for k, v in entry["per_map"].items() if k != "start_cells"}}


@pytest.mark.parametrize(
    ("bumped", "cells", "ran", "computed"),
    [
        # one strategy of a group of two: that strategy alone, in each group that runs it
        ("key-points", True, [("key-points",)], ["remove:key-points"]),
        ("near-path", True, [("near-path",), ("near-path",)], ["add:near-path", "add:exhaustive+near-path"]),
        # a chain's strategy: it starts from the start cells the entry holds, exhaustive does not run
        ("random", True, [("random",), ("random",)], ["add:random", "add:exhaustive+random"]),
        # the start strategy: its chains start from other cells, all of them run
        (
            "exhaustive",
            True,
            [("exhaustive",), ("random", "near-path")],
            ["add:exhaustive", "add:exhaustive+random", "add:exhaustive+near-path"],
        ),
        # an entry made before the start cells: a changed chain runs its start again, for its cells
        (
            "random",
            False,
            [("random",), ("exhaustive",), ("random",)],
            ["add:random", "add:exhaustive", "add:exhaustive+random"],
        ),
        ("key-points", False, [("key-points",)], ["remove:key-points"]),
    ],
)
def test_a_bumped_revision_recomputes_that_strategy_alone_into_a_full_recomputes_entry(
    entry, planner, runs, monkeypatch, bumped, cells, ran, computed
):
    suite = reuse_suite()
    older = entry if cells else _without_start_cells(entry)
    monkeypatch.setattr(strategies.STRATEGIES[bumped], "revision", strategies.STRATEGIES[bumped].revision + 1)
    reused = run_bench(suite, planner, reuse=older)
    assert runs["groups"] == ran * 2 and runs["clean"] == 0  # per chunk: only those strategies, no clean planner
    runs["groups"].clear()
    full = run_bench(suite, planner)
    assert runs["groups"] == [g.strategies for g in GROUPS] * 2
    if not cells and bumped == "key-points":  # neither the older entry nor this run has exhaustive's cells
        assert "start_cells" not in reused["per_map"]
        reused["per_map"]["start_cells"] = full["per_map"]["start_cells"]
    assert entry_json(deterministic_part(reused)) == entry_json(deterministic_part(full))
    assert reused["computed_with"]["strategies"][bumped] == entry["computed_with"]["strategies"][bumped] + 1
    assert reused["time"]["reused"] == {
        "entry_sha256": hashlib.sha256(entry_json(older).encode()).hexdigest(),
        "attacks": [key for key in suite.attack_keys() if key not in computed],
    }
    assert entry_problem(reused) is None


@pytest.mark.parametrize("search", [False, True])
def test_the_chunks_rebuilt_from_an_entry_are_those_computed(entry, planner, monkeypatch, search):
    """Each chunk's records taken from the entry (pair, valid, broken, counts: from the label; a search planner's
    efforts) and its clean part (a search planner's means and per-map values) are those a full computation of the
    chunk gives, so a chunk made with reuse (stored in a database, resumed) is an ordinary chunk."""
    suite = reuse_suite()
    if search:
        planner = load_planner("astar", SIZE)
        entry = run_bench(suite, planner)
        assert (
            entry["computed_with"]["results_format"] == 2
            and "effort" in entry["per_map"]["attacks"]["add:exhaustive"][0]
        )
    monkeypatch.setattr(strategies.STRATEGIES["near-path"], "revision", 2)
    plan = plan_reuse(suite, planner, entry)
    assert plan.computed == {0: ("near-path",), 2: ("near-path",)} and plan.clean
    assert plan.start_cells == ("add:exhaustive",)
    maps = suite_maps(suite)
    for chunk in range(2):
        part = plan.chunk_part(suite, chunk)
        assert set(part["attacks"]) == {"add:random", "add:exhaustive", "add:exhaustive+random", "remove:key-points"}
        assert len(part["start_cells"]["add:exhaustive"]) == (2, 1)[chunk]
        rebuilt = compute_chunk(suite, planner, maps, chunk, plan.computed, part)
        whole = compute_chunk(suite, planner, maps, chunk)
        for result in (rebuilt, whole):
            result.pop("seconds")
        assert json.dumps(rebuilt, sort_keys=True) == json.dumps(whole, sort_keys=True)


def test_an_entry_without_computed_with_is_of_revision_1_and_its_inferred_format(entry, planner):
    suite = reuse_suite()
    old = {k: v for k, v in entry.items() if k != "computed_with"}
    assert recorded_computation(old, suite) == {
        "results_format": 1,
        "strategies": {"exhaustive": 1, "key-points": 1, "near-path": 1, "random": 1},
    }
    plan = plan_reuse(suite, planner, old)
    assert plan.computed == {3: ("key-points",)} and plan.clean  # key-points is revision 2 since it reads the starts
    assert plan.reused == tuple(k for k in suite.attack_keys() if k != "remove:key-points")
    efforts = json.loads(json.dumps(old))
    for records in efforts["per_map"]["attacks"].values():
        for record in records:
            record["effort"] = [None] * 3
            record["effort_harmful"] = [False] * 3
    assert recorded_computation(efforts, suite)["results_format"] == 2  # a planner's that reports expansions
    plan = plan_reuse(suite, planner, efforts)  # not this planner's results format: nothing is taken
    assert set(plan.computed) == set(range(len(GROUPS))) and not plan.clean and plan.reused == ()


def _other_weights(entry: dict) -> dict:
    other = json.loads(json.dumps(entry))
    other["planner"]["weights_sha256"] = other["weights_sha256"] = "0" * 64
    return other


def _other_name(entry: dict) -> dict:
    return {**entry, "planner": {**entry["planner"], "name": "optimal"}}


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda e: {**e, "suite": {**e["suite"], "checksum": "a" * 64}}, "field 'suite.checksum' is aaaaaaaaaaaa"),
        (_other_weights, "field 'planner.weights_sha256' is 000000000000"),
        (_other_name, "field 'planner' is "),
        (lambda e: {**e, "format": "vinadv.bench_entry/1"}, "field 'format' is 'vinadv.bench_entry/1'"),
        (lambda e: {"format": "vinadv.bench_suite/1"}, "field 'format' is 'vinadv.bench_suite/1'"),
        (lambda e: {**e, "per_map": {**e["per_map"], "chunks": []}}, "field 'per_map.chunks' is an empty list"),
    ],
)
def test_another_suite_planner_weights_or_format_is_refused_naming_the_field(entry, planner, change, field):
    bad = change(entry)
    with pytest.raises(InputError) as err:
        run_bench(reuse_suite(), planner, reuse=bad)
    assert str(err.value).startswith(f"reuse: {field}") and err.value.parameters == ("reuse",)


def test_bench_run_reuse_refuses_what_is_not_an_entry_to_reuse_in_one_line(tmp_path, capsys, monkeypatch):
    suite = register(monkeypatch, reuse_suite())
    other = register(monkeypatch, reuse_suite("reuse2-other"))
    out = tmp_path / "e.json"
    base = ["bench", "run", "--suite", suite.name, "--planner", "optimal", "--quiet"]
    assert main([*base, "--out", str(out)]) == 0
    v1 = tmp_path / "v1.json"
    v1.write_text(json.dumps({**json.loads(out.read_text()), "format": "vinadv.bench_entry/1"}))
    (tmp_path / "not.json").write_text("[1, 2")
    cases = [
        ([*base, "--reuse", str(v1)], "field 'format'"),
        ([*base, "--reuse", str(tmp_path / "not.json")], "not.json: not a vinadv.bench_entry/2 entry"),
        ([*base, "--reuse", str(tmp_path / "none.json")], "none.json"),
        (["bench", "run", "--suite", other.name, "--planner", "optimal", "--reuse", str(out)], "'suite.checksum'"),
        ([*base, "--planner", "astar", "--reuse", str(out)], "field 'planner' is "),
    ]
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert err.startswith("vinadv: error: --reuse: ") and message in err and "\n" not in err, err
    again = tmp_path / "again.json"
    assert main([*base, "--reuse", str(out), "--out", str(again)]) == 0  # nothing changed: nothing computed
    first, second = json.loads(out.read_text()), json.loads(again.read_text())
    assert entry_json(deterministic_part(first)) == entry_json(deterministic_part(second))
    assert second["time"]["reused"]["attacks"] == suite.attack_keys()
    assert second["time"]["reused"]["entry_sha256"] == hashlib.sha256(out.read_bytes()).hexdigest()
    assert main(["bench", "verify", str(again), "--chunks", "2", "--quiet"]) == 0
    bad = {**second, "time": {**second["time"], "reused": {"entry_sha256": "x", "attacks": []}}}
    assert entry_problem(bad).startswith("field 'time.reused.entry_sha256' is 'x'")
    assert main([*base, "--reuse", str(again), "--out", str(again)]) == 0  # in place: read before the work
    assert json.loads(again.read_text())["time"]["reused"]["entry_sha256"] != second["time"]["reused"]["entry_sha256"]


def test_a_committed_entry_without_computed_with_recomputes_its_key_points_attacks():
    """The committed entries were made before `computed_with` (revision 1 everywhere): astar's is results format 2
    (its records carry efforts), so its clean parts are taken, and key-points (revision 2) is computed in each group
    that runs it, the group's other strategies taken."""
    path = COMMITTED / "vin28-quick-v2.astar.json"
    reused = ReusedEntry.read(path)
    assert "computed_with" not in reused.entry and reused.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    suite = get_suite("vin28-quick-v2")
    plan = plan_reuse(suite, load_planner("astar", suite.size), reused)
    with_key_points = [i for i, g in enumerate(suite.attacks) if "key-points" in g.strategies]
    assert plan.clean and plan.computed == dict.fromkeys(with_key_points, ("key-points",)) and len(with_key_points) == 2
    assert plan.reused == tuple(k for k in suite.attack_keys() if not k.endswith(":key-points"))
    assert len(plan.reused) == 6 and plan.start_cells == ()  # the quick suite has no chains
