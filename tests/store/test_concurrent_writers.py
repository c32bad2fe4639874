"""Two writers at once, made to meet where they used to collide by a barrier (deterministic, not by timing): two
resumes of one run that both read "nothing stored yet" before either writes, two first uses of one new
database that both find it empty before either creates the tables, and two opens of an old database that both
read its old version before either upgrades it. Both finish, and everything is stored once."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator

import numpy as np
import pytest
import sqlalchemy as sa

from tests.store.old_schemas import LATER_COLUMNS, columns_and_version, table_names, version_1_database
from vinadv.store import SCHEMA_VERSION, Store
from vinadv.store.connection import DeadlockError, is_deadlock
from vinadv.store.pairs import PairQueries
from vinadv.store.schema import evaluations
from vinadv.testing.store import random_records

#: the name of the threads these tests start (`in_two_threads`, the creator): the hooks below are global (every
#: engine, every thread of the worker), and a thread another test left behind (a server's, a pool's) passes through
#: them untouched, or it could take a thread's place at a meeting point (a rare failure of a whole-suite run)
TEST_THREAD = "concurrent-writers-test"


def ours(test_thread: int) -> bool:
    """Whether the calling thread is the test's own (`test_thread`, its ident) or one the test started."""
    return threading.get_ident() == test_thread or threading.current_thread().name.startswith(TEST_THREAD)


def meet_after_first_call(monkeypatch, owner, name: str, when=lambda result: True):
    """Make the first call of `owner.name` in each of two threads wait, once it has its result, until the other
    thread's first call has one too (when `when(result)`): both act on what they read before either writes."""
    barrier = threading.Barrier(2, timeout=30)
    seen = threading.local()
    original = getattr(owner, name)
    test_thread = threading.get_ident()

    def meeting(*args, **kw):
        result = original(*args, **kw)
        if ours(test_thread) and not getattr(seen, "done", False) and when(result):
            seen.done = True
            barrier.wait()
        return result

    monkeypatch.setattr(owner, name, meeting)


