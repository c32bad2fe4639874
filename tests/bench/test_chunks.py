"""Resume that mixes computations (issue 45): a stored chunk is checked on read (its result's schema) and reused only
when its fingerprint (results format, suite checksum, strategy revisions, planner provenance) is this run's; a
mismatch is one line naming both. Chunks stored before fingerprints still resume; the provenance stays out of the
entry key."""

from __future__ import annotations

import json

import pytest
import sqlalchemy as sa

from tests.bench.two_maps import two_map_suite
from tests.progress_bars import recorded_bars
from vinadv.attacks.strategies import STRATEGIES
from vinadv.bench import scoring, suites
from vinadv.bench.scoring import deterministic_part, entry_json, entry_key, run_bench
from vinadv.bench.suites import Suite
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.executor import LocalExecutor
from vinadv.planners.registry import PlannerRef, load_planner


@pytest.fixture(scope="module")
def tiny() -> Suite:
    return two_map_suite("tiny-chunks")


def _sql(db_file, statement: str) -> None:
    engine = sa.create_engine(f"sqlite:///{db_file}")
    with engine.begin() as conn:
        conn.execute(sa.text(statement))
    engine.dispose()


def _no_compute(monkeypatch):
    def computed(*args, **kw):
        raise AssertionError("a stored chunk was computed again")

    monkeypatch.setattr(scoring, "compute_chunk", computed)


