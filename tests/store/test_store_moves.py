"""A run's movement model in the store (schema version 6's `runs.moves`) and the upgrade of a version-4 or -5 database
to it, on SQLite, MariaDB and PostgreSQL: older runs read as octile, their pairs unchanged."""

from __future__ import annotations

import pytest
import sqlalchemy as sa

from tests.store.old_schemas import columns_and_version, old_database, run_columns
from vinadv.errors import InputError
from vinadv.store import SCHEMA_VERSION, Store
from vinadv.store.schema import EFFORT_COLUMNS
from vinadv.testing.store import random_records


def _stored_moves(url: str) -> dict[int, object]:
    """`runs.moves` as the database holds it, by run id (plain SQL, not the store's reading)."""
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        rows = dict(conn.execute(sa.text("SELECT id, moves FROM runs")).all())
    engine.dispose()
    return rows


def test_each_run_keeps_its_movement_model(db_url):
    with Store.open(db_url) as store:
        runs = {moves: store.create_run(f"r-{moves}", moves=moves) for moves in ("octile", "moore", "news")}
        default = store.create_run("default")
        for moves, run in runs.items():
            assert store.run_info(run)["moves"] == moves == store.run_moves(run)
        assert store.run_moves(default) == "octile"
        assert {r["id"]: r["moves"] for r in store.list_runs()} == {
            **{r: m for m, r in runs.items()},
            default: "octile",
        }
        assert {r["id"]: r["moves"] for r in store.list_runs(with_counts=False)}[runs["news"]] == "news"
        with pytest.raises(InputError, match="moves 'hex': expected one of octile, moore, news"):
            store.create_run("bad", moves="hex")
    assert _stored_moves(db_url) == {**{r: m for m, r in runs.items()}, default: "octile"}


@pytest.mark.parametrize("version", [4, 5])
def test_an_older_database_is_upgraded_on_open_and_its_runs_read_as_octile(db_url, version):
    run_id = old_database(db_url, version, 20, lambda conn, quote: None)
    before = columns_and_version(db_url)
    assert before[1] == str(version) and "moves" not in run_columns(db_url)
    with Store.open(db_url, readonly=True) as store:  # read-only use: nothing changes, the run reads as octile
        info = store.run_info(run_id)
        old_pairs = store.read_pairs(run_id)
        assert info["moves"] == "octile" and [r["moves"] for r in store.list_runs()] == ["octile"]
    assert columns_and_version(db_url) == before and "moves" not in run_columns(db_url)
    with Store.open(db_url, create=False) as store:  # not upgraded: a new run would lose its model, so refused
        with pytest.raises(InputError, match="older schema version opened without create"):
            store.create_run("x", moves="moore")
    with Store.open(db_url) as store:  # upgraded on open
        assert store.run_moves(run_id) == "octile"
        assert store.read_pairs(run_id).equals(old_pairs)
        assert {k: v for k, v in store.run_info(run_id).items() if k != "moves"} == {
            k: v for k, v in info.items() if k != "moves"
        }
        fresh = store.create_run("new", moves="moore")
        store.write_pairs(fresh, random_records(4, size=7, seed=5))
    assert (
        columns_and_version(db_url) == (before[0] | {"edit", *EFFORT_COLUMNS}, SCHEMA_VERSION) and SCHEMA_VERSION == "8"
    )
    assert "moves" in run_columns(db_url)
    assert _stored_moves(db_url) == {run_id: None, fresh: "moore"}  # the old run keeps NULL: it reads as octile
