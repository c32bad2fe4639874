"""Concurrent resumes (issue 45): two `bench run --resume` of one entry on one database at once, made to compute the
same chunk before either stores it by a barrier (deterministic, not by timing). The second store of the chunk used to
die on the unique (entry, chunk) constraint; now it is stored once, the other run checks it is the same and uses it,
and both exit 0 with the same entry. A chunk stored meanwhile with another result or fingerprint is refused, one
line naming both, the stored chunk kept."""

from __future__ import annotations

import json

import pytest
import sqlalchemy as sa

from tests.bench.two_maps import two_map_suite
from tests.store.test_concurrent_writers import in_two_threads, meet_after_first_call
from vinadv.bench import scoring, suites
from vinadv.bench.scoring import deterministic_part, entry_json, entry_key, run_bench
from vinadv.bench.suites import Suite
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.planners.registry import load_planner
from vinadv.store import Store


@pytest.fixture(scope="module")
def tiny() -> Suite:
    return two_map_suite("tiny-concurrent")


@pytest.fixture(scope="module")
def alone(tiny) -> str:
    """The entry's deterministic part, computed without a database."""
    return entry_json(deterministic_part(run_bench(tiny, load_planner("optimal", 28))))


def _rows(db_url: str) -> list[tuple[str, int]]:
    engine = sa.create_engine(db_url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        rows = conn.execute(sa.text("SELECT entry, chunk FROM bench_chunks ORDER BY chunk")).all()
    engine.dispose()
    return [tuple(r) for r in rows]


def test_a_chunk_stored_twice_is_stored_once_and_the_first_kept(db_url):
    with Store.open(db_url) as store:
        assert store.add_bench_chunk("e" * 64, 0, {"first_map": 0, "seconds": 1.0}) is None
        again = store.add_bench_chunk("e" * 64, 0, {"first_map": 0, "seconds": 2.0})
        assert again is not None and again["seconds"] == 1.0  # the stored one, read back; nothing changed
        assert store.read_bench_chunks("e" * 64) == {0: again}
    assert _rows(db_url) == [("e" * 64, 0)]


def test_two_resumes_at_once_both_finish_with_the_same_entry(tiny, alone, db_url, monkeypatch):
    # both compute chunk 0 before either stores it: the second store met the first's row (IntegrityError)
    meet_after_first_call(monkeypatch, scoring, "compute_chunk")

    def resume(i: int) -> str:
        entry = run_bench(tiny, load_planner("optimal", 28), db=db_url, resume=True)
        return entry_json(deterministic_part(entry))

    entries = in_two_threads(resume)
    monkeypatch.undo()
    assert entries == [alone, alone], entries
    key = entry_key(tiny, load_planner("optimal", 28))
    assert _rows(db_url) == [(key, 0), (key, 1)]  # each chunk stored once


def test_two_bench_run_commands_at_once_both_exit_0(tiny, alone, tmp_path, monkeypatch):
    monkeypatch.setitem(suites.SUITES, tiny.name, tiny)
    meet_after_first_call(monkeypatch, scoring, "compute_chunk")
    db = tmp_path / "c.db"

    def command(i: int) -> int:
        argv = ["bench", "run", "--suite", tiny.name, "--planner", "optimal", "--db", str(db), "--resume"]
        return main([*argv, "--out", str(tmp_path / f"X{i}.json"), "--quiet"])

    assert in_two_threads(command) == [0, 0]
    for i in range(2):
        assert entry_json(deterministic_part(json.loads((tmp_path / f"X{i}.json").read_text()))) == alone


def _stored_meanwhile(monkeypatch, db: str, change) -> list[dict]:
    """Make another run store chunk 0, changed by `change(result)`, while this run computes it; the list it is kept
    in, once stored."""
    original, kept = scoring.compute_chunk, []

    def compute(suite, planner, maps, chunk, **kw):
        result = original(suite, planner, maps, chunk, **kw)
        if chunk == 0:
            other = change(json.loads(json.dumps({**result, "fingerprint": scoring.chunk_fingerprint(suite, planner)})))
            with Store.open(db) as store:
                assert store.add_bench_chunk(entry_key(suite, planner), 0, other) is None
            kept.append(other)
        return result

    monkeypatch.setattr(scoring, "compute_chunk", compute)
    return kept


def test_a_chunk_stored_meanwhile_with_another_result_is_refused_naming_both(tiny, tmp_path, monkeypatch):
    db = str(tmp_path / "c.db")

    def other_result(result):
        result["clean"]["reached"] = [not r for r in result["clean"]["reached"]]
        return result

    other = _stored_meanwhile(monkeypatch, db, other_result)
    with pytest.raises(
        InputError,
        match="chunk 0 of this entry was stored meanwhile by another run, with another "
        "result than this run's \\(field 'clean'\\)",
    ):
        run_bench(tiny, load_planner("optimal", 28), db=db, resume=True)
    with Store.open(db, readonly=True) as store:  # the stored chunk kept as it was
        stored = store.read_bench_chunks(entry_key(tiny, load_planner("optimal", 28)))
    assert stored == {0: other[0]}


def test_a_chunk_stored_meanwhile_by_another_computation_is_refused_naming_both(tiny, tmp_path, monkeypatch):
    db = str(tmp_path / "c.db")

    def other_format(result):
        result["fingerprint"]["format"] = 99
        return result

    _stored_meanwhile(monkeypatch, db, other_format)
    with pytest.raises(
        InputError,
        match="stored meanwhile by another run computed with results format 99, this run with results format 1",
    ):
        run_bench(tiny, load_planner("optimal", 28), db=db, resume=True)