@pytest.mark.parametrize(
    ("result", "expected"),
    [
        ("{}", "field 'first_map' is missing"),
        ("not json", "not JSON"),
        ('{"first_map": 1}', "field 'maps'"),
        ('{"first_map": 0}', "field 'first_map' is 0, expected 1"),
    ],
)
def test_a_stored_chunk_that_is_not_a_result_is_one_line(tiny, tmp_path, monkeypatch, capsys, result, expected):
    planner = load_planner("optimal", 28)
    db = tmp_path / "b.db"
    run_bench(tiny, planner, db=str(db))
    _sql(db, f"UPDATE bench_chunks SET result = '{result}' WHERE chunk = 1")
    with pytest.raises(InputError, match=f"database .*b.db: stored chunk 1 .*{expected}"):
        run_bench(tiny, planner, db=str(db), resume=True)
    monkeypatch.setitem(suites.SUITES, tiny.name, tiny)
    argv = ["bench", "run", "--suite", tiny.name, "--planner", "optimal", "--db", str(db), "--resume", "--quiet"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "stored chunk 1" in err and expected.split("'")[0] in err


def test_chunks_of_another_results_format_are_refused_naming_both(tiny, tmp_path, monkeypatch):
    planner = load_planner("astar", 28)
    db = str(tmp_path / "b.db")
    run_bench(tiny, planner, db=db)
    monkeypatch.setattr(scoring, "CHUNK_FORMAT", 3)
    _no_compute(monkeypatch)
    with pytest.raises(InputError, match="computed with results format 2, this run with results format 3"):
        run_bench(tiny, planner, db=db, resume=True)


def test_chunks_without_efforts_resume_only_for_a_planner_without_expansions(tiny, tmp_path, monkeypatch):
    # results format 2 added the efforts of a search planner: its chunks of format 1 lack them and are refused, a
    # policy's chunks (nothing changed for it) keep format 1 and resume
    policy, search = load_planner("optimal", 28), load_planner("astar", 28)
    assert scoring.chunk_fingerprint(tiny, policy)["format"] == 1
    assert scoring.chunk_fingerprint(tiny, search)["format"] == 2
    db = tmp_path / "b.db"
    run_bench(tiny, search, db=str(db))
    _sql(db, "UPDATE bench_chunks SET result = json_set(result, '$.fingerprint.format', 1)")
    with pytest.raises(InputError, match="computed with results format 1, this run with results format 2"):
        run_bench(tiny, search, db=str(db), resume=True)
    other = tmp_path / "p.db"
    whole = run_bench(tiny, policy, db=str(other))
    _no_compute(monkeypatch)
    resumed = run_bench(tiny, policy, db=str(other), resume=True)
    assert entry_json(deterministic_part(resumed)) == entry_json(deterministic_part(whole))


def test_chunks_of_another_strategy_revision_are_refused_naming_it(tiny, tmp_path, monkeypatch):
    # a strategy whose results changed (its revision bumped) makes other pairs: its stored chunks must not join
    planner = load_planner("optimal", 28)
    db = tmp_path / "b.db"
    whole = run_bench(tiny, planner, db=str(db))
    # stored before revisions were recorded: every strategy at revision 1, as now for `random`
    _sql(db, "UPDATE bench_chunks SET result = json_remove(result, '$.fingerprint.strategies')")
    resumed = run_bench(tiny, planner, db=str(db), resume=True)
    assert entry_json(deterministic_part(resumed)) == entry_json(deterministic_part(whole))
    monkeypatch.setattr(STRATEGIES["random"], "revision", 2)
    _no_compute(monkeypatch)
    with pytest.raises(InputError, match="computed with random revision 1, this run with random revision 2"):
        run_bench(tiny, planner, db=str(db), resume=True)


def test_chunks_stored_before_fingerprints_still_resume(tiny, tmp_path, monkeypatch):
    planner = load_planner("optimal", 28)
    db = tmp_path / "b.db"
    whole = run_bench(tiny, planner, db=str(db))
    _sql(db, "UPDATE bench_chunks SET result = json_remove(result, '$.fingerprint'), version = '0.1.0'")
    _no_compute(monkeypatch)
    resumed = run_bench(tiny, planner, db=str(db), resume=True)
    assert entry_json(deterministic_part(resumed)) == entry_json(deterministic_part(whole))


PLANNER = """
import os, sys
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import {helper}

def make(size):
    return {helper}.inner(size)
"""
HELPER = """
from vinadv.planners.registry import load_planner

STEP = {step}

def inner(size):
    return load_planner("astar", size)
"""


def test_a_file_planner_whose_imported_module_changed_is_refused_naming_it(tiny, tmp_path, monkeypatch):
    helper = f"helper_{tmp_path.name.replace('-', '_')}"
    (tmp_path / "mine.py").write_text(PLANNER.format(helper=helper))
    (tmp_path / f"{helper}.py").write_text(HELPER.format(step=1))
    spec = f"{tmp_path / 'mine.py'}:make"
    first = load_planner(spec, 28)
    assert set(first.provenance["files"]) == {"mine.py", f"{helper}.py"}
    assert "provenance" not in json.dumps(first.spec())
    db = str(tmp_path / "b.db")
    run_bench(tiny, first, db=db)
    (tmp_path / f"{helper}.py").write_text(HELPER.format(step=2))  # the imported module changed
    second = load_planner(spec, 28)
    assert entry_key(tiny, second) == entry_key(tiny, first)  # the provenance is not in the key
    _no_compute(monkeypatch)
    with pytest.raises(InputError, match=f"computed with {helper}.py [0-9a-f]{{12}}, this run with {helper}.py"):
        run_bench(tiny, second, db=db, resume=True)


def test_a_declared_planner_version_is_its_provenance(tmp_path):
    (tmp_path / "versioned.py").write_text(
        'PLANNER_VERSION = "2.1"\n\ndef make(size):\n    from vinadv.planners.registry import load_planner\n\n'
        '    return load_planner("astar", size)\n'
    )
    assert load_planner(f"{tmp_path / 'versioned.py'}:make", 28).provenance == {"version": "2.1"}


@pytest.mark.slow  # two bench runs of the two-map suite: about two seconds
def test_the_progress_bar_counts_maps_the_stored_ones_done(tiny, tmp_path, monkeypatch):
    """`--resume`'s bar starts at the maps of the stored chunks and moves by each computed chunk's maps; under it the
    computed chunk's attack counts that chunk's maps, its bar cleared when done."""
    planner = load_planner("optimal", 28)
    db = tmp_path / "b.db"
    run_bench(tiny, planner, db=str(db))
    _sql(db, "DELETE FROM bench_chunks WHERE chunk = 1")
    bars = recorded_bars(monkeypatch)
    run_bench(tiny, planner, db=str(db), resume=True, progress=True)
    run, attack = bars  # the random attack of the one chunk computed
    assert (run.desc, run.unit, run.initial, run.total, run.updates) == ("bench tiny-chunks", "map", 1, 2, [1])
    assert (attack.desc, attack.unit, attack.total, sum(attack.updates), attack.leave) == (
        "attack random",
        "map",
        1,
        1,
        None,
    )


class _RemoteHere(LocalExecutor):
    """A remote executor that runs its tasks in this process: what a remote worker would be told."""

    remote = True


def test_a_remote_chunk_shows_no_bar_of_its_attacks(tiny, monkeypatch):
    """A chunk run on a remote worker draws no bar there: only the run's bar, counting the chunks' maps."""
    planner = load_planner("optimal", 28)
    bars = recorded_bars(monkeypatch)
    run_bench(
        tiny, planner, progress=True, executor=_RemoteHere(), planner_ref=PlannerRef.of(planner, "optimal", None, True)
    )
    (run,) = bars
    assert (run.desc, run.total, run.updates) == ("bench tiny-chunks", 2, [1, 1])
