"""Databases as older vinadv versions left them, for the schema-upgrade tests."""

from __future__ import annotations

from collections.abc import Callable

import sqlalchemy as sa

from vinadv.store import Store
from vinadv.store.schema import EFFORT_COLUMNS, map_pairs
from vinadv.testing.store import random_records

Undo = Callable[[sa.Connection, Callable[[str], str]], None]


def drop_columns(conn: sa.Connection, table: str, columns: list[str]) -> None:
    """Drop `columns` of `table`: in one statement on MariaDB and PostgreSQL (each ALTER TABLE of MariaDB's costs
    about a tenth of a second however few columns it drops), one at a time on SQLite (one column per ALTER TABLE)."""
    quote = conn.dialect.identifier_preparer.quote
    drops = [f"DROP COLUMN {quote(column)}" for column in columns]
    for part in ([drops] if conn.dialect.name != "sqlite" else [[d] for d in drops]) if drops else []:
        conn.execute(sa.text(f"ALTER TABLE {quote(table)} {', '.join(part)}"))


def old_database(url: str, version: int, n_pairs: int, undo: Undo, name: str = "old") -> int:
    """Write one run `name` of `n_pairs` random 7x7 one-obstacle pairs with today's schema, then undo what the
    versions after `version` added (version 8: the search effort's columns and `robustness.run_name`; version 7:
    `map_pairs.edit`; version 6: the run's `moves`; version 5: the run
    name's binary collation on MariaDB; version 4: the table `measurements`) and `undo(conn, quote)` what the
    versions after `version` added before those (in one transaction), and stamp the schema `version`; the run's id."""
    with Store.open(url) as store:
        run_id = store.create_run(name)
        store.write_pairs(run_id, random_records(n_pairs, size=7, seed=3))
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    quote = engine.dialect.identifier_preparer.quote
    with engine.begin() as conn:
        # the step to 8's columns (the search effort; the robustness run's name below), the step to 7's column
        drop_columns(conn, "map_pairs", [*(EFFORT_COLUMNS if version < 8 else ()), *(["edit"] if version < 7 else [])])
        if version < 8:
            conn.execute(sa.text(f"ALTER TABLE robustness DROP COLUMN {quote('run_name')}"))
        if version < 6:
            conn.execute(sa.text(f"ALTER TABLE runs DROP COLUMN {quote('moves')}"))  # schema version 6's column
        if version < 5 and engine.dialect.name == "mysql":  # the database's own collation, as before version 5
            conn.execute(sa.text("ALTER TABLE runs MODIFY name VARCHAR(255) CHARACTER SET utf8mb4 NULL"))
        if version < 4:
            conn.execute(sa.text("DROP TABLE measurements"))  # schema version 4's table: no older version has it
        undo(conn, quote)
        stamp = f"UPDATE vinadv_meta SET value = '{int(version)}' WHERE {quote('key')} = 'schema_version'"
        conn.execute(sa.text(stamp))
    engine.dispose()
    return run_id


#: `map_pairs` columns that schema versions 2 and 3 added
LATER_COLUMNS = (
    "opt_cost_o",
    "opt_cost_a",
    "cost_o",
    "cost_a",
    "regret_o",
    "regret_a",
    "expert_label",
    "harm",
    "added_more",
)


def version_1_database(url: str, n_pairs: int, name: str = "old") -> int:
    """A database as vinadv with schema version 1 left it: one run `name` of `n_pairs` pairs, no harm columns (nor
    version 3's `added_more`, version 4's table, version 5's collation); the run's id."""

    def undo(conn, quote):
        harm_index = next(ix for ix in map_pairs.indexes if ix.name == "ix_map_pairs_run_harm")
        harm_index.drop(conn)  # version 1 had no index on harm (SQLite cannot drop an indexed column)
        drop_columns(conn, "map_pairs", list(LATER_COLUMNS))

    return old_database(url, 1, n_pairs, undo, name=name)


def run_name_collation(url: str) -> str | None:
    """The collation of `runs.name` on MariaDB (None elsewhere: SQLite and PostgreSQL compare bytes)."""
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    try:
        if engine.dialect.name != "mysql":
            return None
        with engine.connect() as conn:
            return conn.execute(
                sa.text(
                    "SELECT collation_name FROM information_schema.columns "
                    "WHERE table_schema = DATABASE() AND table_name = 'runs' AND column_name = 'name'"
                )
            ).scalar_one()
    finally:
        engine.dispose()


def columns_and_version(url: str) -> tuple[set, str]:
    """The `map_pairs` columns and the stored schema version."""
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        columns = {c["name"] for c in sa.inspect(conn).get_columns("map_pairs")}
        version = conn.execute(sa.text("SELECT value FROM vinadv_meta")).scalar()
    engine.dispose()
    return columns, version


def inspected(url: str, read: Callable[[sa.Inspector], object]):
    """`read(inspector)` of the database at `url`, on a connection of its own."""
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        found = read(sa.inspect(conn))
    engine.dispose()
    return found


def run_columns(url: str) -> set[str]:
    """The `runs` columns."""
    return inspected(url, lambda inspector: {c["name"] for c in inspector.get_columns("runs")})


def table_names(url: str) -> set[str]:
    return inspected(url, lambda inspector: set(inspector.get_table_names()))
