"""`vinadv export --format parquet` and `vinadv.open` (src/vinadv/analysis.py): the Parquet file read back with pyarrow
and with pandas equals the database's own rows (read by plain SQL and parsed by the oracle, not by vinadv's codec),
nullable columns and several added obstacles included; the API's DataFrames equal what the store reads; `iter_pairs`
batches hold every pair once."""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import sqlalchemy as sa

import vinadv
from tests.store.oracle import parse_map, parse_path
from vinadv.analysis import (
    PAIR_COLUMNS,
    PARQUET_FORMAT,
    ROBUSTNESS_COLUMNS,
    cells,
    grid,
    pair_schema,
    parquet_metadata,
    read_parquet,
    write_parquet,
)
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.intervals import rate_interval
from vinadv.plot.curves import k_series
from vinadv.store import Store
from vinadv.store.schema import HARM_FLOAT_COLUMNS, map_pairs
from vinadv.testing.store import random_records

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "analysis.md"
NULLABLE_FLOATS = ("score", *HARM_FLOAT_COLUMNS)
NULLABLE_STRINGS = ("expert_label", "harm")
EFFORT = ("expanded_o", "expanded_a", "expansions_o", "expansions_a", "astar_expansions_o", "astar_expansions_a")
EFFORT += ("effort_ratio", "astar_effort_ratio", "relative_effort", "effort_harmful")


@pytest.fixture(scope="module")
def stored(module_db_url):
    """Two runs: 'one' (40 pairs of one added obstacle, config stored) and 'three' (23 pairs of three cells, some
    added, some freed: edit `remove`); stored once per module and backend: the tests only read them."""
    db_url = module_db_url
    with Store.open(db_url) as store:
        one = store.create_run("one", config={"n": 40, "size": 7, "attack": "near-path"}, seed=5, attack="near-path")
        store.write_pairs(one, random_records(40, size=7, seed=11))
        three = store.create_run("three", attack="greedy")
        # with the search effort (NULL where not reported)
        store.write_pairs(three, random_records(23, size=6, seed=3, n_added=3, removes=0.4, effort=True))
    return db_url, {"one": one, "three": three}


def database_rows(url: str, run_id: int) -> list[dict]:
    """The run's `map_pairs` rows as the database holds them (plain SQL, no vinadv codec), in pair-index order."""
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    try:
        with engine.connect() as conn:
            c = map_pairs.c
            query = sa.select(map_pairs).where(c.run_id == run_id).order_by(c.pair_index)
            return [dict(r) for r in conn.execute(query).mappings()]
    finally:
        engine.dispose()


def cell_text(cell) -> str:
    return "{},{}".format(*(int(v) for v in cell))


def check_row(row: dict, db: dict) -> None:
    """A pair read back from Parquet (`row`: plain Python values, null as None) against the database's row."""
    for name in ("no", "run_id", "pair_index", "label", "label_source", "term_o", "term_a", *NULLABLE_STRINGS):
        assert row[name] == db[name], name
    assert row["attack"] is bool(db["attack"])
    for name in (*NULLABLE_FLOATS, "dh", "dv"):
        assert row[name] == db[name] and (row[name] is None) == (db[name] is None), name
    assert [[bool(c) for c in r] for r in row["map_o"]] == parse_map(db["map_o"])
    assert [[bool(c) for c in r] for r in row["map_a"]] == parse_map(db["map_a"])
    for side in ("o", "a"):
        assert [tuple(int(v) for v in c) for c in row[f"path_{side}"]] == parse_path(db[f"path_{side}"])
    assert cell_text(row["start"]) == db["start"] and cell_text(row["goal"]) == db["goal"]
    assert row["edit"] == (db["edit"] or "add")  # NULL: a database before schema 7, additions only
    assert cell_text(row["added"][0]) == db["added_obstacle"]
    more = [tuple(int(v) for v in c) for c in row["added"][1:]]
    assert more == (parse_path(db["added_more"]) if db["added_more"] is not None else [])
    check_effort(row, db)


