"""A SQLite database in tmp_path with two runs: 'random' (random_records, 230 pairs) and 'crafted' (three
hand-made pairs with gaps in their indices), and a Flask test client over it."""

from __future__ import annotations

import contextlib
import re
import shutil

import numpy as np
import pytest

from vinadv.grid.paths import PackedPaths
from vinadv.store import PairRecords, Store
from vinadv.testing.store import random_records
from vinadv.viewer.app import create_app

N_RANDOM = 230


def crafted_records() -> PairRecords:
    """Three 6x6 pairs at pair indices 10, 20, 30: FP (score 0.9, dh 3, dv 0), DP (no score), invalid (no dh/dv)."""
    size = 6
    border = np.zeros((size, size), bool)
    border[0, :] = border[-1, :] = border[:, 0] = border[:, -1] = True
    obstacles_o = np.stack([border] * 3)
    obstacles_a = obstacles_o.copy()
    added = np.array([[2, 3], [3, 2], [2, 2]])
    obstacles_a[np.arange(3), added[:, 0], added[:, 1]] = True
    path_o = [[(1, 1), (2, 2), (3, 3), (4, 4)], [(1, 1), (2, 2), (3, 3), (4, 4)], [(1, 1), (1, 2)]]
    path_a = [
        [(1, 1), (1, 2), (1, 3), (1, 4), (2, 4), (3, 4), (4, 4)],
        [(1, 1), (2, 1), (3, 1), (4, 2), (4, 3), (4, 4)],
        [(1, 1), (1, 2)],
    ]

    return PairRecords(
        pair_index=[10, 20, 30],
        obstacles_o=obstacles_o,
        obstacles_a=obstacles_a,
        starts=[[1, 1]] * 3,
        goals=[[4, 4]] * 3,
        added=added,
        path_o=PackedPaths.pack(path_o),
        path_a=PackedPaths.pack(path_a),
        label=["FP", "DP", "invalid"],
        attack=[True, False, False],
        term_o=["goal", "goal", "collision"],
        term_a=["goal", "goal", "collision"],
        label_source=["svm", "svm", "rule"],
        score=[0.9, np.nan, np.nan],
        dh=[3, 1, -1],
        dv=[0, 2, -1],
    )


@pytest.fixture(scope="session")
def db_file(tmp_path_factory):
    """The database file, written once per session: (path, runs as in `db`). Tests get a copy (`db`)."""
    path = tmp_path_factory.mktemp("viewer") / "viewer.db"
    with Store.open(f"sqlite:///{path}") as store:
        runs = {}
        for name, records in (("random", random_records(N_RANDOM, size=12, seed=3)), ("crafted", crafted_records())):
            run_id = store.create_run(name, attack="random", seed=0)
            store.write_pairs(run_id, records)
            store.finish_run(run_id, {"total": 1.0})
            runs[name] = (run_id, records)
    return path, runs


@pytest.fixture
def db(db_file, tmp_path):
    """(url, {"random": (run_id, records), "crafted": (run_id, records)}): a fresh copy of the session's file, so
    a test that labels pairs changes only its own."""
    path, runs = db_file
    shutil.copyfile(path, tmp_path / "viewer.db")
    return f"sqlite:///{tmp_path / 'viewer.db'}", runs


@pytest.fixture
def store(db):
    store = Store.open(db[0], create=False)
    yield store
    store.close()


def viewer_for_tests(store: Store):
    """The viewer over `store` in Flask's testing mode (errors raised in the test, not turned into 500 pages)."""
    app = create_app(store, secret_key="test-secret")
    app.config["TESTING"] = True
    return app


@contextlib.contextmanager
def one_run_client(folder, records: PairRecords):
    """A test client of the viewer over a new database in `folder` holding `records` as its one run; yields
    (client, run id)."""
    with Store.open(f"sqlite:///{folder / 'one-run.db'}") as store:
        run_id = store.create_run("one")
        store.write_pairs(run_id, records)
        yield viewer_for_tests(store).test_client(), run_id


@pytest.fixture
def app(store):
    return viewer_for_tests(store)


@pytest.fixture
def client(app):
    return app.test_client()


def csrf_from(html: str) -> str:
    found = re.search(r'name="csrf_token" value="([^"]+)"', html)
    assert found, "no CSRF token in the page"
    return found.group(1)
