"""The identified map pairs of a `Store` (`map_pairs`): bulk writes that resume, reads decoded into arrays.

Writes: `write_pairs` inserts in batches, each batch in its own transaction (all-or-nothing; inside it, rows are
encoded and inserted a chunk at a time, into SQLite by multi-row INSERT statements). With
`(run_id, pair_index)` unique and stored indices skipped on resume, a killed run that is resumed ends with
every pair exactly once; a power loss may lose the last committed batches (they are then written again on resume).
"""

from __future__ import annotations

import functools
import sqlite3
from collections.abc import Iterator, Sequence

import numpy as np
import sqlalchemy as sa

from vinadv.errors import InputError
from vinadv.store.codec import (
    INSERT_COLUMNS,
    PAIR_COLUMNS,
    decode_rows,
    driver_insert_sql,
    encode_columns,
    encode_rows,
)
from vinadv.store.connection import Database, DeadlockError
from vinadv.store.records import PairRecords
from vinadv.store.schema import map_pairs

#: rows per INSERT transaction; large enough to amortise the round trip, small enough to keep memory flat.
DEFAULT_BATCH = 20_000
#: rows encoded at a time while SQLite inserts a batch (a few MB of text: stays in the CPU cache)
ROW_CHUNK = 2048
#: rows per SQLite INSERT statement (at most what SQLite's parameter limit allows), see `PairQueries._insert_sqlite`
SQLITE_ROWS_PER_STATEMENT = 256


class PairQueries(Database):
    """Write, read and count a run's stored pairs (a part of `Store`)."""

    _multi_insert: tuple[int, str] | None = None  # (rows per statement, SQL), see `_insert_sqlite`

    @functools.cached_property
    def _insert_sql(self) -> str | None:
        """The one-row INSERT in the driver's own paramstyle (None: the driver's style has no plain form)."""
        return driver_insert_sql(self.engine.dialect)

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
        deadlock_retries: int = 3,
    ) -> int:
        """Insert `records` for the run, `batch_size` rows per transaction; return how many were written.

        With `skip_stored` (the resume path) pairs whose index is already stored are skipped, and a batch the
        server rolled back to break a deadlock with another writer of the run (a concurrent resume) is written again,
        what is stored by then skipped, up to `deadlock_retries` times. A batch is all-or-nothing: a crash leaves
        whole batches only. `progress(n_rows)` is called after each batch.
        """
        run_id = int(run_id)
        self.refuse_outdated()
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
            try:
                self._insert_batch(run_id, records, lo, hi)
                done = hi - lo
            except sa.exc.IntegrityError as conflict:
                if not skip_stored:
                    raise
                done = self._insert_missing(run_id, records.take(slice(lo, hi)), batch_size, conflict)
            except DeadlockError:
                if not skip_stored or deadlock_retries < 1:
                    raise
                # rolled back whole: the retry waits on the other writer's locks, then skips what it stored
                batch = records.take(slice(lo, hi))
                done = self.write_pairs(
                    run_id, batch, batch_size=batch_size, skip_stored=True, deadlock_retries=deadlock_retries - 1
                )
            written += done
            if progress is not None:
                progress(hi - lo)
        return written

    def _insert_batch(self, run_id: int, records: PairRecords, lo: int, hi: int) -> None:
        """Insert records `lo:hi` in one transaction (all or nothing)."""
        with self.engine.begin() as conn:
            # encoded and inserted a chunk at a time, inside the batch's one transaction: the batch's text
            # never exists all at once, and each chunk is still in the CPU cache when the driver copies it
            for start in range(lo, hi, ROW_CHUNK):
                stop = min(start + ROW_CHUNK, hi)
                if self.sqlite:
                    self._insert_sqlite(conn, run_id, records, start, stop)
                elif self._insert_sql is not None:
                    # straight to the driver's executemany: SQLAlchemy's per-row parameter processing would
                    # cost more than encoding and inserting together (PyMySQL turns it into multi-row INSERTs)
                    conn.exec_driver_sql(self._insert_sql, encode_rows(run_id, records, start, stop))
                else:
                    rows = encode_rows(run_id, records, start, stop)
                    conn.execute(map_pairs.insert(), [dict(zip(INSERT_COLUMNS, row)) for row in rows])

    def _insert_missing(self, run_id: int, batch: PairRecords, batch_size: int, conflict: sa.exc.IntegrityError) -> int:
        """A batch that met pairs of its own stored since they were read (another writer of the run: a concurrent
        `--resume`): write those still missing. A conflict that no newly stored pair explains (the run's row
        gone, say) is raised as it was."""
        stored = self.stored_indices(run_id, batch.pair_index.min(), batch.pair_index.max())
        missing = ~np.isin(batch.pair_index, stored)
        if missing.all():
            raise conflict
        return self.write_pairs(run_id, batch.take(missing), batch_size=batch_size, skip_stored=True)

    def _insert_sqlite(self, conn: sa.Connection, run_id: int, records: PairRecords, lo: int, hi: int) -> None:
        """Insert records `lo:hi` into SQLite, mostly `SQLITE_ROWS_PER_STATEMENT` rows per INSERT statement.

        One statement of k rows costs SQLite and the sqlite3 module ~1 us less per row than k one-row statements
        (one statement step instead of k, and a tuple of parameters per statement, not per row).
        """
        if self._multi_insert is None:
            limit = getattr(conn.connection.driver_connection, "getlimit", None)
            max_params = limit(sqlite3.SQLITE_LIMIT_VARIABLE_NUMBER) if limit else 999  # 999: SQLite before 3.32
            k = max(1, min(SQLITE_ROWS_PER_STATEMENT, max_params // len(INSERT_COLUMNS)))
            self._multi_insert = (k, driver_insert_sql(self.engine.dialect, rows=k))
        k, sql = self._multi_insert
        columns = encode_columns(run_id, records, lo, hi, sqlite=True)
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

    def iter_pairs(self, run_id: int, *, successful_only: bool = False, chunk: int = 10_000) -> Iterator[PairRecords]:
        """The run's stored pairs, ordered by pair index, decoded into `PairRecords` of at most `chunk` pairs each
        (streamed: a run larger than memory is read a chunk at a time; none for a run without pairs)."""
        if int(chunk) < 1:
            raise InputError(f"chunk: {chunk} pairs, need at least 1", "chunk")
        query = self._pairs_query(run_id, successful_only=successful_only)
        with self.engine.connect() as conn:
            result = conn.execution_options(stream_results=True, yield_per=int(chunk)).execute(query)
            for part in result.partitions(int(chunk)):
                yield decode_rows(part)

    def _pairs_query(self, run_id, *, successful_only=False, labels=None, pair_indices=None) -> sa.Select:
        query = sa.select(
            *[sa.null().label(name) if name in self.absent_columns else map_pairs.c[name] for name in PAIR_COLUMNS]
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