def check_effort(row: dict, db: dict) -> None:
    """The search-effort columns against the database's text, by the definition (DESIGN.md "Search effort")."""
    counts = {}
    for side in ("o", "a"):
        expanded = None if db[f"expanded_{side}"] is None else parse_path(db[f"expanded_{side}"])
        got = row[f"expanded_{side}"]
        assert (None if got is None else [tuple(int(v) for v in c) for c in got]) == expanded
        counts[side] = None if expanded is None else len(expanded)
        assert row[f"expansions_{side}"] == counts[side]
        assert row[f"astar_expansions_{side}"] == db[f"astar_expansions_{side}"]
    e_o, e_a, a_o, a_a = counts["o"], counts["a"], db["astar_expansions_o"], db["astar_expansions_a"]
    if None in (e_o, e_a, a_o, a_a):
        assert row["relative_effort"] is None and row["effort_harmful"] is None
        return
    assert row["effort_ratio"] == pytest.approx(e_a / e_o) and row["astar_effort_ratio"] == pytest.approx(a_a / a_o)
    relative = (e_a / e_o) / (a_a / a_o)
    assert row["relative_effort"] == pytest.approx(relative)
    harmful = None if db["term_o"] != "goal" else (e_a > e_o and relative > 2)
    assert row["effort_harmful"] == harmful


def export(url: str, run: str, out, *extra: str) -> int:
    return main(["export", "--db", url, "--run", run, "--format", "parquet", "--out", str(out), "--quiet", *extra])


def test_parquet_read_with_pyarrow_equals_the_database(stored, tmp_path):
    url, ids = stored
    for name, run_id in ids.items():
        out = tmp_path / f"{name}.parquet"
        assert export(url, name, out) == 0
        table = pq.read_table(out)
        assert table.schema.equals(pair_schema(), check_metadata=False)
        rows, db = table.to_pylist(), database_rows(url, run_id)
        assert len(rows) == len(db) > 0
        for row, db_row in zip(rows, db):
            check_row(row, db_row)
        # the nullable columns do hold NULLs here, and none of the others may
        assert all(table[c].null_count > 0 for c in (*NULLABLE_FLOATS, *NULLABLE_STRINGS, "dh", "dv"))
        # run 'one' has no search effort (a planner without expansions): every effort column null
        nullable = {*NULLABLE_FLOATS, *NULLABLE_STRINGS, "dh", "dv", *EFFORT}
        assert {f.name for f in table.schema if f.nullable} == nullable
        if name == "one":
            assert all(table[c].null_count == len(rows) for c in EFFORT)
        else:  # some pairs are effort-harmful, others not
            assert {True, False} <= set(table["effort_harmful"].to_pylist())
    assert {len(r["added"]) for r in pq.read_table(tmp_path / "three.parquet").to_pylist()} == {3}
    assert set(pq.read_table(tmp_path / "three.parquet")["edit"].to_pylist()) == {"add", "remove"}


def test_parquet_read_with_pandas_equals_the_database_and_the_api(stored, tmp_path):
    url, ids = stored
    out = tmp_path / "three.parquet"
    assert export(url, "three", out) == 0
    frame = pd.read_parquet(out)
    assert list(frame.columns) == list(PAIR_COLUMNS)
    db = database_rows(url, ids["three"])
    assert frame["pair_index"].tolist() == [r["pair_index"] for r in db]
    for name in (*NULLABLE_FLOATS, "dh", "dv"):  # NULL reads as NaN in pandas
        expected = [math.nan if r[name] is None else float(r[name]) for r in db]
        assert np.array_equal(frame[name].to_numpy(dtype=float), expected, equal_nan=True), name
    for name in NULLABLE_STRINGS:
        assert [None if pd.isna(v) else v for v in frame[name]] == [r[name] for r in db], name
    assert frame["attack"].dtype == bool and frame["attack"].tolist() == [bool(r["attack"]) for r in db]
    for i, r in enumerate(db):
        assert grid(frame["map_a"][i]).tolist() == parse_map(r["map_a"])
        assert [tuple(c) for c in cells(frame["path_o"][i]).tolist()] == parse_path(r["path_o"])
        assert cells(frame["added"][i]).shape == (3, 2)
    with vinadv.open(url) as results:
        pairs = results.pairs("three")
    # vinadv's own reader gives the API's DataFrame (the list columns kept as Arrow arrays), with the same values
    read = read_parquet(out)
    pd.testing.assert_frame_equal(read, pairs)
    assert read.attrs == pairs.attrs and read.attrs["vinadv"]["run"]["id"] == ids["three"]
    assert isinstance(read["path_o"].dtype, pd.ArrowDtype)
    for i in range(len(frame)):
        assert np.array_equal(grid(frame["map_o"][i]), grid(read["map_o"][i]))
        for name in ("path_a", "added"):
            assert np.array_equal(cells(frame[name][i]), cells(read[name][i])), name
        assert np.array_equal(cells([frame["start"][i]]), cells([read["start"][i]]))


