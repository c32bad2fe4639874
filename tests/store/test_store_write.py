"""`Store.write_pairs`' fast paths against the plain-Python oracle rows: row encoding (both forms), SQLite's
multi-row INSERT statements and its parameter limit, chunked encoding inside one transaction per batch."""

from __future__ import annotations

import math
import sqlite3

import numpy as np
import pytest

from tests.store.test_store_db import HARM_FLOATS, _oracle_rows, _raw_rows
from vinadv.store import Store, codec, pairs
from vinadv.store.codec import INSERT_COLUMNS, encode_rows
from vinadv.testing.store import random_records


def _comparable(row: tuple) -> tuple:
    """A row with NaN as the string 'NaN' (NaN != NaN) and each value's type, so == checks types too."""
    return tuple(("NaN" if isinstance(v, float) and math.isnan(v) else v, type(v).__name__) for v in row)


def _sqlite_form(row: tuple) -> tuple:
    """An oracle row in SQLite's native form: attack 0/1, NULL score and harm costs NaN, NULL dh/dv -1, NULL
    added_more ''."""
    col = dict(zip(INSERT_COLUMNS, row))
    col["attack"] = int(col["attack"])
    col["score"] = math.nan if col["score"] is None else col["score"]
    col["dh"] = -1 if col["dh"] is None else col["dh"]
    col["dv"] = -1 if col["dv"] is None else col["dv"]
    for name in HARM_FLOATS:
        col[name] = math.nan if col[name] is None else col[name]
    col["added_more"] = "" if col["added_more"] is None else col["added_more"]
    for side in ("o", "a"):
        col[f"expanded_{side}"] = col[f"expanded_{side}"] or ""
        col[f"astar_expansions_{side}"] = (
            -1 if col[f"astar_expansions_{side}"] is None else col[f"astar_expansions_{side}"]
        )
    return tuple(col.values())


@pytest.mark.parametrize("n_added", [1, 3])
@pytest.mark.parametrize(("lo", "hi"), [(0, None), (0, 0), (5, 17), (59, 60), (40, 1000)])
def test_encode_rows_match_oracle(lo, hi, n_added):
    # pair_index 0..59: the oracle's order; the search effort with 3 obstacles (both forms: with and without)
    records = random_records(60, size=13, seed=11, n_added=n_added, effort=n_added == 3)
    expected = _oracle_rows(3, records)[lo:hi]
    assert [_comparable(r) for r in encode_rows(3, records, lo, hi)] == [_comparable(r) for r in expected]
    native = encode_rows(3, records, lo, hi, sqlite=True)
    assert [_comparable(r) for r in native] == [_comparable(_sqlite_form(r)) for r in expected]


@pytest.mark.parametrize(("chunk", "per_statement"), [(100, 7), (2048, 256)])
def test_sqlite_statements_and_chunks_store_the_oracle_rows(sqlite_url, monkeypatch, chunk, per_statement):
    # batches of 1100 and 200 rows: whole statements, and the one-row statements of each chunk's rest
    monkeypatch.setattr(pairs, "ROW_CHUNK", chunk)
    monkeypatch.setattr(pairs, "SQLITE_ROWS_PER_STATEMENT", per_statement)
    records = random_records(1300, size=9, seed=12)
    with Store.open(sqlite_url) as store:
        run_id = store.create_run("chunks")
        assert store.write_pairs(run_id, records, batch_size=1100) == 1300
        back = store.read_pairs(run_id)
        assert back.equals(records)
        assert np.array_equal(np.argsort(back.no), np.arange(1300))  # `no` follows the order written
        assert store._multi_insert[0] == per_statement
    assert _raw_rows(sqlite_url) == _oracle_rows(run_id, records)


def test_sqlite_statements_respect_the_parameter_limit(sqlite_url):
    records = random_records(300, size=7, seed=13)
    with Store.open(sqlite_url) as store:
        run_id = store.create_run("limit")
        with store.engine.connect() as conn:  # the pool's one connection, which write_pairs then uses
            conn.connection.driver_connection.setlimit(sqlite3.SQLITE_LIMIT_VARIABLE_NUMBER, 100)
        assert store.write_pairs(run_id, records) == 300
        assert store._multi_insert[0] == 100 // len(INSERT_COLUMNS)
    assert _raw_rows(sqlite_url) == _oracle_rows(run_id, records)


def test_a_batch_failing_midway_leaves_none_of_its_rows(db_url, monkeypatch):
    # chunks of 50 rows call encode_paths twice each; the 13th call is in batch 2's third chunk, after two of
    # its chunks were inserted: batch 1 stays, batch 2 is rolled back whole
    monkeypatch.setattr(pairs, "ROW_CHUNK", 50)
    real, calls = codec.encode_paths, []

    def failing(*args, **kwargs):
        calls.append(1)
        if len(calls) == 13:
            raise RuntimeError("encoding failed")
        return real(*args, **kwargs)

    monkeypatch.setattr(codec, "encode_paths", failing)
    records = random_records(500, size=7, seed=14)
    with Store.open(db_url) as store:
        run_id = store.create_run("fails")
        with pytest.raises(RuntimeError, match="encoding failed"):
            store.write_pairs(run_id, records, batch_size=200)
        assert np.array_equal(store.stored_indices(run_id), np.arange(200))
        monkeypatch.setattr(codec, "encode_paths", real)
        assert store.write_pairs(run_id, records, batch_size=200) == 300  # the resume writes the rest
        assert store.read_pairs(run_id).equals(records)
