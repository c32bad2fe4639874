"""Two writers at once, made to meet where they used to collide by a barrier (deterministic, not by timing): two
resumes of one run that both read "nothing stored yet" before either writes, and two first uses of one new
database that both find it empty before either creates the tables. Both finish, and everything is stored once."""

from __future__ import annotations

import threading

import numpy as np
import sqlalchemy as sa

from vinadv.store import Store
from vinadv.store.pairs import PairQueries
from vinadv.testing.store import random_records


def meet_after_first_call(monkeypatch, owner, name: str, when=lambda result: True):
    """Make the first call of `owner.name` in each of two threads wait, once it has its result, until the other
    thread's first call has one too (when `when(result)`): both act on what they read before either writes."""
    barrier = threading.Barrier(2, timeout=30)
    seen = threading.local()
    original = getattr(owner, name)

    def meeting(*args, **kw):
        result = original(*args, **kw)
        if not getattr(seen, "done", False) and when(result):
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

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
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
