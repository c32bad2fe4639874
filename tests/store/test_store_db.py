"""Store against real databases: SQLite, MariaDB and PostgreSQL (fresh database/schema per test)."""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
import time
from dataclasses import fields

import numpy as np
import pytest
import sqlalchemy as sa

from tests.fault_files import killed_at_exit
from tests.store.oracle import map_text, path_text
from vinadv.errors import InputError
from vinadv.store import LABELS, PairRecords, Store, resolve_url, schema
from vinadv.testing.store import random_records

HARM_FLOATS = ("opt_cost_o", "opt_cost_a", "cost_o", "cost_a", "regret_o", "regret_a")


def _oracle_rows(run_id: int, records: PairRecords) -> list[tuple]:
    """What the map_pairs rows must hold, built one cell at a time in plain Python."""
    paths_o = records.path_o.unpack()
    paths_a = records.path_a.unpack()
    rows = []
    for i in range(len(records)):
        score = float(records.score[i])
        rows.append(
            (
                run_id,
                int(records.pair_index[i]),
                map_text(records.obstacles_o[i]),
                map_text(records.obstacles_a[i]),
                path_text(paths_o[i]),
                path_text(paths_a[i]),
                str(records.label[i]),
                bool(records.attack[i]),
                "{},{}".format(*records.starts[i]),
                "{},{}".format(*records.goals[i]),
                "{},{}".format(*records.added[i, 0]),
                str(records.label_source[i]),
                None if np.isnan(score) else score,
                str(records.term_o[i]),
                str(records.term_a[i]),
                None if records.dh[i] < 0 else int(records.dh[i]),
                None if records.dv[i] < 0 else int(records.dv[i]),
                *[None if math.isnan(getattr(records, c)[i]) else float(getattr(records, c)[i]) for c in HARM_FLOATS],
                records.expert_label[i],
                records.harm[i],
                ";".join("{},{}".format(*c) for c in records.added[i, 1:].tolist()) or None,  # NULL: one obstacle
                str(records.edit[i]),
                *[_expanded_text(getattr(records, f"expanded_{side}"), i) for side in ("o", "a")],
                *[_count(getattr(records, f"astar_expansions_{side}"), i) for side in ("o", "a")],
            )
        )
    return sorted(rows, key=lambda r: r[1])


def _expanded_text(expanded, i: int) -> str | None:
    """Pair i's expanded cells as the oracle writes them: path text, None (NULL) where none are reported."""
    return None if expanded is None or not len(expanded[i]) else path_text(expanded[i])


def _count(counts, i: int) -> int | None:
    return None if counts is None or counts[i] < 1 else int(counts[i])


def _raw_rows(url: str) -> list[tuple]:
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    cols = (
        "run_id pair_index map_o map_a path_o path_a label attack start goal added_obstacle label_source "
        "score term_o term_a dh dv"
    ).split() + [*HARM_FLOATS, "expert_label", "harm", "added_more", "edit", *schema.EFFORT_COLUMNS]
    with engine.connect() as conn:
        table = schema.map_pairs  # not reflected: a reflected MySQL DOUBLE reads back as a 10-digit Decimal
        rows = conn.execute(sa.select(*[table.c[c] for c in cols]).order_by(table.c.pair_index)).all()
    engine.dispose()
    return [tuple(bool(v) if c == "attack" else v for c, v in zip(cols, row)) for row in rows]


def test_write_read_round_trip_matches_oracle(db_url):
    records = random_records(300, size=11, seed=1, effort=True)  # the search effort too: NULL where not reported
    with Store.open(db_url) as store:
        run_id = store.create_run(
            "rt", config={"n": 300, "size": 11}, seed=7, attack="near-path", classifier="rule", weights_checksum="abc"
        )
        assert store.write_pairs(run_id, records, batch_size=128) == 300
        back = store.read_pairs(run_id)
        assert back.equals(records)
        assert sorted(back.no.tolist()) == back.no.tolist() and len(set(back.no.tolist())) == 300
        # counts per label and attack agree with NumPy on the records
        assert store.label_counts(run_id) == {lab: int((records.label == lab).sum()) for lab in LABELS}
        assert store.attack_counts(run_id) == {True: int(records.attack.sum()), False: int((~records.attack).sum())}
        successful = store.read_pairs(run_id, successful_only=True)
        assert successful.equals(records.take(records.attack))
        fp = store.read_pairs(run_id, labels=["FP"])
        assert fp.equals(records.take(records.label == "FP"))
        some = store.read_pairs(run_id, pair_indices=[5, 3, 250])
        assert some.pair_index.tolist() == [3, 5, 250]
        store.finish_run(run_id, timings={"plan": 1.5, "store": 0.25}, status="done")
        info = store.run_info(run_id)
        assert info["timings"] == {"plan": 1.5, "store": 0.25} and info["status"] == "done"
        assert info["config"] == {"n": 300, "size": 11} and info["seed"] == 7
        assert [r["n_pairs"] for r in store.list_runs()] == [300]
    assert _raw_rows(db_url) == _oracle_rows(run_id, records)


