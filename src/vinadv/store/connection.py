"""The connection under a `Store`: database URLs, engines, schema checks and upgrades.

URLs: `--db` or env `VINADV_DB`, else the SQLite file `vinadv.db`. A plain file path means SQLite. MySQL/MariaDB
via PyMySQL (`mysql+pymysql://root@127.0.0.1:3306/test`), PostgreSQL via psycopg 3
(`postgresql+psycopg://postgres@127.0.0.1:5432/test`).

SQLite runs with `journal_mode=WAL, synchronous=NORMAL`: a crash of the process never corrupts or half-writes a
transaction; a power loss may lose the last committed ones. New SQLite files use 32 KiB pages.

Refusal: a database is checked before anything is written to it (WAL is switched on, tables are created only once
the check passed), so a refused database (foreign tables, another schema version, not a database) is left
byte-identical. `readonly=True` opens it without any write (SQLite `mode=ro`; a WAL file on a read-only file system
as `immutable`). A database error while reading or writing (full disk, read-only file, corrupted file, lost
server) is raised as `OutputError` (an InputError) naming the database in one line.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import os
import re
import sqlite3
import time
import urllib.parse
from collections.abc import Iterable, Iterator
from pathlib import Path

import sqlalchemy as sa
from sqlalchemy import exc as sa_exc

from vinadv.errors import InputError, OutputError, first_line
from vinadv.store.schema import (
    ADDITIVE_TABLES,
    SCHEMA_VERSION,
    TABLE_UPGRADE_COLUMNS,
    TABLES,
    UPGRADABLE_VERSIONS,
    UPGRADE_TABLES,
    UPGRADE_TABLES_SINCE,
    exact_collation,
    meta_table,
    metadata,
    runs,
)

DEFAULT_DB = "vinadv.db"
ENV_DB = "VINADV_DB"
_CONNECT_TIMEOUT_S = 5


def resolve_url(db: str | None = None) -> str:
    """The database URL: `db`, else env `VINADV_DB`, else `vinadv.db`; a plain path becomes `sqlite:///PATH`.
    An empty `db` (not None) is refused: it names no database, and the default is what leaving it out gives."""
    if db is not None and not db.strip():
        raise InputError(f"db: {db!r} names no database (give a file or a URL, or leave it out for the default)", "db")
    db = db or os.environ.get(ENV_DB) or DEFAULT_DB
    if "://" in db:
        return db
    return "sqlite:///" + str(Path(db).expanduser().resolve())


def safe_url(url: str | sa.URL) -> str:
    """The URL with its password hidden, for messages."""
    try:
        return sa.make_url(url).render_as_string(hide_password=True)
    except Exception:  # not parseable: shown as given, but for what could be a password (`user:PASSWORD@`)
        return re.sub(r"(://[^/@:]*:)[^@]*@", r"\1***@", str(url))


def utcnow() -> dt.datetime:
    """Now, as the store's timestamps are written: UTC without a time zone, whole seconds."""
    return dt.datetime.now(dt.UTC).replace(tzinfo=None, microsecond=0)