def test_parquet_metadata_holds_the_run_and_its_config(stored, tmp_path):
    url, ids = stored
    out = tmp_path / "one.parquet"
    assert export(url, str(ids["one"]), out, "--successful-only") == 0
    meta = parquet_metadata(out)
    assert meta["format"] == PARQUET_FORMAT and meta["size"] == 7 and meta["successful_only"] is True
    assert meta["run"]["id"] == ids["one"] and meta["run"]["name"] == "one" and meta["run"]["seed"] == 5
    assert meta["run"]["config"] == {"n": 40, "size": 7, "attack": "near-path"}
    assert json.loads(pq.read_schema(out).metadata[b"vinadv"]) == meta  # what a plain pyarrow reader sees
    table = pq.read_table(out)
    expected = [r["pair_index"] for r in database_rows(url, ids["one"]) if r["attack"]]
    assert table["pair_index"].to_pylist() == expected and 0 < len(expected) < 40
    with vinadv.open(url) as results:  # the API's export is the command's
        assert results.to_parquet(tmp_path / "api.parquet", "one", successful_only=True) == len(expected)
    assert pq.read_table(tmp_path / "api.parquet").equals(table, check_metadata=True)


def test_export_writes_a_row_group_per_batch_and_an_empty_run_as_its_schema(sqlite_url, tmp_path):
    with Store.open(sqlite_url) as store:
        run_id = store.create_run("r")
        store.write_pairs(run_id, random_records(37, size=5, seed=2))
        empty = store.create_run("empty")
        seen = []
        assert write_parquet(store, run_id, tmp_path / "r.parquet", batch_size=10, progress=seen.append) == 37
        assert write_parquet(store, empty, tmp_path / "e.parquet") == 0
    assert seen == [10, 10, 10, 7]
    assert pq.ParquetFile(tmp_path / "r.parquet").metadata.num_row_groups == 4
    assert pq.read_table(tmp_path / "r.parquet")["pair_index"].to_pylist() == list(range(37))
    read = pq.read_table(tmp_path / "e.parquet")
    assert read.num_rows == 0 and read.schema.equals(pair_schema(), check_metadata=False)
    assert parquet_metadata(tmp_path / "e.parquet")["size"] is None


def test_parquet_export_errors(sqlite_url, tmp_path, capsys):
    with Store.open(sqlite_url) as store:
        store.create_run("r")
    assert main(["export", "--db", sqlite_url, "--run", "r", "--format", "parquet"]) == 2
    assert "--out" in capsys.readouterr().err
    pq.write_table(pa.table({"x": [1]}), tmp_path / "other.parquet")
    with pytest.raises(InputError, match="not a Parquet file vinadv exported"):
        parquet_metadata(tmp_path / "other.parquet")


def test_api_dataframes_equal_the_store(stored):
    url, ids = stored
    with Store.open(url) as store:
        listed = store.list_runs()
        records = store.read_pairs(ids["three"])
    with vinadv.open(url) as results:
        runs = results.runs()
        pairs = results.pairs("three")
        latest = results.pairs()
    assert runs["run_id"].tolist() == [r["id"] for r in listed]
    assert runs["n_pairs"].tolist() == [40, 23] and runs["name"].tolist() == ["one", "three"]
    assert runs["config"][0] == {"n": 40, "size": 7, "attack": "near-path"}
    pd.testing.assert_frame_equal(latest, pairs)  # no run named: the latest
    assert pairs.attrs["vinadv"]["run"]["id"] == ids["three"]
    assert np.array_equal(pairs["no"], records.no) and np.array_equal(pairs["pair_index"], records.pair_index)
    assert pairs["label"].tolist() == records.label.tolist()
    assert np.array_equal(pairs["score"], records.score, equal_nan=True)
    assert np.array_equal(pairs["dh"], np.where(records.dh < 0, np.nan, records.dh), equal_nan=True)
    for name in HARM_FLOAT_COLUMNS:
        assert np.array_equal(pairs[name], getattr(records, name), equal_nan=True), name
    assert [None if pd.isna(v) else v for v in pairs["harm"]] == records.harm.tolist()
    assert np.array_equal(np.stack([grid(v) for v in pairs["map_o"]]), records.obstacles_o)
    assert np.array_equal(np.stack([cells(v) for v in pairs["added"]]), records.added)
    assert np.array_equal(np.stack([cells([v]) for v in pairs["start"]])[:, 0], records.starts)
    for i, path in enumerate(records.path_a.unpack()):
        assert np.array_equal(cells(pairs["path_a"][i]), path)


