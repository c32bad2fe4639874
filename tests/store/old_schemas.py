"""Databases as older vinadv versions left them, for the schema-upgrade tests."""

from __future__ import annotations

from collections.abc import Callable

import sqlalchemy as sa

from vinadv.store import Store
from vinadv.testing.store import random_records

Undo = Callable[[sa.Connection, Callable[[str], str]], None]


def old_database(url: str, version: int, n_pairs: int, undo: Undo) -> int:
    """Write one run of `n_pairs` random 7x7 one-obstacle pairs with today's schema, then drop what the step to 7
    added (`map_pairs.edit`) and, for a `version` before 4, what version 4 added, and `undo(conn, quote)` what the
    versions after `version` added before that (in one transaction), and stamp the schema `version`; the run's id."""
    with Store.open(url) as store:
        run_id = store.create_run("old")
        store.write_pairs(run_id, random_records(n_pairs, size=7, seed=3))
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    quote = engine.dialect.identifier_preparer.quote
    with engine.begin() as conn:
        conn.execute(sa.text(f"ALTER TABLE map_pairs DROP COLUMN {quote('edit')}"))  # the step to 7's column
        if version < 4:
            conn.execute(sa.text("DROP TABLE measurements"))  # schema version 4's table: no older version has it
        undo(conn, quote)
        stamp = f"UPDATE vinadv_meta SET value = '{int(version)}' WHERE {quote('key')} = 'schema_version'"
        conn.execute(sa.text(stamp))
    engine.dispose()
    return run_id


def columns_and_version(url: str) -> tuple[set, str]:
    """The `map_pairs` columns and the stored schema version."""
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        columns = {c["name"] for c in sa.inspect(conn).get_columns("map_pairs")}
        version = conn.execute(sa.text("SELECT value FROM vinadv_meta")).scalar()
    engine.dispose()
    return columns, version


def table_names(url: str) -> set[str]:
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        names = set(sa.inspect(conn).get_table_names())
    engine.dispose()
    return names
