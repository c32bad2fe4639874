"""`vinadv export` (src/vinadv/commands/store.py): csv / jsonl / npz of a stored run, and exit status 2 on bad
databases."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import sqlalchemy as sa

from tests.store.oracle import map_text, path_text
from tests.store.test_store_db import HARM_FLOATS
from vinadv.cli import main
from vinadv.store import Store
from vinadv.testing.store import random_records


@pytest.fixture(scope="module")
def stored(module_db_url):
    """A run of 40 pairs, stored once per module and backend: the export tests only read it."""
    db_url = module_db_url
    records = random_records(40, size=7, seed=11, effort=True)
    with Store.open(db_url) as store:
        run_id = store.create_run("exported", attack="near-path")
        store.write_pairs(run_id, records)
    return db_url, run_id, records


def test_export_csv_matches_oracle(stored, tmp_path):
    url, run_id, records = stored
    out = tmp_path / "pairs.csv"
    assert main(["export", "--db", url, "--run", str(run_id), "--format", "csv", "--out", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert [int(r["pair_index"]) for r in rows] == list(range(40))
    # the format's columns, in order (vinadv.labelled_pairs/1: Table 2's first; one-obstacle readers rely on it)
    header = "no map_o map_a path_o path_a label attack run_id pair_index start goal added_obstacle label_source score"
    header += " term_o term_a dh dv opt_cost_o opt_cost_a cost_o cost_a regret_o regret_a expert_label harm added_more"
    header += " edit expanded_o expanded_a astar_expansions_o astar_expansions_a"
    header += " expansions_o expansions_a effort_ratio astar_effort_ratio relative_effort effort_harmful"
    assert list(rows[0]) == header.split()
    paths_a = records.path_a.unpack()
    for i, row in enumerate(rows):
        assert row["map_o"] == map_text(records.obstacles_o[i])
        assert row["map_a"] == map_text(records.obstacles_a[i])
        assert row["path_a"] == path_text(paths_a[i])
        assert row["label"] == records.label[i] and row["attack"] == str(int(records.attack[i]))
        assert row["score"] == ("" if np.isnan(records.score[i]) else repr(float(records.score[i])))
        for name in HARM_FLOATS:
            value = getattr(records, name)[i]
            assert row[name] == ("" if np.isnan(value) else repr(float(value))), name
        assert row["harm"] == (records.harm[i] or "") and row["expert_label"] == (records.expert_label[i] or "")
        counts = [len(getattr(records, f"expanded_{side}")[i]) for side in ("o", "a")]
        astar = [int(getattr(records, f"astar_expansions_{side}")[i]) for side in ("o", "a")]
        assert [row["expansions_o"], row["expansions_a"]] == [str(c) if c else "" for c in counts]
        assert [row["astar_expansions_o"], row["astar_expansions_a"]] == [str(c) if c > 0 else "" for c in astar]
        known = min(counts) > 0 and min(astar) > 0
        relative = counts[1] / counts[0] / (astar[1] / astar[0]) if known else None
        harmful = known and records.term_o[i] == "goal" and counts[1] > counts[0] and relative > 2
        assert row["effort_harmful"] == ("" if not known or records.term_o[i] != "goal" else str(int(harmful)))


def test_export_jsonl_successful_only_by_run_name(stored, capsys):
    url, run_id, records = stored
    assert main(["export", "--db", url, "--run", "exported", "--format", "jsonl", "--successful-only", "--quiet"]) == 0
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [d["pair_index"] for d in lines] == np.flatnonzero(records.attack).tolist()
    assert all(d["attack"] is True and d["label"] in ("UrP", "FP") and d["run_id"] == run_id for d in lines)
    chosen = records.take(records.attack)
    assert [d["harm"] for d in lines] == chosen.harm.tolist()  # None = null
    assert [d["regret_a"] for d in lines] == [None if np.isnan(v) else v for v in chosen.regret_a.tolist()]


def test_export_npz_round_trips(stored, tmp_path):
    url, run_id, records = stored
    out = tmp_path / "pairs.npz"
    assert main(["export", "--db", url, "--run", str(run_id), "--format", "npz", "--out", str(out), "--quiet"]) == 0
    with np.load(out) as data:
        assert str(data["format"]) == "vinadv.labelled_pairs/1" and str(data["strategy"]) == "near-path"
        assert str(data["moves"]) == "octile"  # the run's movement model
        for name in ("obstacles_o", "obstacles_a", "starts", "goals", "attack", "dh", "dv", "pair_index"):
            assert np.array_equal(data[name], getattr(records, name)), name
        assert np.array_equal(data["added"], records.added[:, 0])  # one obstacle per pair: (n, 2), as ever
        for side in ("o", "a"):
            paths = getattr(records, f"path_{side}")
            assert np.array_equal(data[f"path_{side}_cells"], paths.cells)
            assert np.array_equal(data[f"path_{side}_offsets"], paths.offsets)
        assert data["label"].tolist() == records.label.tolist()
        assert np.array_equal(data["score"], records.score, equal_nan=True)
        for name in HARM_FLOATS:
            assert np.array_equal(data[name], getattr(records, name), equal_nan=True), name
        assert data["harm"].tolist() == [h or "" for h in records.harm]
        assert data["expert_label"].tolist() == [h or "" for h in records.expert_label]


def test_export_keeps_every_added_obstacle(sqlite_url, tmp_path, capsys):
    records = random_records(12, size=7, seed=4, n_added=3)
    with Store.open(sqlite_url) as store:
        run_id = store.create_run("three")
        store.write_pairs(run_id, records)
    out = tmp_path / "three.npz"
    assert main(["export", "--db", sqlite_url, "--run", "three", "--format", "npz", "--out", str(out), "--quiet"]) == 0
    with np.load(out) as data:
        assert np.array_equal(data["added"], records.added) and data["added"].shape == (12, 3, 2)
    assert main(["export", "--db", sqlite_url, "--run", "three", "--format", "csv", "--quiet"]) == 0
    rows = list(csv.DictReader(capsys.readouterr().out.splitlines()))
    for row, cells in zip(rows, records.added.tolist()):  # the first cell as ever, the others in added_more
        assert row["added_obstacle"] == "{},{}".format(*cells[0])
        assert row["added_more"] == ";".join("{},{}".format(*c) for c in cells[1:])


def test_export_errors_exit_2(tmp_path, capsys, sqlite_url):
    assert main(["export", "--db", str(tmp_path / "absent.db"), "--run", "1"]) == 2
    assert "no such file" in capsys.readouterr().err
    assert not (tmp_path / "absent.db").exists()
    assert main(["export", "--db", "mysql+pymysql://root:pw@127.0.0.1:1/test", "--run", "1"]) == 2
    err = capsys.readouterr().err
    assert "cannot connect" in err and "127.0.0.1:1" in err and ":pw@" not in err
    with Store.open(sqlite_url):
        pass
    assert main(["export", "--db", sqlite_url, "--run", "5"]) == 2
    assert "no run 5" in capsys.readouterr().err
    assert main(["export", "--db", sqlite_url, "--run", "1", "--format", "npz"]) == 2


def test_export_of_a_foreign_database_exit_2_untouched(db_url, capsys):
    engine = sa.create_engine(db_url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        conn.execute(sa.text("CREATE TABLE runs (id INTEGER PRIMARY KEY, who VARCHAR(10))"))
        conn.execute(sa.text("INSERT INTO runs VALUES (1, 'them')"))
    assert main(["export", "--db", db_url, "--run", "1", "--quiet"]) == 2
    assert "not a vinadv database" in capsys.readouterr().err
    with engine.connect() as conn:
        assert sa.inspect(conn).get_table_names() == ["runs"]
        assert conn.execute(sa.text("SELECT * FROM runs")).all() == [(1, "them")]
    engine.dispose()