class Database:
    """What every part of a `Store` shares: the engine, the URL (password hidden) and what the schema check found.

    `absent_columns`: the `TABLE_UPGRADE_COLUMNS` an older database opened read-only lacks (they read as NULL).
    """

    def __init__(
        self, engine: sa.Engine, url: str, readonly: bool = False, *, absent_columns: frozenset[str] = frozenset()
    ) -> None:
        self.engine = engine
        self.url = safe_url(url)
        self.readonly = readonly
        self.sqlite = engine.dialect.name == "sqlite"  # rows in SQLite's native form (see `codec.encode_rows`)
        self.absent_columns = frozenset(absent_columns)

    def refuse_outdated(self, columns: Iterable[str] | None = None) -> None:
        """InputError before a write where the database is of an older schema version opened without create: it
        lacks one of `columns` (None: any `absent_columns` at all), which the write needs."""
        absent = self.absent_columns if columns is None else self.absent_columns & set(columns)
        if absent:
            raise InputError(
                f"database {self.url}: an older schema version opened without create; "
                "open it with create to upgrade it before writing"
            )

    def insert_row(self, table: sa.Table, **values) -> int:
        """Insert one row of `values` into `table`, in a transaction of its own; return its id."""
        with self.engine.begin() as conn:
            return int(conn.execute(table.insert().values(**values)).inserted_primary_key[0])

    def ensure_table(self, table: sa.Table) -> None:
        """Create `table` unless the database has it (an additive table, see `schema.ADDITIVE_TABLES`), under the
        `schema_lock`: two processes doing so at once create it once."""
        with self.engine.connect() as conn:
            if sa.inspect(conn).has_table(table.name):
                return
        with self.engine.connect() as conn, schema_lock(conn):
            table.create(conn, checkfirst=True)
            conn.commit()


def open_engine(url: str, *, create: bool = True, readonly: bool = False) -> tuple[sa.Engine, frozenset[str]]:
    """An engine on the database at `url` (a URL, see `resolve_url`) whose schema passed `check_schema`, and the
    columns it lacks (see `Database.absent_columns`). InputError, naming the database, when it cannot be used."""
    create = create and not readonly
    shown = safe_url(url)
    try:
        parsed = sa.make_url(url)
    except (sa_exc.ArgumentError, ValueError) as exc:  # ValueError: urllib's, say for 'postgresql://[::1'
        raise InputError(f"db: not a database URL: {shown} ({first_line(exc)})", "db") from None
    backend = parsed.get_backend_name()
    connect_args: dict = {}
    if backend == "sqlite" and create and in_memory(parsed):
        raise InputError(
            f"db: {url} is an in-memory SQLite database: what is stored there is gone when the command ends; "
            "give a file or a server URL",
            "db",
        )
    if backend == "sqlite":
        path = parsed.database
        if path and path != ":memory:" and not path.startswith("file:"):
            if not create and not Path(path).exists():
                raise InputError(f"database {shown}: no such file")
            if not Path(path).parent.exists():
                raise InputError(f"database {shown}: directory {Path(path).parent} does not exist")
    elif backend in ("mysql", "mariadb"):
        connect_args["connect_timeout"] = _CONNECT_TIMEOUT_S
        if parsed.query.get("charset") is None:
            parsed = parsed.update_query_dict({"charset": "utf8mb4"})
    elif backend == "postgresql":
        connect_args["connect_timeout"] = _CONNECT_TIMEOUT_S
    options: dict = {}
    if backend == "sqlite" and readonly and parsed.database not in (None, "", ":memory:"):
        options["creator"] = _sqlite_reader(parsed.database)
    try:
        engine = sa.create_engine(parsed, connect_args=connect_args, pool_pre_ping=backend != "sqlite", **options)
    except (sa_exc.ArgumentError, sa_exc.NoSuchModuleError, ImportError) as exc:
        raise InputError(f"database {shown}: cannot use this URL: {exc}") from None
    if backend == "sqlite":
        sa.event.listen(engine, "connect", _sqlite_pragmas)
    sa.event.listen(engine, "handle_error", _one_line_error(shown))
    try:
        absent = check_schema(engine, shown, create=create, readonly=readonly)
    except InputError:
        engine.dispose()
        raise
    except sa_exc.DBAPIError as exc:
        engine.dispose()
        raise InputError(f"cannot connect to database {shown}: {_error_line(exc)}") from None
    except UnicodeDecodeError:
        # a damaged SQLite file whose error text is no longer UTF-8: sqlite3 cannot even decode the message
        engine.dispose()
        raise InputError(f"database {shown}: a damaged file (SQLite's own error message is not text)") from None
    return engine, absent


