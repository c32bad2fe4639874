"""Run names are compared exactly on every backend (schema version 5; issue 37, case 2): names that differ in case,
accents, emoji or a trailing space are different runs, for `--resume`, `export --run` and the "already called"
check, on SQLite, PostgreSQL and MariaDB (whose default collation ignores case and accents and treats every emoji
as one). The oracle is Python's `==` on the names. A version-4 MariaDB database is upgraded in place, its rows kept,
and an upgrade cut short is finished by the next open."""

from __future__ import annotations

import csv

import numpy as np
import sqlalchemy as sa

from tests.store.old_schemas import (
    LATER_COLUMNS,
    columns_and_version,
    old_database,
    run_name_collation,
    version_1_database,
)
from vinadv.cli import main
from vinadv.store import SCHEMA_VERSION, Store
from vinadv.store.schema import exact_collation, runs
from vinadv.testing.store import random_records

#: names that a case- and accent-insensitive comparison (MariaDB's utf8mb4_general_ci) takes for one another
CONFUSABLE = [
    "Run",
    "run",
    "RUN",
    "café",
    "cafe",
    "cafe\u0301",  # 'café' with a combining accent
    "Straße",
    "strasse",
    "\N{GRINNING FACE}",
    "\N{PILE OF POO}",
    "ı",  # dotless i
    "i",
]


