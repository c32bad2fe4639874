"""Store throughput: rows/s into SQLite, MariaDB and PostgreSQL, maps and paths included, side by side.

    .venv/bin/python perf/store.py [--n 50000] [--size 28] [--max-path 60] [--repeat 3] [--json]

Prints, measured in one run on the same random records (`vinadv.testing.store.random_records`):
- encode only: PairRecords -> row tuples (the vectorised text encoding of maps, paths and cells), in the form
  `Store.write_pairs` sends to SQLite;
- sqlite3 ceiling: the bare `sqlite3` driver inserting the already-encoded rows into the same schema with the same
  pragmas and the same statements as `Store.write_pairs` (`SQLITE_ROWS_PER_STATEMENT` rows per INSERT), one
  transaction per batch: what SQLite itself costs, with no encoding;
- write / read rows/s of `Store.write_pairs` / `Store.read_pairs` for each database (a fresh SQLite file, a fresh
  MariaDB database, a fresh PostgreSQL schema; dropped afterwards). A server that cannot be reached is skipped,
  saying so. Server URLs: --mysql-url / --postgres-url, else $VINADV_TEST_MYSQL_URL / $VINADV_TEST_POSTGRES_URL,
  else the local defaults.

Encoding and the SQLite figures are the best of --repeat trials (each SQLite trial into a fresh file), the servers'
one trial. Next to the wall-clock rates of the in-process work (encoding, SQLite) it prints the rate per second
of this process's CPU time, which other load on the machine hardly changes (the header gives the load average).
"""

from __future__ import annotations

import argparse
import json
import os
import sqlite3
import sys
import tempfile
import time
import uuid
from pathlib import Path

import sqlalchemy as sa

from vinadv.store import Store
from vinadv.store.codec import driver_insert_sql, encode_rows
from vinadv.store.pairs import DEFAULT_BATCH, SQLITE_ROWS_PER_STATEMENT
from vinadv.testing.store import random_records

MYSQL_DEFAULT = "mysql+pymysql://root@127.0.0.1:3306/test"
POSTGRES_DEFAULT = "postgresql+psycopg://postgres@127.0.0.1:5432/test"


def _best(fn, repeat: int, setup=None) -> tuple[float, float]:
    """(least wall-clock seconds, least process CPU seconds) of `repeat` calls of `fn(setup())` (or `fn()`)."""
    wall = cpu = float("inf")
    for _ in range(repeat):
        args = () if setup is None else (setup(),)  # untimed
        start, start_cpu = time.perf_counter(), time.process_time()
        fn(*args)
        wall = min(wall, time.perf_counter() - start)
        cpu = min(cpu, time.process_time() - start_cpu)
    return wall, cpu


def _server_database(kind: str, url: str):
    """(fresh database URL, cleanup) on the server at `url`, or (None, reason)."""
    engine = sa.create_engine(url, connect_args={"connect_timeout": 5}, poolclass=sa.pool.NullPool)
    name = f"vinadv_bench_{uuid.uuid4().hex[:10]}"
    try:
        with engine.begin() as conn:
            if kind == "mysql":
                conn.execute(sa.text(f"CREATE DATABASE `{name}` CHARACTER SET utf8mb4"))
            else:
                conn.execute(sa.text(f'CREATE SCHEMA "{name}"'))
    except Exception as exc:
        return None, f"unreachable ({str(exc).strip().splitlines()[0]})"
    if kind == "mysql":
        fresh = engine.url.set(database=name)
        drop = f"DROP DATABASE IF EXISTS `{name}`"
    else:
        fresh = engine.url.update_query_dict({"options": f"-csearch_path={name}"})
        drop = f'DROP SCHEMA IF EXISTS "{name}" CASCADE'

    def cleanup():
        with engine.begin() as conn:
            conn.execute(sa.text(drop))
        engine.dispose()

    return fresh.render_as_string(hide_password=False), cleanup


def _store_rates(urls, records, batch: int, repeat: int) -> dict:
    """Write then read `records` into a fresh database per trial (`urls()` gives its URL): rows/s, best of trials."""
    n, best = len(records), {"write": [], "read": []}
    for _ in range(repeat):
        with Store.open(urls()) as store:
            run_id = store.create_run("bench")
            write = lambda: store.write_pairs(run_id, records, batch_size=batch, skip_stored=False)  # noqa: E731
            best["write"].append(_best(write, 1))
            best["read"].append(_best(lambda: store.read_pairs(run_id), 1))
    return {
        "write_rows_per_s": n / min(w for w, _ in best["write"]),
        "write_rows_per_cpu_s": n / min(c for _, c in best["write"]),
        "read_rows_per_s": n / min(w for w, _ in best["read"]),
    }