@pytest.mark.parametrize("batch_size", [1, 7, 40, 1000])
def test_iter_pairs_batches_cover_every_pair_once(stored, batch_size):
    url, ids = stored
    with vinadv.open(url) as results:
        batches = list(results.iter_pairs("one", batch_size=batch_size))
        successful = pd.concat(results.iter_pairs("one", batch_size=batch_size, successful_only=True))
        whole = results.pairs("one")
    assert [len(b) for b in batches[:-1]] == [batch_size] * (len(batches) - 1) and 0 < len(batches[-1]) <= batch_size
    joined = pd.concat(batches, ignore_index=True)
    assert joined["pair_index"].tolist() == list(range(40))
    pd.testing.assert_frame_equal(joined, whole)
    assert successful["pair_index"].tolist() == whole["pair_index"][whole["attack"]].tolist()


def test_api_refuses_what_it_cannot_read(sqlite_url):
    with Store.open(sqlite_url):
        pass
    with vinadv.open(sqlite_url) as results:
        with pytest.raises(InputError, match="holds no run"):
            results.pairs()
        with pytest.raises(InputError, match="no run named 'nope'"):
            results.pairs("nope")
        with pytest.raises(InputError, match="batch_size"):
            results.iter_pairs(batch_size=0)
        assert results.runs().empty and list(results.robustness().columns) == list(ROBUSTNESS_COLUMNS)


