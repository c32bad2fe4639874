"""Store throughput: rows/s into SQLite, MariaDB and PostgreSQL, maps and paths included, side by side.

    .venv/bin/python benchmarks/store.py [--n 50000] [--size 28] [--max-path 60] [--json]

Prints, measured in one run on the same random records (`vinadv.store.synthetic.random_records`):
- encode only: PairRecords -> row tuples (the vectorised text encoding of maps, paths and cells);
- sqlite3 ceiling: the bare `sqlite3` driver inserting the already-encoded tuples into the same schema, one
  transaction per batch (what SQLite itself costs, with no encoding);
- write / read rows/s of `Store.write_pairs` / `Store.read_pairs` for each database (a fresh SQLite file, a fresh
  MariaDB database, a fresh PostgreSQL schema; dropped afterwards). A server that cannot be reached is skipped,
  saying so. Server URLs: --mysql-url / --postgres-url, else $VINADV_TEST_MYSQL_URL / $VINADV_TEST_POSTGRES_URL,
  else the local defaults.
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
from vinadv.store.store import DEFAULT_BATCH, _driver_insert_sql, encode_rows
from vinadv.store.synthetic import random_records

MYSQL_DEFAULT = "mysql+pymysql://root@127.0.0.1:3306/test"
POSTGRES_DEFAULT = "postgresql+psycopg://postgres@127.0.0.1:5432/test"


def _best(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


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


def _store_rates(url: str, records, batch: int) -> tuple[float, float]:
    with Store.open(url) as store:
        run_id = store.create_run("bench")
        write_s = _best(lambda: store.write_pairs(run_id, records, batch_size=batch, skip_stored=False), 1)
        read_s = _best(lambda: store.read_pairs(run_id), 1)
    return len(records) / write_s, len(records) / read_s


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=50_000, help="rows per database")
    parser.add_argument("--size", type=int, default=28, help="map side N")
    parser.add_argument("--max-path", type=int, default=60, help="path lengths uniform in 0..max-path cells")
    parser.add_argument("--batch", type=int, default=DEFAULT_BATCH, help="rows per transaction")
    parser.add_argument("--mysql-url", default=os.environ.get("VINADV_TEST_MYSQL_URL") or MYSQL_DEFAULT)
    parser.add_argument("--postgres-url", default=os.environ.get("VINADV_TEST_POSTGRES_URL") or POSTGRES_DEFAULT)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)

    records = random_records(args.n, size=args.size, seed=0, max_path=args.max_path)
    rows = encode_rows(1, records)
    mean_bytes = sum(sum(len(v) for v in r if isinstance(v, str)) for r in rows[:1000]) / min(1000, len(rows))
    result: dict = {"n": args.n, "size": args.size, "mean_text_bytes_per_row": round(mean_bytes), "batch": args.batch}
    result["encode_rows_per_s"] = args.n / _best(lambda: encode_rows(1, records), 3)

    with tempfile.TemporaryDirectory(dir=".") as tmp:
        # bare sqlite3 on the same schema and pragmas: the ceiling without encoding or SQLAlchemy
        ceiling_path = Path(tmp) / "ceiling.db"
        with Store.open(str(ceiling_path)):
            pass
        con = sqlite3.connect(ceiling_path)
        for pragma in ("journal_mode=WAL", "synchronous=NORMAL"):
            con.execute(f"PRAGMA {pragma}")
        sql = _driver_insert_sql(sa.create_engine("sqlite://").dialect)

        def raw():
            for lo in range(0, len(rows), args.batch):
                con.executemany(sql, rows[lo : lo + args.batch])
                con.commit()

        result["sqlite3_ceiling_rows_per_s"] = args.n / _best(raw, 1)
        con.close()
        write, read = _store_rates(str(Path(tmp) / "store.db"), records, args.batch)
        result["sqlite"] = {"write_rows_per_s": write, "read_rows_per_s": read}

    for kind, url in (("mysql", args.mysql_url), ("postgres", args.postgres_url)):
        fresh, cleanup = _server_database(kind, url)
        if fresh is None:
            result[kind] = {"skipped": f"{sa.make_url(url).render_as_string(hide_password=True)} {cleanup}"}
            continue
        try:
            write, read = _store_rates(fresh, records, args.batch)
            result[kind] = {"write_rows_per_s": write, "read_rows_per_s": read}
        finally:
            cleanup()

    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print(f"{args.n} rows, {args.size}x{args.size} maps, paths 0..{args.max_path} cells "
          f"(~{result['mean_text_bytes_per_row']} text bytes/row), {args.batch} rows per transaction")
    print(f"  encode only                  {result['encode_rows_per_s']:>10,.0f} rows/s")
    print(f"  sqlite3 driver, pre-encoded  {result['sqlite3_ceiling_rows_per_s']:>10,.0f} rows/s  (ceiling)")
    for kind in ("sqlite", "mysql", "postgres"):
        entry = result[kind]
        if "skipped" in entry:
            print(f"  {kind:<9} skipped: {entry['skipped']}")
            continue
        extra = ""
        if kind == "sqlite":
            extra = f"  ({entry['write_rows_per_s'] / result['sqlite3_ceiling_rows_per_s']:.2f} x ceiling)"
        print(f"  {kind:<9} write {entry['write_rows_per_s']:>10,.0f} rows/s   read {entry['read_rows_per_s']:>10,.0f} rows/s{extra}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
