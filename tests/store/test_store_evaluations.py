"""The `evaluations` table: an additive change to schema version 1 (older databases gain it, nothing else moves)."""

import pytest
import sqlalchemy as sa

from vinadv.errors import InputError
from vinadv.store import SCHEMA_VERSION, Store

ROW = dict(
    batch="b1",
    classifier="svm",
    setting="baseline",
    training="balanced",
    train_fraction=1.0,
    train_size=12,
    test_size=6,
    seed=3,
    metrics={"accuracy": 0.75, "per_class": {"FP": {"f1": 0.5}}},
    curves={"roc": {"fpr": [0.0, 1.0], "tpr": [0.0, 1.0]}},
)


def test_rows_round_trip_on_every_backend(db_url):
    with Store.open(db_url) as store:
        run = store.create_run("r")
        assert store.add_evaluations(run, [ROW, {**ROW, "training": "imbalanced", "curves": None}]) == 2
        got = store.read_evaluations(run)
        assert [r["training"] for r in got] == ["balanced", "imbalanced"]
        assert got[0]["metrics"] == ROW["metrics"] and got[0]["curves"] == ROW["curves"]
        assert got[1]["curves"] is None
        assert store.read_evaluations(run + 1) == []
        with pytest.raises(InputError, match="no run"):
            store.add_evaluations(run + 1, [ROW])


def test_database_made_before_the_table_existed_is_upgraded_not_refused(sqlite_url):
    with Store.open(sqlite_url) as store:
        run = store.create_run("old")
    engine = sa.create_engine(sqlite_url)
    with engine.begin() as conn:
        conn.execute(sa.text("DROP TABLE evaluations"))
    with Store.open(sqlite_url, create=False) as store:  # read-only use: no table made, nothing to read
        assert store.read_evaluations(run) == []
    with engine.connect() as conn:
        assert not sa.inspect(conn).has_table("evaluations")
    with Store.open(sqlite_url) as store:
        assert store.add_evaluations(run, [ROW]) == 1
    with engine.connect() as conn:
        assert sa.inspect(conn).has_table("evaluations")
        version = conn.execute(sa.text("SELECT value FROM vinadv_meta WHERE key='schema_version'")).scalar()
        assert version == SCHEMA_VERSION