def in_two_threads(work) -> list:
    """`work(i)` for i = 0, 1 in two threads at once; their results, or the exception each raised."""
    results: list = [None, None]

    def run(i: int) -> None:
        try:
            results[i] = work(i)
        except Exception as exc:  # reported to the test, which fails on it
            results[i] = exc

    threads = [threading.Thread(target=run, args=(i,), name=f"{TEST_THREAD}-{i}") for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    return results


def test_two_resumes_of_one_run_store_every_pair_once(db_url, monkeypatch):
    records = random_records(40, size=8, seed=3)
    with Store.open(db_url) as store:
        run_id = store.create_run("twice")
    meet_after_first_call(monkeypatch, PairQueries, "stored_indices")

    def resume(i: int) -> int:
        with Store.open(db_url) as store:
            written = store.write_pairs(run_id, records, batch_size=16, skip_stored=True)
            store.set_shards_done(run_id, 1)
            return written

    written = in_two_threads(resume)
    monkeypatch.undo()
    assert all(isinstance(w, int) for w in written), written
    assert sum(written) == len(records)  # each pair written by one of them
    with Store.open(db_url, readonly=True) as store:
        np.testing.assert_array_equal(store.stored_indices(run_id), records.pair_index)
        assert store.shards_done(run_id) == 1


def test_two_first_uses_of_a_new_database_both_open_it(db_url, monkeypatch):
    # both find no tables before either creates them
    meet_after_first_call(monkeypatch, sa.engine.reflection.Inspector, "get_table_names", lambda names: not names)

    def first_use(i: int) -> int:
        with Store.open(db_url) as store:
            return store.create_run(f"run {i}")

    ids = in_two_threads(first_use)
    monkeypatch.undo()
    assert all(isinstance(i, int) for i in ids), ids
    with Store.open(db_url, readonly=True) as store:
        assert sorted(r["name"] for r in store.list_runs(with_counts=False)) == ["run 0", "run 1"]


#: the statements that take the schema lock (`connection.schema_lock`) on SQLite, PostgreSQL and MariaDB
LOCK_STATEMENTS = ("BEGIN IMMEDIATE", "PG_ADVISORY_XACT_LOCK", "GET_LOCK(")


@contextlib.contextmanager
def meet_at_first(ddl: str) -> Iterator[dict[str, set]]:
    """For the block, make each of two threads wait at its first `ddl` statement (`ALTER TABLE`, `CREATE TABLE`)
    until the other one is about to run its first too, or is about to take the schema lock (which the waiting thread
    then holds): without a lock both change what they read before either changed it, every time; with one, the
    second waits for the first to finish. Yields the threads seen at each point ({"ddl": ..., "lock": ...})."""
    seen: dict[str, set] = {"ddl": set(), "lock": set()}
    ready = threading.Condition()
    mine = threading.local()
    test_thread = threading.get_ident()

    def before(conn, cursor, statement, parameters, context, executemany):
        text, me = statement.lstrip().upper(), threading.get_ident()
        if not ours(test_thread):
            return
        if any(s in text for s in LOCK_STATEMENTS):
            with ready:
                seen["lock"].add(me)
                ready.notify_all()
        elif text.startswith(ddl) and not getattr(mine, "met", False):
            mine.met = True
            with ready:
                seen["ddl"].add(me)
                ready.notify_all()
                assert ready.wait_for(lambda: (seen["ddl"] | seen["lock"]) - {me}, timeout=30), "no other thread"

    sa.event.listen(sa.engine.Engine, "before_cursor_execute", before)
    try:
        yield seen
    finally:
        sa.event.remove(sa.engine.Engine, "before_cursor_execute", before)


def test_two_opens_of_an_old_database_upgrade_it_once(db_url):
    run_id = version_1_database(db_url, 8, name="old")

    def open_and_write(i: int) -> int:
        with Store.open(db_url) as store:
            return store.create_run(f"after {i}")

    with meet_at_first("ALTER TABLE") as seen:
        ids = in_two_threads(open_and_write)
    assert all(isinstance(i, int) for i in ids), ids
    assert len(seen["ddl"]) == 1 and len(seen["lock"]) == 2  # one upgraded, the other waited and found it done
    columns, version = columns_and_version(db_url)
    assert version == SCHEMA_VERSION and set(LATER_COLUMNS) <= columns
    with Store.open(db_url, readonly=True) as store:
        assert len(store.read_pairs(run_id)) == 8
        assert sorted(r["name"] for r in store.list_runs(with_counts=False)) == ["after 0", "after 1", "old"]


def test_two_writers_of_a_missing_additive_table_create_it_once(db_url):
    with Store.open(db_url):
        pass
    engine = sa.create_engine(db_url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        evaluations.drop(conn)  # as an older database lacks it; opened without create, it is made when written
    engine.dispose()

    def ensure(i: int) -> bool:
        with Store.open(db_url, create=False) as store:
            store.ensure_table(evaluations)
            return True

    with meet_at_first("CREATE TABLE") as seen:
        done = in_two_threads(ensure)
    assert done == [True, True], done
    assert len(seen["ddl"]) == 1 and len(seen["lock"]) == 2
    assert "evaluations" in table_names(db_url)


def test_a_resumed_batch_the_server_rolled_back_for_a_deadlock_is_written_again(tmp_path, monkeypatch):
    # the server's side of a deadlock, made by hand: the first batch's transaction is rolled back whole (nothing of it
    # stored) with MariaDB's error 1213; the resume writes it again, a fresh write raises it
    url = f"sqlite:///{tmp_path / 'dead.db'}"
    records = random_records(40, size=8, seed=3)
    original = PairQueries._insert_batch
    calls = []

    def deadlock_once(self, run_id, recs, lo, hi):
        calls.append((lo, hi))
        if len(calls) == 1:
            raise DeadlockError("database x: (1213, 'Deadlock found when trying to get lock')")
        return original(self, run_id, recs, lo, hi)

    monkeypatch.setattr(PairQueries, "_insert_batch", deadlock_once)
    with Store.open(url) as store:
        run_id = store.create_run("dead")
        assert store.write_pairs(run_id, records, batch_size=16, skip_stored=True) == 40
        np.testing.assert_array_equal(store.stored_indices(run_id), records.pair_index)
        calls.clear()
        fresh = store.create_run("fresh")
        with pytest.raises(DeadlockError):
            store.write_pairs(fresh, records, batch_size=16, skip_stored=False)
        calls.clear()
        again = store.create_run("again")
        with pytest.raises(DeadlockError):  # retries used up
            store.write_pairs(again, records, batch_size=16, skip_stored=True, deadlock_retries=0)


def test_deadlocks_are_told_apart_from_other_faults():
    class MySQLError(Exception):
        pass

    class PgError(Exception):
        sqlstate = "40P01"

    def wrapped(orig):
        return sa.exc.OperationalError("INSERT ...", {}, orig)

    assert is_deadlock(wrapped(MySQLError(1213, "Deadlock found")))
    assert is_deadlock(wrapped(PgError("deadlock detected")))
    assert not is_deadlock(wrapped(MySQLError(1205, "Lock wait timeout exceeded")))
    assert not is_deadlock(wrapped(MySQLError("disk full")))


@contextlib.contextmanager
def pause_creator_at(statement: str, nth: int = 1) -> Iterator[tuple[threading.Event, threading.Event]]:
    """For the block, make the thread that runs the `nth` statement starting with `statement` (it creates the tables)
    wait there until another thread is about to take the schema lock, or the test says the other thread's open is
    over. Yields (paused, released): paused is set once the creator waits, released lets it go. What the creator did
    before `statement` is visible where DDL commits itself (MariaDB), so the other open meets a database half made,
    every time."""
    paused, released = threading.Event(), threading.Event()
    seen: dict = {"n": 0, "creator": None}
    test_thread = threading.get_ident()

    def before(conn, cursor, text, parameters, context, executemany):
        text, me = text.lstrip().upper(), threading.get_ident()
        if not ours(test_thread):
            return
        if seen["creator"] not in (None, me) and any(s in text for s in LOCK_STATEMENTS):
            released.set()  # the other open waits for the creator's lock: let the creator finish
        elif text.startswith(statement) and seen["creator"] in (None, me):
            seen["n"] += 1
            if seen["n"] == nth:
                seen["creator"] = me
                paused.set()
                assert released.wait(timeout=30), "the other open neither ended nor took the lock"

    sa.event.listen(sa.engine.Engine, "before_cursor_execute", before)
    try:
        yield paused, released
    finally:
        released.set()
        sa.event.remove(sa.engine.Engine, "before_cursor_execute", before)


def outcome(work):
    """`work()`, or the exception it raised (reported to the test, which fails on it)."""
    try:
        return work()
    except Exception as exc:
        return exc


@pytest.mark.parametrize(("statement", "nth"), [("INSERT INTO", 1), ("CREATE TABLE", 2)], ids=["no-version", "half"])
def test_an_open_of_a_database_another_process_is_creating_waits_for_it(db_url, statement, nth):
    # MariaDB commits each CREATE TABLE: an open that met the creator's tables before its schema version refused the
    # database ("schema version None, this vinadv needs '7'"); it waits for the creator's lock and checks again now
    def use(name: str):
        with Store.open(db_url) as store:
            return store.create_run(name)

    first: list = [None]
    with pause_creator_at(statement, nth) as (paused, released):
        creator = threading.Thread(
            target=lambda: first.__setitem__(0, outcome(lambda: use("first"))), name=f"{TEST_THREAD}-creator"
        )
        creator.start()
        assert paused.wait(timeout=30), "the creator never reached the statement"
        second = outcome(lambda: use("second"))
        released.set()
        creator.join(timeout=60)
    assert isinstance(first[0], int) and isinstance(second, int), (first, second)
    assert columns_and_version(db_url)[1] == SCHEMA_VERSION
    with Store.open(db_url, readonly=True) as store:
        assert sorted(r["name"] for r in store.list_runs(with_counts=False)) == ["first", "second"]