def _statements(rows: list[tuple], k: int) -> tuple[list[tuple], list[tuple]]:
    """One batch's rows as `Store._insert_sqlite` sends them: flat parameter tuples of k rows, and the rest."""
    whole = len(rows) // k * k
    flat = [value for row in rows[:whole] for value in row]
    step = k * len(rows[0]) if rows else 1
    return [tuple(flat[i : i + step]) for i in range(0, len(flat), step)], rows[whole:]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=50_000, help="rows per database")
    parser.add_argument("--size", type=int, default=28, help="map side N")
    parser.add_argument("--max-path", type=int, default=60, help="path lengths uniform in 0..max-path cells")
    parser.add_argument("--batch", type=int, default=DEFAULT_BATCH, help="rows per transaction")
    parser.add_argument("--mysql-url", default=os.environ.get("VINADV_TEST_MYSQL_URL") or MYSQL_DEFAULT)
    parser.add_argument("--postgres-url", default=os.environ.get("VINADV_TEST_POSTGRES_URL") or POSTGRES_DEFAULT)
    parser.add_argument("--repeat", type=int, default=3, help="trials of the in-process measurements (best kept)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)

    records = random_records(args.n, size=args.size, seed=0, max_path=args.max_path)
    # the rows `Store.write_pairs` sends to SQLite (its native form: see `encode_rows`)
    rows = encode_rows(1, records, sqlite=True)
    mean_bytes = sum(sum(len(v) for v in r if isinstance(v, str)) for r in rows[:1000]) / min(1000, len(rows))
    result: dict = {
        "n": args.n,
        "size": args.size,
        "mean_text_bytes_per_row": round(mean_bytes),
        "batch": args.batch,
        "load_average_1min": round(os.getloadavg()[0], 2),
        "cpus": os.cpu_count(),
    }
    wall, cpu = _best(lambda: encode_rows(1, records, sqlite=True), args.repeat)
    result["encode_rows_per_s"], result["encode_rows_per_cpu_s"] = args.n / wall, args.n / cpu

    with tempfile.TemporaryDirectory(dir=".") as tmp:
        trial = iter(range(10**9))
        # bare sqlite3 on the same schema, pragmas and statements: the ceiling without encoding or SQLAlchemy
        limit = sqlite3.connect(":memory:").getlimit(sqlite3.SQLITE_LIMIT_VARIABLE_NUMBER)
        k = max(1, min(SQLITE_ROWS_PER_STATEMENT, limit // len(rows[0])))  # as `Store._insert_sqlite` chooses
        sql_one = driver_insert_sql(sa.create_engine("sqlite://").dialect)
        sql_k = driver_insert_sql(sa.create_engine("sqlite://").dialect, rows=k)
        batches = [_statements(rows[lo : lo + args.batch], k) for lo in range(0, len(rows), args.batch)]

        opened: list[sqlite3.Connection] = []

        def fresh_ceiling() -> sqlite3.Connection:
            path = Path(tmp) / f"ceiling{next(trial)}.db"
            with Store.open(str(path)) as store:
                store.create_run("bench")  # run 1, which the rows reference
            opened.append(sqlite3.connect(path))
            for pragma in ("journal_mode=WAL", "synchronous=NORMAL", "foreign_keys=ON"):
                opened[-1].execute(f"PRAGMA {pragma}")
            return opened[-1]

        def raw(con: sqlite3.Connection) -> None:
            for statements, rest in batches:
                con.executemany(sql_k, statements)
                con.executemany(sql_one, rest)
                con.commit()

        wall, cpu = _best(raw, args.repeat, setup=fresh_ceiling)
        for con in opened:  # closed untimed, like the store (closing checkpoints the WAL)
            con.close()
        result["sqlite3_ceiling_rows_per_s"], result["sqlite3_ceiling_rows_per_cpu_s"] = args.n / wall, args.n / cpu
        store_file = lambda: str(Path(tmp) / f"store{next(trial)}.db")  # noqa: E731
        result["sqlite"] = _store_rates(store_file, records, args.batch, args.repeat)

    for kind, url in (("mysql", args.mysql_url), ("postgres", args.postgres_url)):
        fresh, cleanup = _server_database(kind, url)
        if fresh is None:
            result[kind] = {"skipped": f"{sa.make_url(url).render_as_string(hide_password=True)} {cleanup}"}
            continue
        try:
            result[kind] = _store_rates(lambda: fresh, records, args.batch, 1)
            del result[kind]["write_rows_per_cpu_s"]  # the server's CPU time is not ours to count
        finally:
            cleanup()

    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print(
        f"{args.n} rows, {args.size}x{args.size} maps, paths 0..{args.max_path} cells "
        f"(~{result['mean_text_bytes_per_row']} text bytes/row), {args.batch} rows per transaction; "
        f"load average {result['load_average_1min']} on {result['cpus']} CPUs"
    )
    print(
        f"  encode only                  {result['encode_rows_per_s']:>10,.0f} rows/s"
        f"   ({result['encode_rows_per_cpu_s']:,.0f} per CPU second)"
    )
    print(
        f"  sqlite3 driver, pre-encoded  {result['sqlite3_ceiling_rows_per_s']:>10,.0f} rows/s"
        f"   ({result['sqlite3_ceiling_rows_per_cpu_s']:,.0f} per CPU second; ceiling)"
    )
    for kind in ("sqlite", "mysql", "postgres"):
        entry = result[kind]
        if "skipped" in entry:
            print(f"  {kind:<9} skipped: {entry['skipped']}")
            continue
        extra = ""
        if kind == "sqlite":
            extra = (
                f"   ({entry['write_rows_per_cpu_s']:,.0f} written per CPU second; "
                f"{entry['write_rows_per_s'] / result['sqlite3_ceiling_rows_per_s']:.2f} x ceiling)"
            )
        print(
            f"  {kind:<9} write {entry['write_rows_per_s']:>10,.0f} rows/s   "
            f"read {entry['read_rows_per_s']:>10,.0f} rows/s{extra}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