def in_memory(url: sa.URL) -> bool:
    """Whether the SQLite URL `url` names an in-memory database (`sqlite://`, `sqlite:///:memory:`, a `file:` URI
    with `mode=memory` or `:memory:`), which lives only as long as its connections."""
    database = url.database or ""
    return database in ("", ":memory:") or database.startswith("file::memory:") or url.query.get("mode") == "memory"


def check_schema(engine: sa.Engine, shown: str, *, create: bool, readonly: bool) -> frozenset[str]:
    """Check the database's schema before anything is written to it; return the `UPGRADE_COLUMNS` it lacks (only
    when opened without `create`: with it, an older version is upgraded, see `upgrade`).

    An empty database gets the tables when `create` (else InputError); one with foreign tables of our names, of
    another schema version or with missing tables or columns is refused with InputError naming it (`shown`).

    The check reads the schema without the `schema_lock`, and on MariaDB, which commits each CREATE and ALTER on its
    own, it may find another process's tables half made (no schema version yet, a table missing). So on a server, a
    check that fails is made once more after waiting for the schema lock (`wait_for_schema`): whoever held it has
    finished, and only a database that still fails is refused. SQLite and PostgreSQL create and upgrade in one
    transaction, which no other process sees half done; waiting there is harmless (SQLite, whose lock is a write
    transaction, does not wait: a refused file is not even locked for writing)."""
    try:
        return _check_schema(engine, shown, create=create, readonly=readonly)
    except InputError:
        if engine.dialect.name == "sqlite":
            raise
        wait_for_schema(engine)
    return _check_schema(engine, shown, create=create, readonly=readonly)


def _check_schema(engine: sa.Engine, shown: str, *, create: bool, readonly: bool) -> frozenset[str]:
    """`check_schema` once."""
    sqlite = engine.dialect.name == "sqlite"
    with engine.connect() as conn:
        present = set(sa.inspect(conn).get_table_names())
    ours = {t.name for t in TABLES}
    if not present & ours:
        if not create:
            raise InputError(f"database {shown}: no vinadv tables (nothing stored there yet)")
        if create_tables(engine):
            return frozenset()
        with engine.connect() as conn:  # another process made them first: check them as any others
            present = set(sa.inspect(conn).get_table_names())
    if meta_table.name not in present:
        raise InputError(
            f"database {shown}: has tables {sorted(present & ours)} but no {meta_table.name} table; "
            "not a vinadv database (refusing to touch it)"
        )
    with engine.connect() as conn:
        version = conn.execute(
            sa.select(meta_table.c.value).where(meta_table.c.key == "schema_version")
        ).scalar_one_or_none()
        if version not in (SCHEMA_VERSION, *UPGRADABLE_VERSIONS):
            raise InputError(
                f"database {shown}: schema version {version!r}, this vinadv needs {SCHEMA_VERSION!r}; "
                "use another database (refusing to touch it)"
            )
        inspector = sa.inspect(conn)
        for table in TABLES:
            if table.name not in present and table in ADDITIVE_TABLES:
                continue  # created below (or, read-only, treated as empty)
            if (
                table.name not in present
                and version in UPGRADABLE_VERSIONS
                and table in UPGRADE_TABLES
                and int(version) < UPGRADE_TABLES_SINCE
            ):
                continue  # created by `upgrade` (or, read-only, treated as empty)
            if table.name not in present:
                raise InputError(f"database {shown}: wrong schema: table {table.name} is missing")
            have = {c["name"] for c in inspector.get_columns(table.name)}
            missing = {c.name for c in table.columns} - have
            if version in UPGRADABLE_VERSIONS:
                missing -= set(TABLE_UPGRADE_COLUMNS.get(table, ()))  # added by `upgrade`
            if missing:
                raise InputError(f"database {shown}: wrong schema: table {table.name} lacks columns {sorted(missing)}")
    absent: frozenset[str] = frozenset()
    missing_additive = [t for t in ADDITIVE_TABLES if t.name not in present]
    if version in UPGRADABLE_VERSIONS or (missing_additive and create):
        if create:
            upgrade(engine)
        else:  # read-only use: nothing changes, the columns it lacks read as NULL
            inspector = sa.inspect(engine)
            absent = frozenset(
                name
                for table, names in TABLE_UPGRADE_COLUMNS.items()
                if table.name in present
                for name in set(names) - {c["name"] for c in inspector.get_columns(table.name)}
            )
    if readonly:
        return absent
    if sqlite:
        with engine.connect() as conn:
            if conn.exec_driver_sql("PRAGMA journal_mode").scalar() != "wal":
                switch_to_wal(conn)  # a vinadv file written by another tool, or one being created meanwhile
    return absent


