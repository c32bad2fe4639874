"""`Store`: open a vinadv database by URL, record runs, bulk-write and read identified map pairs.

URLs: `--db` or env `VINADV_DB`, else the SQLite file `vinadv.db`. A plain file path means SQLite. MySQL/MariaDB
via PyMySQL (`mysql+pymysql://root@127.0.0.1:3306/test`), PostgreSQL via psycopg 3
(`postgresql+psycopg://postgres@127.0.0.1:5432/test`).

Writes: `write_pairs` inserts in batches, each batch in its own transaction (all-or-nothing; inside it, rows are
encoded and inserted a chunk at a time, into SQLite by multi-row INSERT statements). With
`(run_id, pair_index)` unique and stored indices skipped on resume, a killed run that is resumed ends with
every pair exactly once. SQLite runs with `journal_mode=WAL, synchronous=NORMAL`: a crash of the process
never corrupts or half-writes a batch; a power loss may lose the last committed batches (they are then
written again on resume). New SQLite files use 32 KiB pages.

Refusal: a database is checked before anything is written to it (WAL is switched on, tables are created only once
the check passed), so a refused database (foreign tables, another schema version, not a database) is left
byte-identical. `readonly=True` opens it without any write (SQLite `mode=ro`; a WAL file on a read-only file system
as `immutable`). A database error while reading or writing (full disk, read-only file, corrupted file, lost
server) is raised as `OutputError` (an InputError) naming the database in one line.
"""

from __future__ import annotations

import datetime as dt
import os
import sqlite3
import urllib.parse
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np
import sqlalchemy as sa
from sqlalchemy import exc as sa_exc

from vinadv import __version__
from vinadv.errors import InputError, OutputError
from vinadv.grid.paths import PackedPaths
from vinadv.store import codec
from vinadv.store.records import PairRecords
from vinadv.store.schema import (
    ADDITIVE_TABLES,
    HARM_COLUMNS,
    HARM_FLOAT_COLUMNS,
    LABELS,
    MORE_ADDED_COLUMN,
    SCHEMA_VERSION,
    TABLES,
    UPGRADABLE_VERSIONS,
    UPGRADE_COLUMNS,
    annotations,
    evaluations,
    map_pairs,
    meta_table,
    metadata,
    robustness,
    runs,
)
from vinadv.vocabulary import FORK_OR_DETOUR

DEFAULT_DB = "vinadv.db"
ENV_DB = "VINADV_DB"
#: rows per INSERT transaction; large enough to amortise the round trip, small enough to keep memory flat.
DEFAULT_BATCH = 20_000
#: rows encoded at a time while SQLite inserts a batch (a few MB of text: stays in the CPU cache)
_ROW_CHUNK = 2048
#: rows per SQLite INSERT statement (at most what SQLite's parameter limit allows), see `Store._insert_sqlite`
_SQLITE_ROWS_PER_STATEMENT = 256
_CONNECT_TIMEOUT_S = 5
#: cost units per grouping step of `Store.regret_changes` (1e-6: far below the gap between two distinct costs)
_MICRO = 1_000_000

_PAIR_TEXT_COLUMNS = ("map_o", "map_a", "path_o", "path_a", "start", "goal", "added_obstacle")


def resolve_url(db: str | None = None) -> str:
    """The database URL: `db`, else env `VINADV_DB`, else `vinadv.db`; a plain path becomes `sqlite:///PATH`."""
    db = db or os.environ.get(ENV_DB) or DEFAULT_DB
    if "://" in db:
        return db
    return "sqlite:///" + str(Path(db).expanduser().resolve())


def safe_url(url: str | sa.URL) -> str:
    """The URL with its password hidden, for messages."""
    try:
        return sa.make_url(url).render_as_string(hide_password=True)
    except Exception:
        return "<unparseable database URL>"


def _utcnow() -> dt.datetime:
    return dt.datetime.now(dt.UTC).replace(tzinfo=None, microsecond=0)


def _first_line(exc: BaseException) -> str:
    orig = getattr(exc, "orig", None) or exc
    return str(orig).strip().splitlines()[0] if str(orig).strip() else type(orig).__name__


