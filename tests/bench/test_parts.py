"""An entry computed in parts (`vinadv bench run --chunks LIST --out PART`, then `--parts PART ...`;
`vinadv.bench.parts`): the entry made from parts is the one computed whole; only the chunks no part holds are
computed; a part of another suite, computation or result, or a bad chunk list, is refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.bench.two_maps import heldout_suite, register
from vinadv.bench import job, scoring
from vinadv.bench.parts import PART_FORMAT, Part, parse_chunks, part_chunks, part_json
from vinadv.bench.scoring import chunk_fingerprint, deterministic_part, entry_json, run_bench, run_part
from vinadv.bench.suites import AttackGroup, get_suite
from vinadv.bench.validate import entry_problem
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.planners.registry import load_planner

#: the parts of entries in progress, committed until `--parts` joins them (docs/results/bench.md)
COMMITTED_PARTS = Path(__file__).resolve().parents[2] / "docs" / "results" / "bench" / "parts"


def parts_suite(name: str = "parts3"):
    """Three 28x28 maps in three chunks of one, one random attack of budget 2 (definitions 2)."""
    groups = (AttackGroup(("random",), "add", 2),)
    return heldout_suite(name, 3, 28, groups, "a test suite in parts", budget=2, chunk=1, definitions=2)


@pytest.fixture(scope="module")
def suite():
    return parts_suite()


@pytest.fixture(scope="module")
def planner():
    return load_planner("astar", 28)


@pytest.fixture(scope="module")
def whole(suite, planner):
    return run_bench(suite, planner)


@pytest.fixture
def computed(monkeypatch):
    """The chunks `compute_chunk` computes, in order."""
    ran = []
    compute = scoring.compute_chunk

    def spy(suite, planner, maps, chunk, *args, **kw):
        ran.append(chunk)
        return compute(suite, planner, maps, chunk, *args, **kw)

    monkeypatch.setattr(scoring, "compute_chunk", spy)
    return ran


def _write(tmp_path, name: str, part: dict) -> str:
    path = tmp_path / name
    path.write_text(part_json(part), encoding="utf-8")
    return str(path)


@pytest.mark.parametrize(
    ("text", "expected"),
    [("0", [0]), ("2,0", [0, 2]), ("0-2", [0, 1, 2]), (" 1 - 2 ,1", [1, 2]), ("0-0,4-5", [0, 4, 5])],
)
def test_a_chunk_list_names_each_chunk_once_in_order(text, expected):
    assert parse_chunks(text, 6) == expected


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ("x", "is not a chunk"),
        ("2-1", "not within"),
        ("6", "not within"),
        ("", "is not a chunk"),
        ("-1", "is not a chunk"),
        ("1,,2", "is not"),
    ],
)
def test_a_bad_chunk_list_names_chunks(text, why):
    with pytest.raises(InputError, match=f"chunks: .*{why}") as info:
        parse_chunks(text, 6)
    assert info.value.parameters == ("chunks",)


def test_an_entry_made_from_parts_is_the_entry_computed_whole(suite, planner, whole, tmp_path, computed):
    first = run_part(suite, planner, [0])
    rest = run_part(suite, planner, [1, 2])
    assert first["format"] == PART_FORMAT and sorted(first["chunks"]) == ["0"] and sorted(rest["chunks"]) == ["1", "2"]
    assert computed == [0, 1, 2]
    paths = [_write(tmp_path, "a.json", first), _write(tmp_path, "b.json", rest)]
    parts = [Part.read(p, suite) for p in paths]
    entry = run_bench(suite, planner, parts=parts)
    assert computed == [0, 1, 2]  # nothing computed again
    assert entry_json(deterministic_part(entry)) == entry_json(deterministic_part(whole))
    assert [p["chunks"] for p in entry["time"]["parts"]] == [[0], [1, 2]]
    assert entry["time"]["parts"][0]["sha256"] == parts[0].sha256
    assert entry_problem(entry) is None
    assert entry_problem({**entry, "time": {**entry["time"], "parts": [{"sha256": "x", "chunks": [0]}]}}) is not None


def test_only_the_chunks_no_part_holds_are_computed(suite, planner, whole, tmp_path, computed):
    path = _write(tmp_path, "mid.json", run_part(suite, planner, [1]))
    computed.clear()
    entry = run_bench(suite, planner, parts=[Part.read(path, suite)])
    assert sorted(computed) == [0, 2]
    assert entry_json(deterministic_part(entry)) == entry_json(deterministic_part(whole))


def test_a_part_takes_its_chunks_from_a_database_with_resume(suite, planner, tmp_path, computed):
    db = str(tmp_path / "b.db")
    run_part(suite, planner, [0, 1], db=db)
    computed.clear()
    part = run_part(suite, planner, [1, 2], db=db, resume=True)
    assert computed == [2] and sorted(part["chunks"]) == ["1", "2"]
    assert not any("fingerprint" in chunk for chunk in part["chunks"].values())


def test_the_cli_computes_parts_and_joins_them(suite, whole, tmp_path, monkeypatch, capsys):
    register(monkeypatch, suite)
    run = ["bench", "run", "--suite", suite.name, "--planner", "astar"]
    a, b, out = (str(tmp_path / n) for n in ("a.json", "b.json", "entry.json"))
    assert main([*run, "--chunks", "0,2", "--out", a]) == 0
    said = capsys.readouterr().out
    assert "chunks 0,2 (2 maps)" in said and a in said and "--parts" in said
    assert main([*run, "--chunks", "1", "--out", b, "--quiet"]) == 0
    assert json.loads(open(a, encoding="utf-8").read())["format"] == PART_FORMAT
    assert main([*run, "--parts", a, b, "--out", out, "--quiet"]) == 0
    entry = json.loads(open(out, encoding="utf-8").read())
    assert entry_json(deterministic_part(entry)) == entry_json(deterministic_part(whole))
    # the output is not one of the parts it reads
    assert main([*run, "--parts", a, b, "--out", a, "--quiet"]) == 2
    assert "it is the input --parts" in capsys.readouterr().err


def _refused(argv, capsys) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0, err
    return err


def test_bad_chunks_and_parts_are_one_line(suite, planner, tmp_path, monkeypatch, capsys):
    register(monkeypatch, suite)
    run = ["bench", "run", "--suite", suite.name, "--planner", "astar", "--quiet"]
    assert "--chunks" in _refused([*run, "--chunks", "3"], capsys)
    assert "--paper: a part" in _refused([*run, "--chunks", "0", "--paper", "https://example.org"], capsys)
    assert "--author: a part" in _refused([*run, "--chunks", "0", "--author", "Ada"], capsys)
    part = run_part(suite, planner, [0])
    good = _write(tmp_path, "good.json", part)
    cases = {
        "another suite": ({**part, "suite": {**part["suite"], "name": "vin28-v2"}}, "field 'suite.name'"),
        "another checksum": ({**part, "suite": {**part["suite"], "checksum": "0" * 64}}, "field 'suite.checksum'"),
        "a chunk past the suite": ({**part, "chunks": {"7": part["chunks"]["0"]}}, "'7' is not a chunk"),
        "a chunk of the wrong maps": (
            {**part, "chunks": {"1": part["chunks"]["0"]}},
            "field 'chunks.1': field 'first_map'",
        ),
        "no fingerprint": ({**part, "fingerprint": None}, "field 'fingerprint' is not an object"),
    }
    for name, (bad, why) in cases.items():
        path = _write(tmp_path, "bad.json", bad)
        err = _refused([*run, "--parts", good, path], capsys)
        assert "bad.json" in err and why in err, (name, err)
    (tmp_path / "entry.json").write_text('{"format": "vinadv.bench_entry/2"}', encoding="utf-8")
    err = _refused([*run, "--parts", str(tmp_path / "entry.json")], capsys)
    assert "entry.json" in err and PART_FORMAT in err
    assert "missing.json" in _refused([*run, "--parts", str(tmp_path / "missing.json")], capsys)


def test_a_part_of_another_computation_is_refused_naming_both(suite, planner, tmp_path, monkeypatch):
    path = _write(tmp_path, "old.json", run_part(suite, planner, [0]))
    monkeypatch.setattr(scoring, "CHUNK_FORMAT", 3)
    with pytest.raises(InputError, match="old.json: chunk 0 .*results format 2, this run with results format 3"):
        part_chunks([Part.read(path, suite)], chunk_fingerprint(suite, planner))


def test_a_chunk_in_two_parts_must_be_the_same(suite, planner, tmp_path):
    part = run_part(suite, planner, [0])
    same = {**part, "chunks": {"0": {**part["chunks"]["0"], "seconds": 99.0}}}  # another time: the same chunk
    chunk = json.loads(json.dumps(part["chunks"]["0"]))
    chunk["clean"]["reached"] = [not r for r in chunk["clean"]["reached"]]
    other = {**part, "chunks": {"0": chunk}}
    paths = [_write(tmp_path, f"{n}.json", p) for n, p in (("a", part), ("b", same), ("c", other))]
    fingerprint = chunk_fingerprint(suite, planner)
    assert (
        part_chunks([Part.read(p, suite) for p in paths[:2]], fingerprint)[0]["seconds"]
        == part["chunks"]["0"]["seconds"]
    )
    with pytest.raises(
        InputError,
        match="c.json: chunk 0 of this entry was in an earlier part, with another result "
        "than this part's \\(field 'clean'\\)",
    ):
        part_chunks([Part.read(p, suite) for p in (paths[0], paths[2])], fingerprint)


@pytest.mark.parametrize("path", sorted(COMMITTED_PARTS.glob("*.json")), ids=lambda p: p.name)
def test_the_committed_parts_are_parts_of_their_suites(path):
    """Each committed part reads as a part of its suite (this vinadv's checksum, every chunk's schema), is named after
    its suite, planner and chunks, and holds chunks computed as this vinadv computes them for that planner (the
    fingerprint: results format, 1 for a planner that reports no expansions, and strategy revisions)."""
    raw = json.loads(path.read_text(encoding="utf-8"))
    suite = get_suite(raw["suite"]["name"])
    part = Part.read(path, suite)
    chunks = sorted(part.part["chunks"])
    assert path.name.startswith(f"{suite.name}.{raw['planner']['name']}.chunks-{chunks[0]}-{chunks[-1]}")
    planner = load_planner(raw["planner"]["name"], suite.size, moves=suite.movement())
    assert raw["fingerprint"] == chunk_fingerprint(suite, planner)


def test_a_part_refuses_submission_fields(suite, monkeypatch):
    register(monkeypatch, suite)
    config = job.BenchConfig(suite.name, "astar", authors=("Ada Lovelace",))
    with pytest.raises(InputError, match="authors: a part holds no submission") as info:
        job.run(config, chunks="0")
    assert info.value.parameters == ("authors", "chunks", "parts")