#: how long a switch to WAL waits for other connections to the file, as SQLite's busy timeout waits for locks
_WAL_WAIT_S = 30.0


def switch_to_wal(conn: sa.Connection) -> None:
    """`PRAGMA journal_mode=WAL` on the SQLite file behind `conn`. The switch needs the file to itself, and SQLite
    answers "database is locked" at once, without its busy timeout, while another connection holds its write lock
    (a second process opening a database while the first creates its tables): tried again until `_WAL_WAIT_S` has
    passed, then OutputError naming the database."""
    # on the driver's connection: the engine's `handle_error` turns a lock into OutputError, not to be tried again
    driver = conn.connection.driver_connection
    deadline = time.monotonic() + _WAL_WAIT_S
    while True:
        try:
            driver.execute("PRAGMA journal_mode=WAL").fetchall()
            return
        except sqlite3.OperationalError as exc:
            if "locked" not in str(exc) or time.monotonic() > deadline:
                raise OutputError(f"database {safe_url(conn.engine.url)}: {first_line(exc)}") from None
            time.sleep(0.02)


#: PostgreSQL's advisory lock key for changing the schema (advisory locks are per database): "vinadv" and 1
_PG_SCHEMA_LOCK = 0x76696E616476_0001
_LOCK_TIMEOUT_S = 30


@contextlib.contextmanager
def schema_lock(conn: sa.Connection) -> Iterator[None]:
    """Hold, for the block, the lock that one process at a time holds while it creates or upgrades the tables of
    the database behind `conn` (SQLite: an immediate transaction, the write lock; MariaDB: a named lock, held by
    the session across its DDL, which MariaDB commits statement by statement; PostgreSQL: an advisory lock until
    the transaction ends). The block commits what it did; the lock is waited for (`_LOCK_TIMEOUT_S` on MariaDB,
    SQLite's busy timeout), so the block reads the schema only once no other process is changing it."""
    dialect = conn.dialect.name
    lock_name = f"vinadv schema {conn.engine.url.database}"[:64]  # MariaDB's named locks are server-wide
    if dialect == "sqlite":
        conn.exec_driver_sql("BEGIN IMMEDIATE")  # the write lock, waited for (busy_timeout) before the check
    elif dialect == "postgresql":
        conn.execute(sa.text("SELECT pg_advisory_xact_lock(:key)"), {"key": _PG_SCHEMA_LOCK})
    else:
        got = conn.execute(
            sa.text("SELECT GET_LOCK(:name, :timeout)"), {"name": lock_name, "timeout": _LOCK_TIMEOUT_S}
        ).scalar()
        if got != 1:
            raise OutputError(f"database {safe_url(conn.engine.url)}: another process holds the schema lock")
    try:
        yield
    finally:
        if dialect not in ("sqlite", "postgresql"):
            conn.rollback()  # after a failure: the lock is released on a usable connection
            conn.execute(sa.text("SELECT RELEASE_LOCK(:name)"), {"name": lock_name})
            conn.commit()
        elif conn.in_transaction():
            conn.rollback()  # after a failure, or nothing to do: the lock goes with the transaction


