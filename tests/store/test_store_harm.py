"""The harm columns of `map_pairs` (schema version 2): round trip, and the upgrade of a version-1 database on
open, on SQLite, MariaDB and PostgreSQL."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
import sqlalchemy as sa

from tests.store.old_schemas import columns_and_version, run_columns, version_1_database
from vinadv.errors import InputError
from vinadv.store import SCHEMA_VERSION, Store
from vinadv.store.schema import map_pairs
from vinadv.testing.store import random_records

HARM_INDEX = next(ix for ix in map_pairs.indexes if ix.name == "ix_map_pairs_run_harm")
HARM_COLUMNS = ("opt_cost_o", "opt_cost_a", "cost_o", "cost_a", "regret_o", "regret_a", "expert_label", "harm")


def _make_version_1(url: str) -> int:
    """A database as vinadv with schema version 1 left it: 30 pairs, no harm columns (nor version 3's
    `added_more`)."""
    return version_1_database(url, 30)


def test_harm_columns_round_trip_with_nulls(db_url):
    records = random_records(120, size=9, seed=8)
    assert np.isnan(records.regret_a).any() and (records.harm == None).any()  # noqa: E711 - NULLs are written too
    with Store.open(db_url) as store:
        run_id = store.create_run("h")
        store.write_pairs(run_id, records)
        back = store.read_pairs(run_id)
    assert back.equals(records)
    for name in HARM_COLUMNS[:6]:
        assert np.allclose(getattr(back, name), getattr(records, name), equal_nan=True, rtol=0, atol=0)
    assert back.harm.tolist() == records.harm.tolist() and back.expert_label.tolist() == records.expert_label.tolist()


def test_version_1_database_is_upgraded_on_open(db_url):
    run_id = _make_version_1(db_url)
    columns, version = columns_and_version(db_url)
    assert version == "1" and not columns & set(HARM_COLUMNS)
    with Store.open(db_url, create=False) as store:  # read-only use: nothing changes, harm reads as NULL
        old = store.read_pairs(run_id)
        assert len(old) == 30 and all(h is None for h in old.harm) and np.isnan(old.opt_cost_o).all()
        page = store.page_pairs(run_id, limit=5)
        assert len(page) == 5 and all(r["harm"] is None and r["regret_a"] is None for r in page)
        assert store.page_pairs(run_id, harm="harmful") == []
        # sorted by what it lacks: every pair without the value, so in pair order, paged as any other order
        for sort in ("harm", "regret"):
            first = store.page_pairs(run_id, sort=sort, limit=5)
            assert [r["pair_index"] for r in first] == sorted(old.pair_index.tolist())[:5]
            after = store.page_pairs(run_id, sort=sort, after=first[-1]["pair_index"], limit=5)
            assert [r["pair_index"] for r in after] == sorted(old.pair_index.tolist())[5:10]
        assert store.page_pairs(run_id, min_regret=0.0) == []
        assert store.harm_counts_by_run() == {run_id: {None: 30}}
        with pytest.raises(InputError, match="opened without create"):
            store.write_pairs(run_id, random_records(2, size=7, seed=9, first_index=500))
    assert columns_and_version(db_url) == (columns, "1")
    with Store.open(db_url) as store:
        assert store.run_moves(run_id) == "octile"  # chained up to version 6: the run's model reads as octile
        assert store.read_pairs(run_id).equals(old)  # the old rows: same values, harm NULL
        new = random_records(10, size=7, seed=4, first_index=100)
        store.write_pairs(run_id, new)
        assert store.read_pairs(run_id, pair_indices=new.pair_index).equals(new)
    columns, version = columns_and_version(db_url)
    assert version == SCHEMA_VERSION == "8" and {*HARM_COLUMNS, "added_more"} <= columns
    assert "moves" in run_columns(db_url)
    with Store.open(db_url) as store:  # opening again changes nothing
        assert store.count_pairs(run_id) == 40


def test_version_1_database_with_a_missing_column_is_refused_untouched(sqlite_url):
    _make_version_1(sqlite_url)
    engine = sa.create_engine(sqlite_url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        conn.execute(sa.text("ALTER TABLE map_pairs DROP COLUMN dv"))
    engine.dispose()
    before = columns_and_version(sqlite_url)
    with pytest.raises(InputError, match=r"lacks columns \['dv'\]"):
        Store.open(sqlite_url)
    assert columns_and_version(sqlite_url) == before


@pytest.mark.parametrize("version", ["0", "99", "1.5"])
def test_unknown_version_is_refused_and_the_file_stays_byte_identical(tmp_path, version):
    path = tmp_path / "v.db"
    url = f"sqlite:///{path}"
    _make_version_1(url)
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        conn.execute(sa.text(f"UPDATE vinadv_meta SET value = '{version}'"))
    engine.dispose()
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    with pytest.raises(InputError, match=f"schema version '{version}'"):
        Store.open(url)
    assert hashlib.sha256(path.read_bytes()).hexdigest() == digest


def test_records_refuse_unknown_harm_values():
    records = random_records(3, size=5, seed=1)
    with pytest.raises(InputError, match="harm: 'bad'"):
        fields = {f: getattr(records, f) for f in records.__dataclass_fields__}
        records.__class__(**{**fields, "harm": ["bad", None, None]})
    part = records.take([2, 0])
    assert part.harm.tolist() == [records.harm[2], records.harm[0]]
    assert np.array_equal(part.regret_a, records.regret_a[[2, 0]], equal_nan=True)


def _index_names(url: str) -> set[str]:
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        names = {ix["name"] for ix in sa.inspect(conn).get_indexes("map_pairs")}
    engine.dispose()
    return names


def test_harm_index_is_made_for_new_databases_and_by_ensure_indexes_for_older_ones(db_url):
    run_id = _make_version_1(db_url)
    assert HARM_INDEX.name not in _index_names(db_url)
    with Store.open(db_url, create=False) as store:  # version 1, not upgraded: no harm column to index yet
        assert store.ensure_indexes() == []
        assert store.page_pairs(run_id, harm="harmful") == []
    assert HARM_INDEX.name not in _index_names(db_url) and columns_and_version(db_url)[1] == "1"
    with Store.open(db_url) as store:  # upgraded on open; the index comes with `ensure_indexes` (`vinadv serve`)
        assert store.ensure_indexes() == [HARM_INDEX.name]
        assert store.ensure_indexes() == []
    with Store.open(db_url) as store:
        fresh = store.create_run("new")
        records = random_records(40, size=7, seed=5)
        store.write_pairs(fresh, records)
        got = [r["pair_index"] for r in store.page_pairs(fresh, harm="harmless", limit=100)]
    assert got == [int(i) for i, h in zip(records.pair_index, records.harm) if h == "harmless"]


def test_new_database_has_the_harm_index_and_the_harm_filter_reads_it(sqlite_url):
    with Store.open(sqlite_url) as store:
        run_id = store.create_run("r")
        store.write_pairs(run_id, random_records(200, size=7, seed=2))
        seen = []
        sa.event.listen(
            store.engine,
            "before_cursor_execute",
            lambda conn, cursor, statement, params, context, many: seen.append((statement, params)),
        )
        store.page_pairs(run_id, harm="harmful", after=50, limit=5)
        statement, params = seen[-1]
        with store.engine.connect() as conn:
            plan = " ".join(str(row) for row in conn.exec_driver_sql("EXPLAIN QUERY PLAN " + statement, params))
    assert HARM_INDEX.name in _index_names(sqlite_url)
    assert f"USING INDEX {HARM_INDEX.name}" in plan and "TEMP B-TREE" not in plan, plan
