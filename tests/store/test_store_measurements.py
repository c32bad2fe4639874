"""The evaluation stage's measurements of a run (schema version 4's `measurements` table) and the upgrade of a
version-3 database to it, on SQLite, MariaDB and PostgreSQL."""

from __future__ import annotations

import pytest
import sqlalchemy as sa

from tests.store.old_schemas import columns_and_version, old_database, table_names
from vinadv.errors import InputError
from vinadv.store import SCHEMA_VERSION, Store
from vinadv.store.schema import EFFORT_COLUMNS
from vinadv.testing.store import random_records
from vinadv.vocabulary import PLANNER_QUALITY, TIMING


def test_the_newest_measurement_of_a_run_and_kind_is_read_back(db_url):
    quality = {"metrics": {"success_rate": 0.75, "maps": 50}, "source": "a quick evaluation"}
    with Store.open(db_url) as store:
        first, second = store.create_run("a"), store.create_run("b")
        assert store.read_measurement(first, PLANNER_QUALITY) is None
        store.add_measurement(first, PLANNER_QUALITY, {"metrics": {}, "source": "older"})
        store.add_measurement(first, PLANNER_QUALITY, quality)
        store.add_measurement(first, TIMING, {"pairs": 100, "rule_s": 0.25})
        store.add_measurement(second, PLANNER_QUALITY, {"metrics": {}, "source": "the other run"})
        assert store.read_measurement(first, PLANNER_QUALITY) == quality
        assert store.read_measurement(first, TIMING) == {"pairs": 100, "rule_s": 0.25}
        assert store.read_measurement(second, PLANNER_QUALITY)["source"] == "the other run"
        assert store.read_measurement(second, TIMING) is None
        with pytest.raises(InputError, match="kind"):
            store.add_measurement(first, "speed", {})
        with pytest.raises(InputError):
            store.add_measurement(second + 100, TIMING, {})


def _make_version_3(url: str) -> int:
    """A database as vinadv with schema version 3 left it: 20 one-obstacle pairs, no `measurements` table."""
    return old_database(url, 3, 20, lambda conn, quote: None)


def test_version_3_database_is_upgraded_on_open_and_read_only_reads_no_measurement(db_url):
    run_id = _make_version_3(db_url)
    before = columns_and_version(db_url)
    assert before[1] == "3" and "measurements" not in table_names(db_url)
    with Store.open(db_url, create=False) as store:  # read-only use: nothing changes
        assert len(store.read_pairs(run_id)) == 20
        assert store.read_measurement(run_id, TIMING) is None
    assert columns_and_version(db_url) == before and "measurements" not in table_names(db_url)
    with Store.open(db_url) as store:
        store.add_measurement(run_id, TIMING, {"pairs": 20})
        assert store.read_measurement(run_id, TIMING) == {"pairs": 20}
        fresh = store.create_run("new")
        store.write_pairs(fresh, random_records(4, size=7, seed=5))
    assert (
        columns_and_version(db_url) == (before[0] | {"edit", *EFFORT_COLUMNS}, SCHEMA_VERSION) and SCHEMA_VERSION == "8"
    )
    assert "measurements" in table_names(db_url)


def test_a_current_database_without_the_table_is_refused(sqlite_url):
    # stamped with today's version without the table version 4 created: not a database this vinadv wrote
    with Store.open(sqlite_url):
        pass
    engine = sa.create_engine(sqlite_url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        conn.execute(sa.text("DROP TABLE measurements"))
    engine.dispose()
    with pytest.raises(InputError, match="table measurements is missing"):
        Store.open(sqlite_url)