def wait_for_schema(engine: sa.Engine) -> None:
    """Wait until no process is creating or upgrading the tables of the database behind `engine`: take the
    `schema_lock` and let it go at once, changing nothing."""
    with engine.connect() as conn, schema_lock(conn):
        pass


def create_tables(engine: sa.Engine) -> bool:
    """Create vinadv's tables and record the schema version in the database behind `engine`, which was found empty,
    under the `schema_lock`, all in one transaction where the backend allows. Returns False, having done nothing,
    when the database is no longer empty once the lock is held: another process made the tables first. Without the
    lock, two first uses of one database at once collided (a table created twice, or a schema version read before
    the other wrote it)."""
    sqlite = engine.dialect.name == "sqlite"
    with engine.connect() as conn:
        if sqlite:
            # page size first: it takes effect only before the first table is written, and not in WAL mode
            conn.exec_driver_sql("PRAGMA page_size=32768")
        with schema_lock(conn):
            if set(sa.inspect(conn).get_table_names()) & {t.name for t in TABLES}:
                return False
            metadata.create_all(conn)
            conn.execute(meta_table.insert(), [{"key": "schema_version", "value": SCHEMA_VERSION}])
            conn.commit()
        if sqlite:
            switch_to_wal(conn)  # outside the transaction, as SQLite requires
    return True


def upgrade(engine: sa.Engine) -> None:
    """Schema version 1 to 7 -> 8, under the `schema_lock` (two processes opening one old database at once upgrade
    it once; the second finds it done): add the `UPGRADE_COLUMNS` the database lacks (the harm columns, `added_more`,
    version 7's `edit`, version 8's search effort; all nullable, existing rows read them as NULL), the
    `RUN_UPGRADE_COLUMNS` (`runs.moves`, version 6: NULL reads as octile), the `ROBUSTNESS_UPGRADE_COLUMNS` of an
    existing `robustness` table (version 8's `run_name`), the `UPGRADE_TABLES` (`measurements`) and
    `ADDITIVE_TABLES` it lacks, give
    `runs.name` its exact collation on MySQL/MariaDB (version 5: the column is changed in place, its rows kept), then
    record the new version. Only what is missing is done, so an upgrade cut short (MariaDB commits each ALTER on its
    own) is finished by the next open, and the steps compose."""
    prep = engine.dialect.identifier_preparer
    with engine.connect() as conn, schema_lock(conn):
        version = conn.execute(
            sa.select(meta_table.c.value).where(meta_table.c.key == "schema_version")
        ).scalar_one_or_none()
        if version not in (SCHEMA_VERSION, *UPGRADABLE_VERSIONS):  # changed by another program meanwhile
            raise InputError(f"database {safe_url(engine.url)}: schema version {version!r} changed while opening it")
        inspector = sa.inspect(conn)
        present = set(inspector.get_table_names())
        for table, names in TABLE_UPGRADE_COLUMNS.items():
            if table.name not in present:
                continue  # an additive table made below, with every column
            have = {c["name"] for c in inspector.get_columns(table.name)}
            for name in names:
                if name not in have:
                    kind = table.c[name].type.compile(dialect=engine.dialect)
                    shown, column = prep.format_table(table), prep.quote(name)
                    conn.execute(sa.text(f"ALTER TABLE {shown} ADD COLUMN {column} {kind}"))
        for new_table in (*UPGRADE_TABLES, *ADDITIVE_TABLES):
            new_table.create(conn, checkfirst=True)
        _exact_run_names(conn)
        if version != SCHEMA_VERSION:
            conn.execute(meta_table.update().where(meta_table.c.key == "schema_version").values(value=SCHEMA_VERSION))
        conn.commit()


