"""The pairs' edit (`add` or `remove`, the step to schema version 7's `edit` column): stored and read back, and an
older database (version 4, the one before the step) upgraded on open, its rows read as `add`, on SQLite, MariaDB
and PostgreSQL."""

from __future__ import annotations

import numpy as np
import pytest

from tests.store.old_schemas import columns_and_version, old_database
from vinadv.errors import InputError
from vinadv.store import SCHEMA_VERSION, Store
from vinadv.testing.store import random_records


def test_edits_round_trip(db_url):
    records = random_records(40, size=7, seed=11, removes=0.5, n_added=2)
    assert 5 < (records.edit == "remove").sum() < 35  # both edits present
    with Store.open(db_url) as store:
        run_id = store.create_run("edits")
        store.write_pairs(run_id, records)
        back = store.read_pairs(run_id)
    assert back.equals(records) and list(back.edit) == list(records.edit)


def test_version_4_database_is_upgraded_and_its_rows_read_as_add(db_url):
    run_id = old_database(db_url, 4, 12, lambda conn, quote: None)
    before = columns_and_version(db_url)
    assert before[1] == "4" and "edit" not in before[0]
    with Store.open(db_url, create=False) as store:  # read-only use: nothing changes, the rows read as `add`
        old = store.read_pairs(run_id)
        assert list(old.edit) == ["add"] * 12
        with pytest.raises(InputError, match="opened without create"):
            store.write_pairs(run_id, random_records(2, size=7, seed=9, first_index=500))
    assert columns_and_version(db_url) == before
    with Store.open(db_url) as store:
        assert store.read_pairs(run_id).equals(old)
        fresh = store.create_run("new")
        new = random_records(10, size=7, seed=4, removes=0.5)
        store.write_pairs(fresh, new)
        assert np.array_equal(store.read_pairs(fresh).edit, new.edit)
    columns, version = columns_and_version(db_url)
    assert version == SCHEMA_VERSION == "8" and "edit" in columns
