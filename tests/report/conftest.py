"""A small stored database for the report tests, made once per session: two runs (saliency and near-path) on 12x12
maps with the evaluation stage's measurements (planner quality, processing time), and a copy with the classifier
comparison too (`evaluated`). The report only reads, so the tests share these and write reports from them."""

from __future__ import annotations

import shutil

import pytest
from tests.report.formats import figures_not_rendered, png_figures_only

from vinadv.cli import main
from vinadv.evaluation import evaluate_planner_quality, evaluate_timing
from vinadv.pipeline import RunConfig, run_pipeline
from vinadv.report import write_report
from vinadv.store import Store

SIZE = 12


@pytest.fixture(scope="session")
def report_weights(planning_weights) -> str:
    return planning_weights(SIZE)


@pytest.fixture(scope="session")
def base_db(tmp_path_factory, report_weights):
    """(SQLite path, run ids): run 1 saliency (has FP and DP pairs), run 2 near-path, each with its planner quality
    and processing time stored, no classifier comparison. Copy before writing."""
    path = tmp_path_factory.mktemp("report_db") / "base.db"
    url = f"sqlite:///{path}"
    ids = []
    for attack in ("saliency", "near-path"):
        config = RunConfig(n=80, size=SIZE, attack=attack, seed=4, shard_size=80, weights=report_weights)
        ids.append(run_pipeline(config, db=url, name=attack, progress=False).run_id)
    with Store.open(url) as store:
        for run_id in ids:
            evaluate_planner_quality(store, run_id)
            evaluate_timing(store, run_id)
    return path, ids


@pytest.fixture(scope="session")
def base_report(base_db, tmp_path_factory):
    """The report of the base database, run 1 the main run beside run 2 (the report only reads, so the database
    itself): (URL, run ids, report folder). Read it, don't write there."""
    path, ids = base_db
    url = f"sqlite:///{path}"
    index = write_report(url, tmp_path_factory.mktemp("base_report") / "rep", run_id=ids[0], runs=ids)
    return url, ids, index.parent


@pytest.fixture
def png_only():
    """Within the test, reports save their figures as PNG only (tests/report/formats.py): for a test of the PNGs."""
    with png_figures_only():
        yield


@pytest.fixture
def unrendered():
    """Within the test, reports draw their figures but render none, every figure file empty (tests/report/formats.py):
    for the tests of a report's data, sections and links, not of its figures' pixels."""
    with figures_not_rendered():
        yield


@pytest.fixture
def db_copy(base_db, tmp_path):
    """A private copy of the base database: (URL, run ids)."""
    path, ids = base_db
    target = tmp_path / "copy.db"
    shutil.copy(path, target)
    for suffix in ("-wal", "-shm"):
        if path.with_name(path.name + suffix).exists():
            shutil.copy(path.with_name(path.name + suffix), target.with_name(target.name + suffix))
    return f"sqlite:///{target}", ids


@pytest.fixture(scope="session")
def evaluated(base_db, tmp_path_factory):
    """The base database after `vinadv evaluate` (svm, rule, hausdorff, hybrid; fraction 0.5) and its report:
    (URL, run ids, report folder)."""
    path, ids = base_db
    folder = tmp_path_factory.mktemp("evaluated")
    shutil.copy(path, folder / "e.db")
    url = f"sqlite:///{folder / 'e.db'}"
    assert (
        main(
            [
                "evaluate",
                "--db",
                url,
                "--run",
                str(ids[0]),
                "--classifiers",
                "svm,rule,hausdorff,hybrid",
                "--sizes",
                "0.5",
                "--quiet",
            ]
        )
        == 0
    )
    out = folder / "report"
    assert main(["report", "--db", url, "--run", str(ids[0]), "--out", str(out), "--quiet"]) == 0
    return url, ids, out