def _exact_run_names(conn: sa.Connection) -> None:
    """Schema version 5 on MySQL/MariaDB: `runs.name` in the `exact_collation` (in place, keeping every row and the
    name index), unless it has it already; nothing elsewhere."""
    collation = exact_collation(conn.dialect)
    if collation is None:
        return
    current = conn.execute(
        sa.text(
            "SELECT collation_name FROM information_schema.columns "
            "WHERE table_schema = DATABASE() AND table_name = :table AND column_name = 'name'"
        ),
        {"table": runs.name},
    ).scalar_one_or_none()
    if current != collation:
        prep = conn.dialect.identifier_preparer
        kind = runs.c.name.type.compile(dialect=conn.dialect)
        conn.execute(sa.text(f"ALTER TABLE {prep.format_table(runs)} MODIFY {prep.quote('name')} {kind} NULL"))


def _error_line(exc: BaseException) -> str:
    """The first line of a database error: the driver's own message (SQLAlchemy's wrapper adds the statement)."""
    return first_line(getattr(exc, "orig", None) or exc)


def _sqlite_pragmas(dbapi_conn, _record) -> None:
    """Per-connection settings only: nothing here writes to the file (a database is checked before any write).

    The file's own settings are made once, by `check_schema` when it creates the tables: 32 KiB pages (large
    pages hold many ~2 KB rows (maps + paths) each: 16 KiB gave a ~30% smaller file and faster inserts than 4 KiB,
    32 KiB another ~10% less CPU per inserted row than 16 KiB, 64 KiB no better) and journal_mode=WAL (readers
    don't block the writer; a crash leaves whole commits)."""
    cursor = dbapi_conn.cursor()
    cursor.execute("PRAGMA synchronous=NORMAL")  # safe in WAL against process crashes; fsync at checkpoints
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.execute("PRAGMA busy_timeout=30000")
    cursor.close()


def _sqlite_reader(path: str):
    """A connect function opening the SQLite file `path` read-only (`mode=ro`): never a write, no file created.

    A WAL database needs its `-shm` file, which SQLite cannot create in a read-only folder or file system; there
    the file is opened `immutable` (nobody can write it then)."""
    uri = "file:" + urllib.parse.quote(str(Path(path).expanduser().resolve())) + "?mode=ro"

    def connect() -> sqlite3.Connection:
        try:
            conn = sqlite3.connect(uri, uri=True, check_same_thread=False)
            conn.execute("SELECT count(*) FROM sqlite_master").fetchone()
            return conn
        except sqlite3.OperationalError:
            if os.access(Path(path).parent, os.W_OK):
                raise
        return sqlite3.connect(uri + "&immutable=1", uri=True, check_same_thread=False)

    return connect


#: DBAPI errors that come from the database's state or its file (full disk, read-only or corrupted file, lost
#: server, lock timeout), not from vinadv's statements: raised as one-line `OutputError`s naming the database
_FAULTS = (sa_exc.OperationalError, sa_exc.InternalError)


class DeadlockError(OutputError):
    """The server rolled a transaction back to break a lock cycle with another writer (MySQL/MariaDB error 1213,
    PostgreSQL SQLSTATE 40P01): nothing of it is stored, and it may be run again."""


def is_deadlock(exc: BaseException) -> bool:
    """Whether `exc` (a SQLAlchemy error) is the server breaking a deadlock (`DeadlockError`)."""
    orig = getattr(exc, "orig", None)
    if orig is None:
        return False
    code = orig.args[0] if getattr(orig, "args", None) else None
    return code == 1213 or getattr(orig, "sqlstate", None) == "40P01"


def _one_line_error(shown: str):
    """A `handle_error` listener: a fault of the database (see `_FAULTS`) becomes an `OutputError` naming it,
    without SQLAlchemy's multi-line text (the statement and its parameters: maps and paths)."""

    def handle(context) -> Exception | None:
        exc = context.sqlalchemy_exception
        if context.connection is None or not (isinstance(exc, _FAULTS) or type(exc) is sa_exc.DatabaseError):
            return None  # connect errors: `open_engine` words them; integrity/programming errors are bugs
        error = DeadlockError if is_deadlock(exc) else OutputError
        return error(f"database {shown}: {_error_line(exc)}")

    return handle