def test_backends_read_back_identical(sqlite_url, mysql_url, postgres_url):
    records = random_records(200, size=28, seed=2)
    read, raw = {}, {}
    for name, url in (("sqlite", sqlite_url), ("mysql", mysql_url), ("postgres", postgres_url)):
        with Store.open(url) as store:
            run_id = store.create_run("same")
            store.write_pairs(run_id, records, batch_size=64)
            read[name] = store.read_pairs(run_id)
        raw[name] = _raw_rows(url)
    for name in ("mysql", "postgres"):
        assert read[name].equals(read["sqlite"]), name
        assert np.array_equal(read[name].no, read["sqlite"].no), name
        assert raw[name] == raw["sqlite"], name
    assert read["sqlite"].equals(records)


def test_resume_skips_stored_pairs_and_rejects_duplicates(sqlite_url):
    records = random_records(100, size=8, seed=3)
    with Store.open(sqlite_url) as store:
        run_id = store.create_run("resume")
        store.write_pairs(run_id, records.take(np.arange(0, 100, 3)))
        assert store.find_run("resume") == run_id and store.find_run("nope") is None
        assert store.write_pairs(run_id, records) == 100 - 34
        assert np.array_equal(store.stored_indices(run_id), np.arange(100))
        assert store.read_pairs(run_id).equals(records)
        # without skipping, a stored pair is a unique-key violation and the whole batch is rolled back
        with pytest.raises(sa.exc.IntegrityError):
            store.write_pairs(run_id, records.take([0]), skip_stored=False)
        assert store.count_pairs(run_id) == 100


# the writer: a process of its own to be killed (`python -c`), and the resume, run in the test's process (`exec`)
_WRITER = textwrap.dedent("""
    import sys, time
    import numpy as np
    from vinadv.store import Store
    from vinadv.testing.store import random_records

    def write(url, n, pause):
        records = random_records(n, size=12, seed=5)
        records = records.take(np.random.default_rng(0).permutation(n))  # stored out of index order
        with Store.open(url) as store:
            run_id = store.find_run("killed") or store.create_run("killed")
            store.write_pairs(run_id, records, batch_size=50, progress=lambda k: time.sleep(pause))

    if __name__ == "__main__":
        write(sys.argv[1], int(sys.argv[2]), 0.02)
        print("finished")
""")


@pytest.mark.slow
def test_killed_writer_resumes_with_every_pair_exactly_once(db_url):
    n, batch = 2000, 50
    with Store.open(db_url) as store:  # create the schema up front so the child only writes
        pass
    argv = [sys.executable, "-c", _WRITER, db_url, str(n)]
    with killed_at_exit(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE) as child:
        with Store.open(db_url) as store:
            deadline = time.monotonic() + 120
            stored = 0
            while stored < 300 and time.monotonic() < deadline and child.poll() is None:
                run_id = store.find_run("killed")
                stored = store.count_pairs(run_id) if run_id else 0
                time.sleep(0.05)
        assert child.poll() is None, f"writer ended before it was killed: {child.communicate()}"
    with Store.open(db_url) as store:
        run_id = store.find_run("killed")
        partial = store.count_pairs(run_id)
        assert 300 <= partial < n
        assert partial % batch == 0  # whole batches only: a batch is all-or-nothing
    # resume: the same writer again, skipping what is stored (here: only the killed one needs a process of its own)
    writer: dict = {"__name__": "writer"}
    exec(compile(_WRITER, "writer", "exec"), writer)
    writer["write"](db_url, n, 0)
    with Store.open(db_url) as store:
        assert store.count_pairs(run_id) == n
        assert np.array_equal(store.stored_indices(run_id), np.arange(n))
        assert store.read_pairs(run_id).equals(random_records(n, size=12, seed=5))
        assert len(store.list_runs()) == 1


def _foreign_table(url: str) -> None:
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        conn.execute(sa.text("CREATE TABLE map_pairs (id INTEGER PRIMARY KEY, note VARCHAR(20))"))
        conn.execute(sa.text("INSERT INTO map_pairs (id, note) VALUES (1, 'keep me')"))
    engine.dispose()


