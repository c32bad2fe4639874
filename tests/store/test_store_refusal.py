"""Refused databases stay byte-identical; read-only databases stay readable; database faults are one line.

(issue 21: the schema check ran after WAL was switched on, a read-only file could not be read, a full disk printed
SQLAlchemy's traceback with the SQL parameters.)
"""

from __future__ import annotations

import os
import sqlite3
import subprocess
import threading
import uuid
from pathlib import Path

import numpy as np
import pytest
import sqlalchemy as sa

from tests.fault_files import tmpfs
from vinadv.cli import main
from vinadv.commands import cli_message
from vinadv.errors import InputError, OutputError
from vinadv.report import build_report
from vinadv.store import Store
from vinadv.testing.store import random_records


def _snapshot(folder: Path) -> dict[str, bytes]:
    """Every file of `folder` with its bytes (a -wal or -shm file appearing counts as a change)."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _foreign_sqlite(path: Path) -> None:
    conn = sqlite3.connect(path)
    conn.execute("CREATE TABLE map_pairs (id INTEGER PRIMARY KEY, note TEXT)")
    conn.execute("INSERT INTO map_pairs VALUES (1, 'keep me')")
    conn.commit()
    conn.close()


def _other_version(path: Path) -> None:
    with Store.open(str(path)) as store:
        store.write_pairs(store.create_run("old"), random_records(5, size=6, seed=1))
    conn = sqlite3.connect(path)
    conn.execute("UPDATE vinadv_meta SET value = '999' WHERE key = 'schema_version'")
    conn.commit()
    conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    conn.execute("PRAGMA journal_mode=DELETE")  # one file, so that any later write shows in its bytes
    conn.close()


def _not_sqlite(path: Path) -> None:
    path.write_bytes(np.random.default_rng(3).bytes(5000))


def _text_file(path: Path) -> None:
    path.write_text("run,pair\n1,2\n")


@pytest.mark.parametrize(
    "make, message",
    [
        (_foreign_sqlite, "not a vinadv database"),
        (_other_version, "schema version '999'"),
        (_not_sqlite, "not a database"),
        (_text_file, "not a database"),
    ],
)
@pytest.mark.parametrize("how", ["create", "read", "readonly"])
def test_refused_sqlite_file_is_left_byte_identical(tmp_path, make, message, how):
    folder = tmp_path / "db"
    folder.mkdir()
    path = folder / "x.db"
    make(path)
    before = _snapshot(folder)
    with pytest.raises(InputError, match=message) as err:
        Store.open(str(path), create=how == "create", readonly=how == "readonly")
    assert "\n" not in str(err.value)
    assert _snapshot(folder) == before


def test_refused_database_cli_exit_2_and_untouched(tmp_path, capsys):
    folder = tmp_path / "db"
    folder.mkdir()
    _foreign_sqlite(folder / "x.db")
    before = _snapshot(folder)
    assert main(["export", "--db", str(folder / "x.db"), "--run", "1"]) == 2
    assert main(["run", "--n", "2", "--db", str(folder / "x.db"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("not a vinadv database") == 2 and "Traceback" not in err
    assert _snapshot(folder) == before


def _remount_readonly(path: Path) -> None:
    subprocess.run(["mount", "-o", "remount,ro", str(path)], check=True)


def test_read_only_database_can_be_read(tmp_path):
    with tmpfs(tmp_path / "ro") as folder:
        url = str(folder / "runs.db")
        records = random_records(30, size=7, seed=2)
        with Store.open(url) as store:
            run_id = store.create_run("kept")
            store.write_pairs(run_id, records)
        for extra in folder.glob("runs.db-*"):  # as a clean close leaves it: no -wal, no -shm
            assert extra.stat().st_size == 0 or extra.name.endswith("-shm")
        _remount_readonly(folder)
        before = _snapshot(folder)
        with Store.open(url, readonly=True) as store:
            assert store.readonly
            assert store.read_pairs(store.resolve_run("kept")).equals(records)
            with pytest.raises(OutputError, match="runs.db"):
                store.create_run("new")
        out = tmp_path / "out.csv"
        assert main(["export", "--db", url, "--run", "kept", "--out", str(out), "--quiet"]) == 0
        assert len(out.read_text().splitlines()) == 31
        assert _snapshot(folder) == before


def test_read_only_database_report(tmp_path):
    """`report` opens the database read-only too (a file on a read-only file system)."""
    with tmpfs(tmp_path / "ro") as folder:
        url = str(folder / "runs.db")
        with Store.open(url) as store:
            store.write_pairs(store.create_run("kept", attack="random"), random_records(12, size=7, seed=2))
        _remount_readonly(folder)
        with Store.open(url, readonly=True) as store:
            assert store.list_runs()[0]["n_pairs"] == 12
        with pytest.raises(InputError, match="run_id: no run named 'absent'"):
            build_report(url, tmp_path / "report", run_id="absent")


def test_full_disk_while_writing_is_one_line_naming_the_database(tmp_path):
    with tmpfs(tmp_path / "full", size="3M") as folder:
        url = str(folder / "full.db")
        with Store.open(url) as store:
            run_id = store.create_run("big")
            with pytest.raises(OutputError) as err:
                store.write_pairs(run_id, random_records(3000, size=28, seed=1), batch_size=500)
        message = str(err.value)
        assert "full.db" in message and "full" in message and "\n" not in message
        assert "INSERT" not in message and len(message) < 300


def test_run_name_is_unique_and_not_a_number(sqlite_url):
    with Store.open(sqlite_url) as store:
        first = store.create_run("k")
        with pytest.raises(InputError, match="already called 'k'.*resume") as caught:
            store.create_run("k")
        assert "with --resume, or choose another --name" in cli_message(caught.value)
        with pytest.raises(InputError, match="numbers are run ids"):
            store.create_run("12")
        assert [r["id"] for r in store.list_runs()] == [first]
        store.create_run(None)
        store.create_run(None)  # unnamed runs are not resumable and need no unique name


def test_one_rule_for_run_references(sqlite_url):
    with Store.open(sqlite_url) as store:
        a = store.create_run("alpha")
        b = store.create_run("beta")
        assert store.resolve_run(str(a)) == a and store.resolve_run(b) == b
        assert store.resolve_run("beta") == b and store.resolve_run(" alpha ") == a
        for bad in ("99", "gamma", ""):
            with pytest.raises(InputError, match="run_id: no run") as caught:  # the library names the parameter
                store.resolve_run(bad)
            assert caught.value.parameters == ("run_id",)  # which the command line shows as --run


def test_mysql_and_postgres_refusal_changes_nothing(db_url):
    """The same check-first order on the servers: a foreign table is refused, its rows and tables unchanged."""
    engine = sa.create_engine(db_url, poolclass=sa.pool.NullPool)
    name = f"t{uuid.uuid4().hex[:6]}"
    with engine.begin() as conn:
        conn.execute(sa.text("CREATE TABLE runs (id INTEGER PRIMARY KEY, note VARCHAR(20))"))
        conn.execute(sa.text(f"CREATE TABLE {name} (id INTEGER PRIMARY KEY)"))
    with engine.connect() as conn:
        tables = sorted(sa.inspect(conn).get_table_names())
    with pytest.raises(InputError, match="not a vinadv database"):
        Store.open(db_url)
    with engine.connect() as conn:
        assert sorted(sa.inspect(conn).get_table_names()) == tables
    engine.dispose()


def test_sqlite_created_file_uses_wal_and_large_pages(tmp_path):
    path = tmp_path / "new.db"
    with Store.open(str(path)):
        pass
    conn = sqlite3.connect(path)
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    assert conn.execute("PRAGMA page_size").fetchone()[0] == 32768
    conn.close()
    assert os.path.getsize(path) % 32768 == 0


def test_a_switch_to_wal_waits_for_another_connections_write_lock(tmp_path):
    """A vinadv file in rollback-journal mode (another tool's setting) whose write lock another connection holds
    while vinadv opens it: SQLite refuses the switch to WAL at once ("database is locked", without its busy
    timeout), and the switch is tried again until the lock is let go, not raised. Two first uses of one new
    database at once met this: one switching while the other held the schema lock (a CI failure)."""
    path = tmp_path / "old-journal.db"
    with Store.open(str(path)):
        pass
    other = sqlite3.connect(path, isolation_level=None, check_same_thread=False)
    other.execute("PRAGMA journal_mode=DELETE")
    other.execute("BEGIN IMMEDIATE")
    released = threading.Timer(0.3, other.execute, args=("COMMIT",))
    released.start()
    try:
        with Store.open(str(path)):
            pass
    finally:
        released.join()
        other.close()
    conn = sqlite3.connect(path)
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    conn.close()