class Store:
    """A vinadv database. Use `Store.open(url)`; close with `.close()` or a `with` block.

    `create=True` creates the tables in an empty database; a database that holds other tables with the same
    names, or another schema version, is refused with `InputError` (nothing is changed).
    """

    def __init__(self, engine: sa.Engine, url: str, readonly: bool = False) -> None:
        self.engine = engine
        self.url = safe_url(url)
        self.readonly = readonly
        self._insert_sql = _driver_insert_sql(engine.dialect)
        self._sqlite = engine.dialect.name == "sqlite"  # rows in SQLite's native form (see `encode_rows`)
        self._multi_insert: tuple[int, str] | None = None  # (rows per statement, SQL), see `_insert_sqlite`
        # the `UPGRADE_COLUMNS` an older database opened read-only lacks (they read as NULL)
        self._absent_columns: frozenset[str] = frozenset()

    # ------------------------------------------------------------------------------------------ opening

    @classmethod
    def open(cls, url: str | None = None, *, create: bool = True, readonly: bool = False) -> Store:
        """Open (and with `create`, initialise) the database at `url` (see `resolve_url`).

        `readonly`: never write (implies `create=False`); a SQLite file is opened with `mode=ro`, so a file the
        user may only read can still be exported, reported and browsed.
        """
        create = create and not readonly
        url = resolve_url(url)
        shown = safe_url(url)
        try:
            parsed = sa.make_url(url)
        except sa_exc.ArgumentError as exc:
            raise InputError(f"db: not a database URL: {shown} ({exc})", "db") from None
        backend = parsed.get_backend_name()
        connect_args: dict = {}
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
        store = cls(engine, url, readonly=readonly)
        try:
            store._check_schema(create)
        except InputError:
            engine.dispose()
            raise
        except sa_exc.DBAPIError as exc:
            engine.dispose()
            raise InputError(f"cannot connect to database {shown}: {_first_line(exc)}") from None
        except UnicodeDecodeError:
            # a damaged SQLite file whose error text is no longer UTF-8: sqlite3 cannot even decode the message
            engine.dispose()
            raise InputError(f"database {shown}: a damaged file (SQLite's own error message is not text)") from None
        return store

    def _check_schema(self, create: bool) -> None:
        with self.engine.connect() as conn:
            present = set(sa.inspect(conn).get_table_names())
        ours = {t.name for t in TABLES}
        if not present & ours:
            if not create:
                raise InputError(f"database {self.url}: no vinadv tables (nothing stored there yet)")
            with self.engine.begin() as conn:
                if self._sqlite:
                    # page size first: it takes effect only before the first table is written, and not in WAL mode
                    conn.exec_driver_sql("PRAGMA page_size=32768")
                    conn.exec_driver_sql("PRAGMA journal_mode=WAL")
                metadata.create_all(conn)
                conn.execute(meta_table.insert(), [{"key": "schema_version", "value": SCHEMA_VERSION}])
            return
        if meta_table.name not in present:
            raise InputError(
                f"database {self.url}: has tables {sorted(present & ours)} but no {meta_table.name} table; "
                "not a vinadv database (refusing to touch it)"
            )
        with self.engine.connect() as conn:
            version = conn.execute(
                sa.select(meta_table.c.value).where(meta_table.c.key == "schema_version")
            ).scalar_one_or_none()
            if version not in (SCHEMA_VERSION, *UPGRADABLE_VERSIONS):
                raise InputError(
                    f"database {self.url}: schema version {version!r}, this vinadv needs {SCHEMA_VERSION!r}; "
                    "use another database (refusing to touch it)"
                )
            inspector = sa.inspect(conn)
            for table in TABLES:
                if table.name not in present and table in ADDITIVE_TABLES:
                    continue  # created below (or, read-only, treated as empty)
                if table.name not in present:
                    raise InputError(f"database {self.url}: wrong schema: table {table.name} is missing")
                have = {c["name"] for c in inspector.get_columns(table.name)}
                missing = {c.name for c in table.columns} - have
                if version in UPGRADABLE_VERSIONS and table is map_pairs:
                    missing -= set(UPGRADE_COLUMNS)  # added by `_upgrade`
                if missing:
                    raise InputError(
                        f"database {self.url}: wrong schema: table {table.name} lacks columns {sorted(missing)}"
                    )
        if version in UPGRADABLE_VERSIONS:
            if create:
                self._upgrade()
            else:  # read-only use: nothing changes, the columns it lacks read as NULL
                self._absent_columns = frozenset(UPGRADE_COLUMNS) - {
                    c["name"] for c in sa.inspect(self.engine).get_columns(map_pairs.name)
                }
        if self.readonly:
            return
        with self.engine.connect() as conn:
            if self._sqlite and conn.exec_driver_sql("PRAGMA journal_mode").scalar() != "wal":
                conn.exec_driver_sql("PRAGMA journal_mode=WAL")  # a vinadv file written by another tool
        missing_additive = [t for t in ADDITIVE_TABLES if t.name not in present]
        if missing_additive and create:
            # an older version-1 database: add the new tables (nothing existing changes)
            with self.engine.begin() as conn:
                for table in missing_additive:
                    table.create(conn, checkfirst=True)

    def _upgrade(self) -> None:
        """Schema version 1 or 2 -> 3: add the `UPGRADE_COLUMNS` the database lacks (the harm columns, `added_more`;
        all nullable, existing rows read them as NULL), then record the new version. Only the missing columns are
        added, so an upgrade cut short (MySQL commits each ALTER on its own) is finished by the next open."""
        prep = self.engine.dialect.identifier_preparer
        with self.engine.begin() as conn:
            have = {c["name"] for c in sa.inspect(conn).get_columns(map_pairs.name)}
            for name in UPGRADE_COLUMNS:
                if name not in have:
                    kind = map_pairs.c[name].type.compile(dialect=self.engine.dialect)
                    table, column = prep.format_table(map_pairs), prep.quote(name)
                    conn.execute(sa.text(f"ALTER TABLE {table} ADD COLUMN {column} {kind}"))
            conn.execute(meta_table.update().where(meta_table.c.key == "schema_version").values(value=SCHEMA_VERSION))

    def close(self) -> None:
        self.engine.dispose()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # --------------------------------------------------------------------------------------------- runs

    def create_run(
        self,
        name: str | None = None,
        *,
        config: dict | None = None,
        seed: int | None = None,
        weights_checksum: str | None = None,
        attack: str | None = None,
        classifier: str | None = None,
        version: str = __version__,
        status: str = "running",
    ) -> int:
        """Insert a run and return its id. A `name` is unique in a database (`--resume` finds a run by it) and
        not a number (`resolve_run` reads a number as a run id): InputError otherwise."""
        if name is not None:
            if not name.strip() or name.strip().isdigit():
                raise InputError(
                    f"name: {name!r} cannot be a run name (a name needs a letter; numbers are run ids)", "name"
                )
            found = self.find_run(name)
            if found is not None:
                raise InputError(
                    f"name: run {found} in database {self.url} is already called {name!r}; "
                    "continue it with resume, or choose another name",
                    "name",
                    "resume",
                    "name",
                )
        with self.engine.begin() as conn:
            result = conn.execute(
                runs.insert().values(
                    name=name,
                    created=_utcnow(),
                    config=config,
                    seed=None if seed is None else int(seed),
                    weights_checksum=weights_checksum,
                    attack=attack,
                    classifier=classifier,
                    version=version,
                    timings=None,
                    status=status,
                )
            )
            return int(result.inserted_primary_key[0])

    def find_run(self, name: str) -> int | None:
        """The id of the latest run called `name` (for `--resume`), or None."""
        with self.engine.connect() as conn:
            found = conn.execute(
                sa.select(runs.c.id).where(runs.c.name == name).order_by(runs.c.id.desc()).limit(1)
            ).scalar_one_or_none()
        return None if found is None else int(found)

    def resolve_run(self, ref: str | int, param: str = "run_id") -> int:
        """The id of the run `ref` names: the one rule for every run reference. A number is a run id (a run name is
        never a number, see `create_run`), anything else a run name (its latest run). InputError (naming the
        parameter `param`) when there is no such run."""
        text = str(ref).strip()
        if text.isdigit():
            found = None
            if int(text) < 2**63:  # a larger number is no id (and no SQL integer)
                with self.engine.connect() as conn:
                    found = conn.execute(sa.select(runs.c.id).where(runs.c.id == int(text))).scalar_one_or_none()
            if found is None:
                raise InputError(f"{param}: no run {text} in database {self.url}", param)
            return int(text)
        found = self.find_run(text) if text else None
        if found is None:
            raise InputError(f"{param}: no run named {text!r} in database {self.url} (give a run id or name)", param)
        return found

    def shards_done(self, run_id: int) -> int:
        """How many shards of the run are completely stored, from shard 0 on (0 when none recorded)."""
        with self.engine.connect() as conn:
            value = conn.execute(
                sa.select(meta_table.c.value).where(meta_table.c.key == _shards_key(run_id))
            ).scalar_one_or_none()
        return int(value) if value is not None else 0

    def set_shards_done(self, run_id: int, shards: int) -> None:
        """Record that shards `0 .. shards-1` of the run are completely stored (`--resume` skips them)."""
        key = _shards_key(run_id)
        with self.engine.begin() as conn:
            updated = conn.execute(
                meta_table.update().where(meta_table.c.key == key).values(value=str(int(shards)))
            ).rowcount
            if not updated:
                conn.execute(meta_table.insert().values(key=key, value=str(int(shards))))

    def run_info(self, run_id: int) -> dict:
        """The run's row as a dict; `InputError` when there is no such run."""
        with self.engine.connect() as conn:
            row = conn.execute(sa.select(runs).where(runs.c.id == int(run_id))).mappings().one_or_none()
        if row is None:
            raise InputError(f"run_id: no run {run_id} in database {self.url}", "run_id")
        return dict(row)

    def list_runs(self, with_counts: bool = True) -> list[dict]:
        """All runs, oldest first, each with its stored pair count (`n_pairs`) unless `with_counts` is False
        (counting reads every pair's index entry: ~0.1 s per million pairs on SQLite)."""
        if not with_counts:
            with self.engine.connect() as conn:
                return [dict(r) for r in conn.execute(sa.select(runs).order_by(runs.c.id)).mappings()]
        counts = sa.select(map_pairs.c.run_id, sa.func.count().label("n_pairs")).group_by(map_pairs.c.run_id).subquery()
        query = (
            sa.select(runs, sa.func.coalesce(counts.c.n_pairs, 0).label("n_pairs"))
            .select_from(runs.outerjoin(counts, counts.c.run_id == runs.c.id))
            .order_by(runs.c.id)
        )
        with self.engine.connect() as conn:
            return [dict(r) for r in conn.execute(query).mappings()]

    def finish_run(self, run_id: int, timings: dict | None = None, status: str = "done") -> None:
        """Record the run's timings (seconds per stage) and final status."""
        with self.engine.begin() as conn:
            updated = conn.execute(
                runs.update().where(runs.c.id == int(run_id)).values(timings=timings, status=status)
            ).rowcount
        if updated != 1:
            raise InputError(f"run_id: no run {run_id} in database {self.url}", "run_id")

    # -------------------------------------------------------------------------------------------- pairs

    def stored_indices(self, run_id: int, lo: int | None = None, hi: int | None = None) -> np.ndarray:
        """Sorted pair indices already stored for the run, int64 (k,); only those in `[lo, hi]` when given."""
        query = sa.select(map_pairs.c.pair_index).where(map_pairs.c.run_id == int(run_id))
        if lo is not None:
            query = query.where(map_pairs.c.pair_index >= int(lo))
        if hi is not None:
            query = query.where(map_pairs.c.pair_index <= int(hi))
        with self.engine.connect() as conn:
            rows = conn.execute(query).scalars().all()
        return np.sort(np.asarray(rows, dtype=np.int64))

    def write_pairs(
        self,
        run_id: int,
        records: PairRecords,
        *,
        batch_size: int = DEFAULT_BATCH,
        skip_stored: bool = True,
        progress=None,
    ) -> int:
        """Insert `records` for the run, `batch_size` rows per transaction; return how many were written.

        With `skip_stored` (the resume path) pairs whose index is already stored are skipped. A batch is
        all-or-nothing: a crash leaves whole batches only. `progress(n_rows)` is called after each batch.
        """
        run_id = int(run_id)
        if self._absent_columns:
            raise InputError(
                f"database {self.url}: an older schema version opened without create; "
                "open it with create to upgrade it before writing"
            )
        # strictly increasing, as jobs write them, means no duplicates: the sort of np.unique only otherwise
        increasing = bool((np.diff(records.pair_index) > 0).all())
        if not increasing and len(np.unique(records.pair_index)) != len(records):
            raise InputError("write_pairs: pair_index has duplicates")
        if skip_stored and len(records):
            # only the records' own index range: a resumed shard must not read the whole run
            stored = self.stored_indices(run_id, records.pair_index.min(), records.pair_index.max())
            if len(stored):
                records = records.take(~np.isin(records.pair_index, stored))
        written = 0
        for lo in range(0, len(records), batch_size):
            hi = min(lo + batch_size, len(records))
            with self.engine.begin() as conn:
                # encoded and inserted a chunk at a time, inside the batch's one transaction: the batch's text
                # never exists all at once, and each chunk is still in the CPU cache when the driver copies it
                for start in range(lo, hi, _ROW_CHUNK):
                    stop = min(start + _ROW_CHUNK, hi)
                    if self._sqlite:
                        self._insert_sqlite(conn, run_id, records, start, stop)
                    elif self._insert_sql is not None:
                        # straight to the driver's executemany: SQLAlchemy's per-row parameter processing would
                        # cost more than encoding and inserting together (PyMySQL turns it into multi-row INSERTs)
                        conn.exec_driver_sql(self._insert_sql, encode_rows(run_id, records, start, stop))
                    else:
                        rows = encode_rows(run_id, records, start, stop)
                        conn.execute(map_pairs.insert(), [dict(zip(INSERT_COLUMNS, row)) for row in rows])
            written += hi - lo
            if progress is not None:
                progress(hi - lo)
        return written

    def _insert_sqlite(self, conn: sa.Connection, run_id: int, records: PairRecords, lo: int, hi: int) -> None:
        """Insert records `lo:hi` into SQLite, mostly `_SQLITE_ROWS_PER_STATEMENT` rows per INSERT statement.

        One statement of k rows costs SQLite and the sqlite3 module ~1 us less per row than k one-row statements
        (one statement step instead of k, and a tuple of parameters per statement, not per row).
        """
        if self._multi_insert is None:
            limit = getattr(conn.connection.driver_connection, "getlimit", None)
            max_params = limit(sqlite3.SQLITE_LIMIT_VARIABLE_NUMBER) if limit else 999  # 999: SQLite before 3.32
            k = max(1, min(_SQLITE_ROWS_PER_STATEMENT, max_params // len(INSERT_COLUMNS)))
            self._multi_insert = (k, _driver_insert_sql(self.engine.dialect, rows=k))
        k, sql = self._multi_insert
        columns = _encode_columns(run_id, records, lo, hi, sqlite=True)
        width, whole = len(INSERT_COLUMNS), (hi - lo) // k * k
        if whole:
            # interleave the columns into one flat parameter list (C-level slice assignments), then cut it
            flat: list = [None] * (width * whole)
            for j, column in enumerate(columns):
                flat[j::width] = column if whole == hi - lo else column[:whole]
            step = width * k
            conn.exec_driver_sql(sql, [tuple(flat[i : i + step]) for i in range(0, len(flat), step)])
        if whole < hi - lo:
            conn.exec_driver_sql(self._insert_sql, list(zip(*(column[whole:] for column in columns))))

    def read_pairs(
        self,
        run_id: int,
        *,
        successful_only: bool = False,
        labels: Sequence[str] | None = None,
        pair_indices: np.ndarray | None = None,
    ) -> PairRecords:
        """The run's stored pairs, ordered by pair index, decoded back into arrays."""
        query = self._pairs_query(run_id, successful_only=successful_only, labels=labels, pair_indices=pair_indices)
        with self.engine.connect() as conn:
            rows = conn.execute(query).all()
        return decode_rows(rows)

    def iter_pair_rows(
        self, run_id: int, *, successful_only: bool = False, chunk: int = 10_000
    ) -> Iterator[list[dict]]:
        """The run's stored rows as text, ordered by pair index, in chunks of dicts (streamed; for export)."""
        query = self._pairs_query(run_id, successful_only=successful_only)
        with self.engine.connect() as conn:
            result = conn.execution_options(stream_results=True, yield_per=chunk).execute(query)
            for part in result.mappings().partitions(chunk):
                yield [dict(r) for r in part]

    def _pairs_query(self, run_id, *, successful_only=False, labels=None, pair_indices=None) -> sa.Select:
        query = sa.select(
            *[sa.null().label(name) if name in self._absent_columns else map_pairs.c[name] for name in PAIR_COLUMNS]
        ).where(map_pairs.c.run_id == int(run_id))
        if successful_only:
            query = query.where(map_pairs.c.attack == sa.true())
        if labels is not None:
            query = query.where(map_pairs.c.label.in_(list(labels)))
        if pair_indices is not None:
            query = query.where(map_pairs.c.pair_index.in_([int(i) for i in np.asarray(pair_indices).ravel()]))
        return query.order_by(map_pairs.c.pair_index)

    def count_pairs(self, run_id: int) -> int:
        with self.engine.connect() as conn:
            return int(
                conn.execute(
                    sa.select(sa.func.count()).select_from(map_pairs).where(map_pairs.c.run_id == int(run_id))
                ).scalar_one()
            )

    def _group_counts(self, run_id: int, *keys: sa.ColumnElement) -> list[sa.Row]:
        """The run's stored pairs counted per value of the `map_pairs` columns `keys`, in one GROUP BY: rows
        `(*values, count)`, one per combination present."""
        with self.engine.connect() as conn:
            return conn.execute(
                sa.select(*keys, sa.func.count()).where(map_pairs.c.run_id == int(run_id)).group_by(*keys)
            ).all()

    def label_counts(self, run_id: int) -> dict[str, int]:
        """Stored pairs per label, every label present (0 where none), in DESIGN.md order."""
        counts = {label: 0 for label in LABELS}
        counts.update({label: int(k) for label, k in self._group_counts(run_id, map_pairs.c.label)})
        return counts

    def attack_counts(self, run_id: int) -> dict[bool, int]:
        """Stored pairs per attack outcome: {True: successful, False: not}."""
        counts = {True: 0, False: 0}
        counts.update({bool(a): int(k) for a, k in self._group_counts(run_id, map_pairs.c.attack)})
        return counts

    # -------------------------------------------------------------------------------------- annotations

    def add_annotations(self, run_id: int, pair_indices, labels, annotator: str) -> int:
        """Store human labels for stored pairs (one row per (pair, label) given); return how many."""
        pair_indices = np.asarray(pair_indices, dtype=np.int64).reshape(-1)
        labels = np.broadcast_to(np.asarray(labels, dtype=object), pair_indices.shape)
        bad = ~np.isin(labels, LABELS)
        if bad.any():
            raise InputError(f"annotation label {labels[bad][0]!r} is not one of {'|'.join(LABELS)}")
        if not annotator:
            raise InputError("annotator: must be a non-empty name")
        if len(pair_indices) == 0:
            return 0
        now = _utcnow()
        rows = [
            {"run_id": int(run_id), "pair_index": int(i), "label": str(lab), "annotator": annotator, "created": now}
            for i, lab in zip(pair_indices.tolist(), labels.tolist())
        ]
        with self.engine.begin() as conn:
            conn.execute(annotations.insert(), rows)
        return len(rows)

    def read_annotations(self, run_id: int, pair_indices=None) -> list[dict]:
        """The run's annotations (of `pair_indices` only, if given), oldest first: dicts with id, pair_index,
        label, annotator, created."""
        query = (
            sa.select(
                annotations.c.id,
                annotations.c.pair_index,
                annotations.c.label,
                annotations.c.annotator,
                annotations.c.created,
            )
            .where(annotations.c.run_id == int(run_id))
            .order_by(annotations.c.id)
        )
        if pair_indices is not None:
            query = query.where(annotations.c.pair_index.in_([int(i) for i in np.asarray(pair_indices).ravel()]))
        with self.engine.connect() as conn:
            rows = conn.execute(query).mappings().all()
        return [dict(r) for r in rows]

    # -------------------------------------------------------------------------------------- evaluations

    def add_evaluations(self, run_id: int, rows: Sequence[dict]) -> int:
        """Store classifier evaluations of a run (`vinadv evaluate`), all in one transaction; return how many.

        Each row: classifier, setting, training ('balanced'|'imbalanced'), train_fraction, train_size,
        test_size, seed, metrics (JSON dict), curves (JSON dict or None), batch (id shared by one call).
        """
        self.run_info(run_id)  # InputError for an unknown run
        if not rows:
            return 0
        self._ensure_table(evaluations)
        now = _utcnow()
        keys = (
            "batch",
            "classifier",
            "setting",
            "training",
            "train_fraction",
            "train_size",
            "test_size",
            "seed",
            "metrics",
            "curves",
        )
        values = [{"run_id": int(run_id), "created": now, **{k: row.get(k) for k in keys}} for row in rows]
        with self.engine.begin() as conn:
            conn.execute(evaluations.insert(), values)
        return len(values)

    def read_evaluations(self, run_id: int) -> list[dict]:
        """The run's stored evaluations, oldest first (`[]` when none, or when the table does not exist yet)."""
        with self.engine.connect() as conn:
            if not sa.inspect(conn).has_table(evaluations.name):
                return []
            rows = (
                conn.execute(
                    sa.select(evaluations).where(evaluations.c.run_id == int(run_id)).order_by(evaluations.c.id)
                )
                .mappings()
                .all()
            )
        return [dict(r) for r in rows]

    # ------------------------------------------------------------------------------------- robustness

    def add_robustness(
        self, planner: str, weights_checksum: str | None, settings: dict, result: dict, version: str = __version__
    ) -> int:
        """Store one robustness benchmark (`vinadv robustness`): the planner's name and weights checksum, the
        benchmark's settings and its figures (`vinadv.robustness.RobustnessResult.to_dict()`), JSON; return its id."""
        self._ensure_table(robustness)
        with self.engine.begin() as conn:
            row = conn.execute(
                robustness.insert().values(
                    created=_utcnow(),
                    planner=str(planner),
                    weights_checksum=weights_checksum,
                    settings=settings,
                    result=result,
                    version=version,
                )
            )
            return int(row.inserted_primary_key[0])

    def read_robustness(self, ids: Sequence[int] | None = None) -> list[dict]:
        """The stored robustness benchmarks (of `ids` only, if given), oldest first: dicts of the table's columns
        (`[]` when none, or when the table does not exist yet)."""
        with self.engine.connect() as conn:
            if not sa.inspect(conn).has_table(robustness.name):
                return []
            query = sa.select(robustness).order_by(robustness.c.id)
            if ids is not None:
                query = query.where(robustness.c.id.in_([int(i) for i in ids]))
            return [dict(r) for r in conn.execute(query).mappings().all()]

    def _ensure_table(self, table: sa.Table) -> None:
        with self.engine.begin() as conn:
            table.create(conn, checkfirst=True)

    # ----------------------------------------------------------------------------- paging (the viewer)

    def ensure_indexes(self) -> list[str]:
        """Create the indexes of the current schema that the database lacks (one made by an older vinadv);
        return their names. Paging stays correct without them, only slower. An index on a column the database
        does not have yet (the harm columns of a version-1 database opened without `create`) is left for later."""
        created = []
        with self.engine.begin() as conn:
            present = {ix["name"] for ix in sa.inspect(conn).get_indexes(map_pairs.name)}
            for index in sorted(map_pairs.indexes, key=lambda ix: ix.name):
                if {c.name for c in index.columns} & self._absent_columns:
                    continue
                if index.name not in present:
                    index.create(conn)
                    created.append(index.name)
        return created

    def page_pairs(
        self,
        run_id: int,
        *,
        label: str | None = None,
        attack: bool | None = None,
        label_source: str | None = None,
        harm: str | None = None,
        after: int | None = None,
        before: int | None = None,
        limit: int = 50,
    ) -> list[dict]:
        """One page of the run's pairs, without maps and paths, ordered by pair index (keyset paging).

        `after`/`before`: only pairs with a larger/smaller index (`before` returns the `limit` pairs just before
        it, still in ascending order). Filters are exact matches. Each dict: pair_index, label, attack,
        label_source, score, dh, dv, term_o, term_a, added_obstacle, harm, regret_o, regret_a. With the
        (run_id, <filter>, pair_index) indexes every page is one index range read, however deep.
        """
        c = map_pairs.c
        harm_columns = [
            sa.null().label(name) if name in self._absent_columns else c[name]
            for name in ("harm", "regret_o", "regret_a")
        ]
        query = sa.select(
            c.pair_index,
            c.label,
            c.attack,
            c.label_source,
            c.score,
            c.dh,
            c.dv,
            c.term_o,
            c.term_a,
            c.added_obstacle,
            *harm_columns,
        ).where(c.run_id == int(run_id))
        if label is not None:
            query = query.where(c.label == label)
        if attack is not None:
            query = query.where(c.attack == (sa.true() if attack else sa.false()))
        if label_source is not None:
            query = query.where(c.label_source == label_source)
        if harm is not None:
            query = query.where(sa.false() if "harm" in self._absent_columns else c.harm == harm)
        if after is not None:
            query = query.where(c.pair_index > int(after))
        if before is not None:
            query = query.where(c.pair_index < int(before))
            query = query.order_by(c.pair_index.desc())
        else:
            query = query.order_by(c.pair_index)
        with self.engine.connect() as conn:
            rows = [dict(r) for r in conn.execute(query.limit(int(limit))).mappings()]
        for row in rows:
            row["attack"] = bool(row["attack"])
        return rows[::-1] if before is not None else rows

    def label_counts_by_run(self) -> dict[int, dict[str, int]]:
        """Stored pairs per label of every run, in one query: {run_id: {label: n}} (every label present)."""
        with self.engine.connect() as conn:
            rows = conn.execute(
                sa.select(map_pairs.c.run_id, map_pairs.c.label, sa.func.count()).group_by(
                    map_pairs.c.run_id, map_pairs.c.label
                )
            ).all()
        counts: dict[int, dict[str, int]] = {}
        for run_id, label, k in rows:
            counts.setdefault(int(run_id), {lab: 0 for lab in LABELS})[label] = int(k)
        return counts

    def label_sources(self, run_id: int) -> list[str]:
        """The distinct label sources of the run's pairs, sorted."""
        with self.engine.connect() as conn:
            rows = (
                conn.execute(sa.select(map_pairs.c.label_source).where(map_pairs.c.run_id == int(run_id)).distinct())
                .scalars()
                .all()
            )
        return sorted(rows)

    # ------------------------------------------------------------------------------- reads for the report

    def pair_labels(self, run_id: int) -> tuple[np.ndarray, np.ndarray]:
        """Every stored pair of the run without maps and paths: `(pair_index int64 (n,), label object (n,))`,
        ordered by pair index (the report's and the evaluation's pair selection)."""
        with self.engine.connect() as conn:
            rows = conn.execute(
                sa.select(map_pairs.c.pair_index, map_pairs.c.label)
                .where(map_pairs.c.run_id == int(run_id))
                .order_by(map_pairs.c.pair_index)
            ).all()
        index = np.fromiter((r[0] for r in rows), dtype=np.int64, count=len(rows))
        labels = np.empty(len(rows), dtype=object)
        labels[:] = [r[1] for r in rows]
        return index, labels

    def termination_counts(self, run_id: int, side: str = "o") -> dict[str, int]:
        """Stored pairs per termination of the original (`side='o'`) or adversarial (`'a'`) path:
        {termination: n}, only those present, sorted by name."""
        if side not in ("o", "a"):
            raise InputError(f"side: {side!r} is not 'o' or 'a'")
        rows = self._group_counts(run_id, map_pairs.c[f"term_{side}"])
        return {str(term): int(k) for term, k in sorted(rows)}

    def harm_counts(self, run_id: int) -> dict[str, dict[str | None, int]]:
        """Stored pairs per (paper label, harm), in one GROUP BY: `{label: {harm: n}}`, only the combinations
        present. Harm None: not computed (NULL: a pair stored before vinadv kept harm, or every pair of a
        version-1 database opened read-only)."""
        c = map_pairs.c
        keys = (c.label,) if "harm" in self._absent_columns else (c.label, c.harm)
        counts: dict[str, dict[str | None, int]] = {}
        for row in self._group_counts(run_id, *keys):
            harm = row[1] if len(keys) == 2 else None
            counts.setdefault(str(row[0]), {})[harm] = int(row[-1])
        return counts

    def regret_changes(
        self, run_id: int, labels: Sequence[str] = FORK_OR_DETOUR
    ) -> dict[tuple[str, str], tuple[np.ndarray, np.ndarray]]:
        """What the attack added to the planner's regret, `regret_a - regret_o` (cost units), over the run's pairs
        with a label of `labels` whose two regrets are stored, as one GROUP BY (the report's histogram):
        `{(label, harm): (changes (k,) float64 ascending, pairs (k,) int64)}`, only the groups present.

        Changes are grouped after rounding to 1e-6 cost units: costs are sums of 1 and sqrt 2, so a run of any size
        has few distinct changes, and rounding merges the float noise of one value's different sums."""
        c = map_pairs.c
        if self._absent_columns & {"harm", "regret_o", "regret_a"}:
            return {}
        change = sa.func.round((c.regret_a - c.regret_o) * _MICRO).label("change")
        query = (
            sa.select(c.label, c.harm, change, sa.func.count())
            .where(
                c.run_id == int(run_id),
                c.label.in_(list(labels)),
                c.harm.is_not(None),
                c.regret_o.is_not(None),
                c.regret_a.is_not(None),
            )
            .group_by(c.label, c.harm, change)
        )
        with self.engine.connect() as conn:
            rows = conn.execute(query).all()
        groups: dict[tuple[str, str], list] = {}
        for label, harm, value, k in rows:
            groups.setdefault((str(label), str(harm)), []).append((float(value) / _MICRO, int(k)))
        return {
            key: (np.array([v for v, _ in part], dtype=np.float64), np.array([k for _, k in part], np.int64))
            for key, part in ((key, sorted(part)) for key, part in sorted(groups.items()))
        }


def _sqlite_pragmas(dbapi_conn, _record) -> None:
    """Per-connection settings only: nothing here writes to the file (a database is checked before any write).

    The file's own settings are made once, by `_check_schema` when it creates the tables: 32 KiB pages (large
    pages hold many ~2 KB rows (maps + paths) each: 16 KiB gave a ~30% smaller file and faster inserts than 4 KiB,
    32 KiB another ~10% less CPU per inserted row than 16 KiB, 64 KiB no better) and journal_mode=WAL (readers
    don't block the writer; a crash leaves whole commits)."""
    cursor = dbapi_conn.cursor()
    cursor.execute("PRAGMA synchronous=NORMAL")  # safe in WAL against process crashes; fsync at checkpoints
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.execute("PRAGMA busy_timeout=30000")
    cursor.close()


def _shards_key(run_id: int) -> str:
    """The `vinadv_meta` key of a run's stored-shard count (in the meta table: no schema change)."""
    return f"run:{int(run_id)}:shards_done"


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


def _one_line_error(shown: str):
    """A `handle_error` listener: a fault of the database (see `_FAULTS`) becomes an `OutputError` naming it,
    without SQLAlchemy's multi-line text (the statement and its parameters: maps and paths)."""

    def handle(context) -> Exception | None:
        exc = context.sqlalchemy_exception
        if context.connection is None or not (isinstance(exc, _FAULTS) or type(exc) is sa_exc.DatabaseError):
            return None  # connect errors: `Store.open` words them; integrity/programming errors are bugs
        return OutputError(f"database {shown}: {_first_line(exc)}")

    return handle


# ------------------------------------------------------------------------------------ row encoding

#: columns read back, in order (`decode_rows` relies on it)
PAIR_COLUMNS = (
    "no",
    "pair_index",
    "map_o",
    "map_a",
    "path_o",
    "path_a",
    "label",
    "attack",
    "start",
    "goal",
    "added_obstacle",
    "label_source",
    "score",
    "term_o",
    "term_a",
    "dh",
    "dv",
    *HARM_COLUMNS,
    MORE_ADDED_COLUMN,
)


#: columns written by `encode_rows`, in order: those read back, with the run instead of the row number
INSERT_COLUMNS = ("run_id", *PAIR_COLUMNS[1:])


def _driver_insert_sql(dialect: sa.Dialect, rows: int = 1) -> str | None:
    """A plain `INSERT INTO map_pairs (...) VALUES (?, ...)` of `rows` rows (flat parameters, row after row) in the
    driver's positional paramstyle, or None.

    For SQLite it takes `encode_rows(..., sqlite=True)` rows (dh and dv as `NULLIF(?, -1)`, added_more as
    `NULLIF(?, '')`)."""
    marker = {"qmark": "?", "format": "%s", "pyformat": "%s"}.get(dialect.paramstyle)
    if marker is None:
        return None
    prep = dialect.identifier_preparer
    names = ", ".join(prep.quote(name) for name in INSERT_COLUMNS)
    sqlite_null = {"dh": "-1", "dv": "-1", MORE_ADDED_COLUMN: "''"} if dialect.name == "sqlite" else {}
    values = [
        f"NULLIF({marker}, {sqlite_null[name]})" if name in sqlite_null else marker  # see encode_rows
        for name in INSERT_COLUMNS
    ]
    group = f"({', '.join(values)})"
    return f"INSERT INTO {prep.format_table(map_pairs)} ({names}) VALUES {', '.join([group] * rows)}"


def encode_rows(
    run_id: int, records: PairRecords, lo: int = 0, hi: int | None = None, *, sqlite: bool = False
) -> list[tuple]:
    """Records `lo:hi` (default all) -> parameter tuples in `INSERT_COLUMNS` order, text columns encoded in bulk.

    NULLs are None and `attack` a bool, unless `sqlite`: then rows take SQLite's native form, holding only ints,
    floats and strs, which the sqlite3 module binds without looking for an adapter (it does for any other value,
    bool and None included: ~0.5 us each): `attack` 0/1, a NULL score a NaN (SQLite stores a NaN as NULL), a NULL
    dh/dv -1 (`_driver_insert_sql` wraps them in `NULLIF(?, -1)`), a NULL harm cost a NaN, a NULL added_more ''
    (`NULLIF(?, '')`).
    """
    return list(zip(*_encode_columns(run_id, records, lo, hi, sqlite)))


def _encode_columns(run_id: int, records: PairRecords, lo: int, hi: int | None, sqlite: bool) -> list:
    """The `INSERT_COLUMNS` of records `lo:hi`, one list of n values each.

    Reads the row range through views (no copy of the records, unlike `PairRecords.subset`).
    """
    hi = len(records) if hi is None else min(hi, len(records))
    lo = min(max(lo, 0), hi)
    n = hi - lo
    rows = slice(lo, hi)

    def path(side: str) -> list[str]:
        paths = getattr(records, f"path_{side}")
        offsets = paths.offsets[lo : hi + 1]
        cells = paths.cells[offsets[0] : offsets[-1]]
        return codec.encode_paths(cells, offsets - offsets[0])

    def nullable(values: np.ndarray, null: np.ndarray) -> list:
        if sqlite:
            return values.tolist()  # NaN and -1 stand for NULL (see `encode_rows`)
        out = values.astype(object)
        out[null] = None
        return out.tolist()

    score, dh, dv = records.score[rows], records.dh[rows], records.dv[rows]
    attack = records.attack[rows]
    columns = {
        "run_id": [int(run_id)] * n,
        "pair_index": records.pair_index[rows].tolist(),
        "map_o": codec.encode_maps(records.obstacles_o[rows]),
        "map_a": codec.encode_maps(records.obstacles_a[rows]),
        "path_o": path("o"),
        "path_a": path("a"),
        "label": records.label[rows].tolist(),
        "attack": (attack.astype(np.int64) if sqlite else attack).tolist(),
        "start": codec.encode_cells(records.starts[rows]),
        "goal": codec.encode_cells(records.goals[rows]),
        "added_obstacle": codec.encode_cells(records.added[rows, 0]),
        "label_source": records.label_source[rows].tolist(),
        "score": nullable(score, np.isnan(score)),
        "term_o": records.term_o[rows].tolist(),
        "term_a": records.term_a[rows].tolist(),
        "dh": nullable(dh, dh < 0),
        "dv": nullable(dv, dv < 0),
        **{
            name: nullable(getattr(records, name)[rows], np.isnan(getattr(records, name)[rows]))
            for name in HARM_FLOAT_COLUMNS
        },
        "expert_label": records.expert_label[rows].tolist(),  # None = NULL
        "harm": records.harm[rows].tolist(),
        MORE_ADDED_COLUMN: _encode_more_added(records.added[rows], "" if sqlite else None),
    }
    assert tuple(columns) == INSERT_COLUMNS
    return list(columns.values())


def _encode_more_added(added: np.ndarray, null) -> list:
    """`added_more` of `added (n, K, 2)`: the cells after the first as path text, `null` for every row when K = 1."""
    n, k = added.shape[:2]
    if k == 1:
        return [null] * n
    return codec.encode_paths(added[:, 1:].reshape(-1, 2), np.arange(n + 1, dtype=np.int64) * (k - 1))


def _decode_added(first: Sequence[str], more: Sequence[str | None]) -> np.ndarray:
    """`(n, K, 2)` added cells from `added_obstacle` and `added_more` texts (None: none after the first); every row
    must add as many cells (InputError otherwise: read one run's pairs at a time)."""
    first_cells = codec.decode_cells(first).reshape(-1, 1, 2)
    if all(m is None for m in more):
        return first_cells
    cells, offsets = codec.decode_paths(["" if m is None else m for m in more])
    counts = np.diff(offsets)
    if (counts != counts[0]).any():
        raise InputError(
            f"map_pairs: rows with different numbers of added obstacles ({sorted(set(counts + 1))}) "
            "in one read; read one run at a time"
        )
    rest = cells.astype(np.int64).reshape(len(first_cells), int(counts[0]), 2)
    return np.concatenate([first_cells, rest], axis=1)


def decode_rows(rows: Sequence) -> PairRecords:
    """Rows of `PAIR_COLUMNS` -> PairRecords (text columns decoded in bulk)."""
    cols = list(zip(*rows)) if rows else [()] * len(PAIR_COLUMNS)
    col = dict(zip(PAIR_COLUMNS, cols))
    path_o = codec.decode_paths(col["path_o"])
    path_a = codec.decode_paths(col["path_a"])
    map_o = codec.decode_maps(col["map_o"])
    map_a = codec.decode_maps(col["map_a"], size=map_o.shape[-1] if len(rows) else None)

    def nullable(values, fill, dtype):
        return np.array([fill if v is None else v for v in values], dtype=dtype).reshape(-1)

    return PairRecords(
        no=np.array(col["no"], dtype=np.int64).reshape(-1),
        pair_index=np.array(col["pair_index"], dtype=np.int64).reshape(-1),
        obstacles_o=map_o,
        obstacles_a=map_a,
        starts=codec.decode_cells(col["start"]).reshape(-1, 2),
        goals=codec.decode_cells(col["goal"]).reshape(-1, 2),
        added=_decode_added(col["added_obstacle"], col[MORE_ADDED_COLUMN]),
        path_o=PackedPaths(*path_o),
        path_a=PackedPaths(*path_a),
        label=np.array(col["label"], dtype=object),
        attack=np.array([bool(a) for a in col["attack"]], dtype=bool),
        term_o=np.array(col["term_o"], dtype=object),
        term_a=np.array(col["term_a"], dtype=object),
        label_source=np.array(col["label_source"], dtype=object),
        score=nullable(col["score"], np.nan, np.float64),
        dh=nullable(col["dh"], -1, np.int64),
        dv=nullable(col["dv"], -1, np.int64),
        **{name: nullable(col[name], np.nan, np.float64) for name in HARM_FLOAT_COLUMNS},
        expert_label=np.array(col["expert_label"], dtype=object),
        harm=np.array(col["harm"], dtype=object),
    )