def figures(k: int, valid: int, harmful: int) -> dict:
    """One `Figures.to_dict()` as the robustness benchmark stores it (without intervals: readers compute them)."""
    return {
        "k": k,
        "maps": 10,
        "attacked": 9,
        "valid": valid,
        "broken": harmful // 2,
        "paper_success_rate": (harmful // 2) / valid if valid else None,
        "harmful": harmful,
        "harmful_rate": harmful / valid if valid else None,
        "reached": valid - harmful,
        "mean_regret": 0.5 * k if valid else None,
    }


def test_robustness_is_one_row_per_benchmark_strategy_and_k(sqlite_url):
    settings = {"n": 10, "size": 8, "maps_seed": 1000, "objective": "harm", "strategies": ["random", "near-path"]}
    result = {
        "clean": {"maps": 10, "reached": 9, "success_rate": 0.9, "mean_regret": 0.25},
        "strategies": {
            "random": {"name": "random", "seconds": 1.5, "planner_calls": 3, "by_obstacles": [figures(1, 9, 2)]},
            "near-path": {"name": "near-path", "seconds": 2.0, "planner_calls": 4, "by_obstacles": [figures(1, 9, 4)]},
        },
        "overall": [figures(1, 9, 5)],
        "seconds": 4.0,
    }
    with Store.open(sqlite_url) as store:
        first = store.add_robustness("vin", "ab" * 32, settings, result)
        second = store.add_robustness("optimal", None, {**settings, "size": 12}, {**result, "overall": []})
    with vinadv.open(sqlite_url) as results:
        frame = results.robustness()
    assert list(frame.columns) == list(ROBUSTNESS_COLUMNS)
    assert frame["benchmark"].tolist() == [first] * 3 + [second] * 2
    assert frame["strategy"].tolist() == ["random", "near-path", "worst case", "random", "near-path"]
    worst = frame[(frame["benchmark"] == first) & (frame["strategy"] == "worst case")].iloc[0]
    assert worst["harmful"] == 5 and worst["harmful_rate"] == 5 / 9 and worst["seconds"] == 4.0
    assert worst["planner"] == "vin" and worst["clean_success"] == 0.9 and worst["size"] == 8
    assert frame["seconds"].tolist()[:2] == [1.5, 2.0] and frame["size"].tolist()[3:] == [12, 12]
    # each rate's Wilson 95% interval, computed from the counts (this stored result holds none)
    assert (worst["harmful_rate_low"], worst["harmful_rate_high"]) == rate_interval(5, 9)
    assert (worst["paper_success_rate_low"], worst["paper_success_rate_high"]) == rate_interval(2, 9)
    assert (worst["clean_success_low"], worst["clean_success_high"]) == rate_interval(9, 10)
    assert (frame["harmful_rate_low"] <= frame["harmful_rate"]).all()
    assert (frame["harmful_rate"] <= frame["harmful_rate_high"]).all()
    # a mean regret's bootstrap interval is as stored: none in this one, stored before them
    assert worst[["mean_regret_low", "clean_regret_low"]].isna().all()
    # and the k curve draws them as bands, as it draws `{rate}_low` / `{rate}_high` points
    series = dict(k_series(frame))
    assert series["vin"][0]["harmful_rate_low"] == rate_interval(5, 9)[0]


def test_import_vinadv_stays_light(sqlite_url):
    # `vinadv.open` imports vinadv.analysis when called: the package itself brings no NumPy, pandas, pyarrow or
    # SQLAlchemy
    code = "import sys, vinadv; print(sorted(set(sys.modules) & {'numpy', 'pandas', 'pyarrow', 'sqlalchemy'}))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert done.stdout.strip() == "[]"
    with Store.open(sqlite_url) as store:
        store.create_run("r")
    with vinadv.open(sqlite_url) as results:
        assert isinstance(results, vinadv.analysis.Results) and results.runs()["name"].tolist() == ["r"]


@pytest.mark.slow  # a run of 200 maps with the shipped VIN: seconds
def test_the_guides_python_tour_runs_as_written():
    # docs/guide/analysis.md's one Python block, exactly as written there: a small run, its DataFrames, the export
    (code,) = re.findall(r"```python\n(.*?)```", GUIDE.read_text(encoding="utf-8"), flags=re.S)
    namespace: dict = {}
    with contextlib.redirect_stdout(io.StringIO()) as out:
        exec(compile(code, str(GUIDE), "exec"), namespace)
    pairs = namespace["pairs"]
    assert len(pairs) > 0 and namespace["runs"]["n_pairs"].tolist() == [len(pairs)]
    assert "near-path" in out.getvalue() and "(28, 28)" in out.getvalue()


@pytest.mark.parametrize("url", [123, 1.5, b"x.db", ["x.db"]])
def test_open_refuses_what_is_not_a_url_or_a_path_in_one_line(url):
    with pytest.raises(InputError, match=r"^url: vinadv.open takes a database URL or a SQLite file") as caught:
        vinadv.open(url)
    assert "\n" not in str(caught.value) and caught.value.parameters == ("url",)


def test_open_takes_a_path_object(tmp_path):
    with Store.open(str(tmp_path / "r.db")) as store:
        store.create_run("p")
    with vinadv.open(tmp_path / "r.db") as db:
        assert len(db.runs()) == 1


def test_a_mean_regrets_bootstrap_interval_is_read_as_stored(sqlite_url):
    settings = {"n": 10, "size": 8, "maps_seed": 1000, "objective": "harm", "strategies": ["random"]}
    one = {**figures(1, 9, 2), "mean_regret_low": 0.25, "mean_regret_high": 0.75}
    result = {
        "clean": {
            "maps": 10,
            "reached": 9,
            "success_rate": 0.9,
            "mean_regret": 0.0,
            "mean_regret_low": -0.1,
            "mean_regret_high": 0.1,
        },
        "strategies": {"random": {"name": "random", "seconds": 1.0, "planner_calls": 3, "by_obstacles": [one]}},
        "overall": [one],
        "seconds": 1.0,
    }
    with Store.open(sqlite_url) as store:
        store.add_robustness("vin", "ab" * 32, settings, result)
    with vinadv.open(sqlite_url) as results:
        row = results.robustness().iloc[0]
    assert (row["mean_regret_low"], row["mean_regret_high"]) == (0.25, 0.75)
    assert (row["clean_regret_low"], row["clean_regret_high"]) == (-0.1, 0.1)