def _tables_and_rows(url: str) -> tuple[list[str], list[tuple]]:
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.connect() as conn:
        names = sorted(sa.inspect(conn).get_table_names())
        rows = conn.execute(sa.text("SELECT * FROM map_pairs ORDER BY 1")).all()
    engine.dispose()
    return names, [tuple(r) for r in rows]


def test_foreign_schema_is_refused_and_left_untouched(db_url):
    _foreign_table(db_url)
    before = _tables_and_rows(db_url)
    with pytest.raises(InputError, match="not a vinadv database"):
        Store.open(db_url)
    assert _tables_and_rows(db_url) == before == (["map_pairs"], [(1, "keep me")])


def test_other_schema_version_is_refused_and_left_untouched(db_url):
    records = random_records(20, size=6, seed=4)
    with Store.open(db_url) as store:
        run_id = store.create_run("old")
        store.write_pairs(run_id, records)
    engine = sa.create_engine(db_url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        key = engine.dialect.identifier_preparer.quote("key")
        conn.execute(sa.text(f"UPDATE vinadv_meta SET value = '999' WHERE {key} = 'schema_version'"))
    engine.dispose()
    before = _tables_and_rows(db_url)
    with pytest.raises(InputError, match="schema version '999'"):
        Store.open(db_url)
    assert _tables_and_rows(db_url) == before


def test_missing_column_is_refused(sqlite_url):
    with Store.open(sqlite_url):
        pass
    engine = sa.create_engine(sqlite_url)
    with engine.begin() as conn:
        conn.execute(sa.text("ALTER TABLE map_pairs DROP COLUMN dv"))
    engine.dispose()
    with pytest.raises(InputError, match=r"map_pairs lacks columns \['dv'\]"):
        Store.open(sqlite_url)


@pytest.mark.parametrize(
    "url",
    [
        "mysql+pymysql://root:s3cret@127.0.0.1:1/test",
        "postgresql+psycopg://postgres:s3cret@127.0.0.1:1/test",
    ],
)
def test_unreachable_server_is_a_clear_error(url):
    with pytest.raises(InputError) as err:
        Store.open(url)
    message = str(err.value)
    assert "cannot connect" in message and "127.0.0.1:1" in message and "s3cret" not in message and "***" in message


def test_missing_sqlite_file_without_create(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        Store.open(str(tmp_path / "absent.db"), create=False)
    assert not (tmp_path / "absent.db").exists()


def test_url_resolution(tmp_path, monkeypatch):
    monkeypatch.delenv("VINADV_DB", raising=False)
    monkeypatch.chdir(tmp_path)
    assert resolve_url(None) == f"sqlite:///{tmp_path / 'vinadv.db'}"
    assert resolve_url("x/y.db") == f"sqlite:///{tmp_path / 'x' / 'y.db'}"
    monkeypatch.setenv("VINADV_DB", "postgresql+psycopg://u@h/db")
    assert resolve_url(None) == "postgresql+psycopg://u@h/db"
    assert resolve_url("mysql+pymysql://a@b/c") == "mysql+pymysql://a@b/c"


def test_annotations(db_url):
    with Store.open(db_url) as store:
        run_id = store.create_run("ann")
        store.write_pairs(run_id, random_records(5, size=6, seed=6))
        assert store.add_annotations(run_id, [1, 3], ["FP", "DP"], annotator="alice") == 2
        assert store.add_annotations(run_id, [1], "DP", annotator="bob") == 1
        got = [(a["pair_index"], a["label"], a["annotator"]) for a in store.read_annotations(run_id)]
        assert got == [(1, "FP", "alice"), (3, "DP", "alice"), (1, "DP", "bob")]
        with pytest.raises(InputError, match="'XP'"):
            store.add_annotations(run_id, [2], ["XP"], annotator="alice")


def test_records_validation_names_the_field():
    records = random_records(4, size=5, seed=0)
    with pytest.raises(InputError, match="label"):
        PairRecords(**{**_fields(records), "label": np.array(["UrP", "bad", "FP", "DP"])})
    with pytest.raises(InputError, match="starts"):
        PairRecords(**{**_fields(records), "starts": np.zeros((3, 2), int)})


def test_subset_and_concatenate_keep_paths():
    records = random_records(30, size=9, seed=8)
    idx = np.array([29, 0, 7, 7, 15])
    sub = records.take(idx)
    paths = records.path_o.unpack()
    assert [p.tolist() for p in sub.path_o.unpack()] == [paths[i].tolist() for i in idx]
    assert PairRecords.concat([records.take(np.arange(10)), records.take(np.arange(10, 30))]).equals(records)


def _fields(records: PairRecords) -> dict:
    return {f.name: getattr(records, f.name) for f in fields(records)}