def _insert_names(url: str, names: list[str]) -> list[int]:
    """Rows of `runs` called `names`, inserted as an older vinadv (or another program) could have: without the
    checks of `create_run`; their ids."""
    engine = sa.create_engine(url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        ids = [
            int(
                conn.execute(
                    runs.insert().values(name=n, created=sa.func.now(), version="0", status="done")
                ).inserted_primary_key[0]
            )
            for n in names
        ]
    engine.dispose()
    return ids


def test_confusable_names_are_different_runs(db_url):
    assert len(set(CONFUSABLE)) == len(CONFUSABLE)
    with Store.open(db_url) as store:
        ids = [store.create_run(name) for name in CONFUSABLE]  # none is "already called" by another
        assert len(set(ids)) == len(CONFUSABLE)
        assert [store.find_run(name) for name in CONFUSABLE] == ids
        assert [store.resolve_run(name) for name in CONFUSABLE] == ids
        assert [store.run_info(i)["name"] for i in ids] == CONFUSABLE
        for unknown in ("rUN", "CAFÉ", "\N{SMILING FACE WITH HORNS}", "STRASSE", "I"):
            assert store.find_run(unknown) is None


def test_a_trailing_space_makes_another_name(db_url):
    # `create_run` refuses names with outer spaces today; an older vinadv stored them as given
    with Store.open(db_url) as store:
        plain = store.create_run("x")
    spaced, spaced_twice = _insert_names(db_url, ["x ", "x  "])
    with Store.open(db_url, readonly=True) as store:
        assert [store.find_run(n) for n in ("x", "x ", "x  ")] == [plain, spaced, spaced_twice]
        assert [store.resolve_run(n) for n in ("x", "x ", "x  ")] == [plain, spaced, spaced_twice]


def test_export_and_resume_find_the_run_of_that_exact_name(db_url, tmp_path, capsys):
    with Store.open(db_url) as store:
        upper = store.create_run("Run", config={"n": 1})
        store.write_pairs(upper, random_records(3, size=7, seed=1))
        lower = store.create_run("run", config={"n": 1})
        store.write_pairs(lower, random_records(5, size=7, seed=2))
    for name, run_id, n in (("Run", upper, 3), ("run", lower, 5)):
        out = tmp_path / f"{run_id}.csv"
        assert main(["export", "--db", db_url, "--run", name, "--out", str(out), "--quiet"]) == 0
        with out.open(newline="") as fh:
            rows = list(csv.DictReader(fh))
        assert len(rows) == n and {r["run_id"] for r in rows} == {str(run_id)}
    assert main(["export", "--db", db_url, "--run", "RUN", "--quiet"]) == 2
    assert "no run named 'RUN'" in capsys.readouterr().err
    assert (
        main(
            [
                "run",
                "--n",
                "2",
                "--size",
                "8",
                "--planner",
                "optimal",
                "--db",
                db_url,
                "--name",
                "RUN",
                "--resume",
                "--quiet",
            ]
        )
        == 2
    )
    assert "no run named 'RUN'" in capsys.readouterr().err


def test_a_version_4_database_holding_names_is_upgraded_in_place(db_url):
    run_id = old_database(db_url, 4, 12, lambda conn, quote: None, name="Old")
    # names a version-4 MariaDB database could hold side by side (stored when its checks compared otherwise)
    others = _insert_names(db_url, ["old", "OLD ", "café", "cafe"])
    old_collation = run_name_collation(db_url)
    assert columns_and_version(db_url)[1] == "4"
    names = ["Old", "old", "OLD ", "café", "cafe"]
    ids = [run_id, *others]
    with Store.open(db_url, readonly=True) as store:  # read-only: compared exactly already, nothing changes
        assert [store.find_run(n) for n in names] == ids and store.find_run("OLD") is None
        before = store.read_pairs(run_id)
    assert columns_and_version(db_url)[1] == "4" and run_name_collation(db_url) == old_collation
    with Store.open(db_url) as store:
        assert [store.find_run(n) for n in names] == ids
        assert [store.run_info(i)["name"] for i in ids] == names
        assert store.read_pairs(run_id).equals(before)
        assert store.create_run("OLD") not in ids
    assert columns_and_version(db_url)[1] == SCHEMA_VERSION == "8"
    engine = sa.create_engine(db_url, poolclass=sa.pool.NullPool)
    engine.connect().close()  # the dialect learns the server
    assert run_name_collation(db_url) == exact_collation(engine.dialect)
    if engine.dialect.name == "mysql":
        assert old_collation == "utf8mb4_general_ci" and run_name_collation(db_url) == "utf8mb4_nopad_bin"
        with engine.connect() as conn:  # the name index survived the change of the column
            assert "ix_runs_name" in {ix["name"] for ix in sa.inspect(conn).get_indexes("runs")}
    engine.dispose()


def test_a_version_1_database_gains_the_columns_and_the_exact_names(db_url):
    # the additive steps (versions 2 to 4) and version 5's collation compose in one open
    run_id = version_1_database(db_url, 6, name="Run")
    (other,) = _insert_names(db_url, ["run"])
    with Store.open(db_url) as store:
        assert [store.find_run("Run"), store.find_run("run")] == [run_id, other]
        assert len(store.read_pairs(run_id)) == 6
    columns, version = columns_and_version(db_url)
    assert version == SCHEMA_VERSION == "8" and set(LATER_COLUMNS) <= columns


def test_an_upgrade_cut_short_is_finished_by_the_next_open(mysql_url):
    # MariaDB commits each ALTER on its own: the collation changed, the version not yet recorded
    run_id = old_database(mysql_url, 4, 3, lambda conn, quote: None, name="Cut")
    engine = sa.create_engine(mysql_url, poolclass=sa.pool.NullPool)
    with engine.begin() as conn:
        conn.execute(
            sa.text("ALTER TABLE runs MODIFY name VARCHAR(255) CHARACTER SET utf8mb4 COLLATE utf8mb4_nopad_bin")
        )
    engine.dispose()
    (other,) = _insert_names(mysql_url, ["cut"])
    assert columns_and_version(mysql_url)[1] == "4"
    with Store.open(mysql_url) as store:
        assert [store.find_run("Cut"), store.find_run("cut")] == [run_id, other]
        np.testing.assert_array_equal(store.stored_indices(run_id), np.arange(3))
    assert columns_and_version(mysql_url)[1] == "8" and run_name_collation(mysql_url) == "utf8mb4_nopad_bin"
