"""Pairs of several added obstacles in the store (schema version 3's `added_more`), the upgrade of a version-2
database, and the `robustness` table, on SQLite, MariaDB and PostgreSQL."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
import sqlalchemy as sa

from tests.store.old_schemas import columns_and_version, old_database
from vinadv.errors import InputError
from vinadv.store import SCHEMA_VERSION, Store
from vinadv.testing.store import random_records
from vinadv.vocabulary import TIMING


def _rows(url: str, run_id: int) -> list[tuple]:
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        rows = conn.execute(
            sa.text(
                f"SELECT pair_index, added_obstacle, added_more FROM map_pairs "
                f"WHERE run_id = {int(run_id)} ORDER BY pair_index"
            )
        ).all()
    engine.dispose()
    return [tuple(r) for r in rows]


def test_every_added_cell_round_trips_and_one_obstacle_rows_keep_added_more_null(db_url):
    three = random_records(40, size=9, seed=1, n_added=3)
    one = random_records(25, size=9, seed=2)
    with Store.open(db_url) as store:
        run3, run1 = store.create_run("three"), store.create_run("one")
        store.write_pairs(run3, three)
        store.write_pairs(run1, one)
        back3, back1 = store.read_pairs(run3), store.read_pairs(run1)
    assert back3.equals(three) and back3.added.shape == (40, 3, 2)
    assert back1.equals(one) and back1.added.shape == (25, 1, 2)
    # plain Python oracle of the text columns: the first cell as ever, the others "r,c;r,c" in order
    for (_, first, more), cells in zip(_rows(db_url, run3), three.added.tolist()):
        assert first == "{},{}".format(*cells[0]) and more == ";".join("{},{}".format(*c) for c in cells[1:])
    assert all(more is None for _, _, more in _rows(db_url, run1))


def test_a_read_mixing_obstacle_counts_is_refused(sqlite_url):
    with Store.open(sqlite_url) as store:
        run = store.create_run("mixed")
        store.write_pairs(run, random_records(5, size=7, seed=1, n_added=2))
        store.write_pairs(run, random_records(5, size=7, seed=2, first_index=10))
        with pytest.raises(InputError, match="different numbers of added obstacles"):
            store.read_pairs(run)
        assert store.read_pairs(run, pair_indices=np.arange(5)).added.shape == (5, 2, 2)


def _make_version_2(url: str) -> int:
    """A database as vinadv with schema version 2 left it: 20 one-obstacle pairs, no `added_more`, no robustness
    table."""

    def undo(conn, quote):
        conn.execute(sa.text("ALTER TABLE map_pairs DROP COLUMN added_more"))
        conn.execute(sa.text("DROP TABLE robustness"))

    return old_database(url, 2, 20, undo)


def test_version_2_database_is_upgraded_on_open_and_read_only_reads_one_obstacle(db_url):
    run_id = _make_version_2(db_url)
    before = columns_and_version(db_url)
    assert before[1] == "2" and "added_more" not in before[0]
    with Store.open(db_url, create=False) as store:  # read-only use: nothing changes
        old = store.read_pairs(run_id)
        assert old.added.shape == (20, 1, 2) and store.read_robustness() == []
        with pytest.raises(InputError, match="opened without create"):
            store.write_pairs(run_id, random_records(2, size=7, seed=9, first_index=500))
    assert columns_and_version(db_url) == before
    with Store.open(db_url) as store:
        assert store.read_pairs(run_id).equals(old)
        new = random_records(6, size=7, seed=4, n_added=2)
        fresh = store.create_run("new")
        store.write_pairs(fresh, new)
        assert store.read_pairs(fresh).equals(new)
        assert store.add_robustness("vin", None, {"n": 3}, {"clean": {}}) >= 1
    columns, version = columns_and_version(db_url)
    assert version == SCHEMA_VERSION == "8" and "added_more" in columns


def test_version_2_database_read_only_stays_byte_identical(tmp_path):
    path = tmp_path / "v2.db"
    url = f"sqlite:///{path}"
    _make_version_2(url)
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    with Store.open(url, readonly=True) as store:
        assert len(store.read_pairs(1)) == 20 and store.read_robustness() == []
        assert store.read_measurement(1, TIMING) is None  # no version before 4 has the table
    assert hashlib.sha256(path.read_bytes()).hexdigest() == digest


def test_robustness_rows_round_trip(db_url):
    settings = {"n": 10, "seed": 1000, "strategies": ["random"], "max_obstacles": 2}
    result = {"clean": {"success_rate": 0.9}, "overall": [{"k": 1, "harmful_rate": 0.25}]}
    with Store.open(db_url) as store:
        first = store.add_robustness("vin", "ab" * 32, settings, result)
        second = store.add_robustness("optimal", None, {**settings, "n": 5}, result)
        rows = store.read_robustness()
        assert [r["id"] for r in rows] == [first, second]
        assert rows[0]["planner"] == "vin" and rows[0]["weights_checksum"] == "ab" * 32
        # version 0 records (`vinadv.records`): read with the fields their writers left out
        filled = {"moves": "octile", "maps": None, "maps_sha256": None, "edit": "add"}
        filled |= {"planner": None, "name": None, "effort_tolerance": None}  # and those of version 2
        assert rows[0]["settings"] == {**filled, **settings, "record_version": 2}
        assert rows[0]["result"] == {**result, "record_version": 2}
        assert rows[1]["weights_checksum"] is None
        assert [r["id"] for r in store.read_robustness([second])] == [second]
