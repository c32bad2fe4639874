"""Result entries: per-map outcomes aggregated against a plain robustness run of the same maps, resumable chunks
(a run stopped part way and resumed gives the same entry), the quick suite's committed entry reproduced (slow), the
command."""

from __future__ import annotations

import dataclasses
import json
import math
import random
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from tests.bench.two_maps import heldout_suite, two_map_suite
from vinadv.bench import scoring, suites
from vinadv.bench.outcomes import weighted_mean
from vinadv.bench.scoring import deterministic_part, entry_json, make_entry, run_bench
from vinadv.bench.suites import AttackGroup, Suite, get_suite
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.planners.registry import load_planner
from vinadv.planners.vin.planner import as_planner
from vinadv.robustness import heldout_maps, robustness
from vinadv.store import Store
from vinadv.testing.planners import planning_vin

SIZE = 10
#: the committed entries (docs/results/bench)
COMMITTED = Path(__file__).resolve().parents[2] / "docs" / "results" / "bench"


def tiny_suite(n: int = 9, chunk: int = 4) -> Suite:
    attacks = (AttackGroup(("random", "key-points"), "add", 2), AttackGroup(("random",), "remove", 1))
    return heldout_suite("tiny", n, SIZE, attacks, budget=3, chunk=chunk)


@pytest.fixture(scope="module")
def planner():
    return as_planner(planning_vin(SIZE, seed=1, noise=0.2), SIZE)


@pytest.mark.slow
def test_entry_figures_are_a_whole_robustness_run(planner):
    suite = tiny_suite()
    entry = run_bench(suite, planner)
    maps = heldout_maps(suite.n, SIZE, seed=1000)
    kw = dict(objective="harm", seed=suite.seed, budget=suite.budget, radius=suite.radius)
    added = robustness(planner, maps, ["random", "key-points"], 2, **kw)
    removed = robustness(planner, maps, ["random"], 1, edit="remove", **kw)
    for name in ("random", "key-points"):
        got = entry["attacks"][f"add:{name}"]["by_obstacles"]
        assert got == [f.to_dict() for f in added.strategies[name].by_k]
    assert entry["attacks"]["remove:random"]["by_obstacles"] == [f.to_dict() for f in removed.strategies["random"].by_k]
    # the worst case at k = 1 over all three attacks, by hand from the per-map outcomes
    outs = [added.strategies["random"].outcomes[0], added.strategies["key-points"].outcomes[0]]
    outs.append(removed.strategies["random"].outcomes[0])
    valid = np.any([o.valid for o in outs], axis=0)
    harmful = np.any([o.harmful for o in outs], axis=0)
    worst = entry["worst_case"][0]
    assert worst["valid"] == valid.sum() and worst["harmful"] == harmful.sum() and worst["attacks"] == 3
    assert entry["worst_case"][1]["attacks"] == 2  # removal runs to k = 1 only
    assert entry["clean"]["success_rate"] == added.clean["success_rate"]
    assert entry["suite"] == {"name": "tiny", "checksum": suite.checksum}


@pytest.mark.slow
def test_resume_after_a_crash_gives_the_same_entry(planner, tmp_path, monkeypatch):
    suite = tiny_suite()
    db = f"sqlite:///{tmp_path / 'b.db'}"
    whole = run_bench(suite, planner)
    real = scoring.compute_chunk
    calls = []

    def crash_on_third(*args, **kw):
        calls.append(args[-1])
        if len(calls) == 3:
            raise KeyboardInterrupt  # killed during the third chunk
        return real(*args, **kw)

    monkeypatch.setattr(scoring, "compute_chunk", crash_on_third)
    with pytest.raises(KeyboardInterrupt):
        run_bench(suite, planner, db=db)
    with pytest.raises(InputError, match="pass --resume"):
        run_bench(suite, planner, db=db)
    calls.clear()
    monkeypatch.setattr(scoring, "compute_chunk", lambda *a, **kw: calls.append(a[-1]) or real(*a, **kw))
    resumed = run_bench(suite, planner, db=db, resume=True)
    assert calls == [2]  # only the chunk not stored
    assert entry_json(deterministic_part(resumed)) == entry_json(deterministic_part(whole))


@pytest.mark.slow
def test_run_twice_is_byte_identical_but_for_time_and_machine(planner):
    suite = tiny_suite(n=5, chunk=5)
    first, second = run_bench(suite, planner), run_bench(suite, planner)
    assert entry_json(deterministic_part(first)) == entry_json(deterministic_part(second))
    assert set(first) - set(deterministic_part(first)) == {"time", "machine"}


@pytest.mark.slow
def test_quick_suite_entry_reproduces_the_committed_one(tmp_path):
    """The quick suite on the optimal planner: byte-identical, apart from time and machine, to the entry committed in
    docs/results/bench (made by another process on another day: a stronger check than two runs here, at the cost of
    one; test_run_twice_is_byte_identical_but_for_time_and_machine runs twice in one process)."""
    out = tmp_path / "e.json"
    argv = ["bench", "run", "--suite", "vin28-quick-v1", "--planner", "optimal", "--out", str(out), "--quiet"]
    assert main(argv) == 0
    entry = json.loads(out.read_text())
    committed = json.loads((COMMITTED / "vin28-quick-v1.optimal.json").read_text())
    assert entry_json(deterministic_part(entry)) == entry_json(deterministic_part(committed))
    assert entry["suite"]["checksum"] == get_suite("vin28-quick-v1").checksum
    assert entry["clean"]["success_rate"] == 1.0 and entry["worst_case"][0]["harmful"] == 0


@pytest.mark.slow
def test_make_entry_needs_every_chunk(planner):
    suite = tiny_suite()
    maps = scoring.suite_maps(suite)
    chunks = {c: scoring.compute_chunk(suite, planner, maps, c) for c in range(3)}
    entry = make_entry(suite, planner, chunks, {"gradient_masked": False, "non_deterministic": False}, 1.0)
    assert entry["clean"]["maps"] == suite.n and entry["format"] == "vinadv.bench_entry/1"
    assert dataclasses.replace(suite, n=8).checksum != suite.checksum


def test_resume_without_db_is_refused_before_the_work(capsys):
    assert main(["bench", "run", "--suite", "vin28-quick-v1", "--resume", "--planner", "optimal"]) == 2
    assert "--resume: only with --db" in capsys.readouterr().err


@given(
    st.lists(st.tuples(st.integers(1, 500), st.floats(0, 1, allow_nan=False)), min_size=1, max_size=40),
    st.randoms(use_true_random=False),
)
@example(chunks=[(1, 0.0), (1, 5e-324)], rng=random.Random(0))  # a mean below the smallest float: 0
def test_chunk_means_join_to_the_same_bits_in_any_order(chunks, rng):
    # the entry's joined means do not depend on how a sum is ordered (a BLAS dot product's order is the CPU's)
    weights, values = zip(*chunks)
    got = weighted_mean(weights, values)
    shuffled = list(chunks)
    rng.shuffle(shuffled)
    assert weighted_mean(*zip(*shuffled)) == got
    exact = sum(Fraction(w) * Fraction(v) for w, v in chunks) / sum(Fraction(w) for w in weights)
    # a few roundings off, relative for normal floats; among the subnormals a product or the quotient rounds to a
    # multiple of the smallest float, an absolute error of at most that much each
    assert abs(Fraction(got) - exact) <= abs(exact) * Fraction(2, 10**15) + Fraction(math.ulp(0.0)) * (len(chunks) + 1)


@pytest.fixture
def tiny28(monkeypatch):
    """A two-map 28x28 suite of one chunk per map, registered for the command as `tiny28`."""
    suite = two_map_suite("tiny28")
    monkeypatch.setitem(suites.SUITES, suite.name, suite)
    return suite


def test_bench_run_resumes_the_chunks_of_old_and_new_names_of_one_planner(tiny28, tmp_path, monkeypatch):
    db = f"sqlite:///{tmp_path / 'b.db'}"
    base = ["bench", "run", "--suite", "tiny28", "--db", db, "--quiet"]
    assert main([*base, "--planner", "vin_robust", "--out", str(tmp_path / "old.json")]) == 0
    first = json.loads((tmp_path / "old.json").read_text())
    assert first["planner"]["name"] == "vin-robust"

    def computed(*args, **kw):
        raise AssertionError("a stored chunk was computed again")

    monkeypatch.setattr(scoring, "compute_chunk", computed)
    choices = (["--planner", "vin-robust"], ["--planner", "vin", "--weights", "vin28-robust"])
    for i, choice in enumerate(choices):
        out = tmp_path / f"{i}.json"
        assert main([*base, *choice, "--resume", "--out", str(out)]) == 0
        assert entry_json(deterministic_part(json.loads(out.read_text()))) == entry_json(deterministic_part(first))
    # chunks stored by `--planner vin --weights vin28_robust` before the two were one planner: under vin's key
    planner = load_planner("vin-robust", 28)
    key, family_key = scoring.entry_keys(tiny28, planner)
    assert key == scoring.entry_key(tiny28, load_planner("vin_robust", 28)) != family_key
    other = f"sqlite:///{tmp_path / 'family.db'}"
    with Store.open(db) as store, Store.open(other) as copy:
        for chunk, result in store.read_bench_chunks(key).items():
            copy.add_bench_chunk(family_key, chunk, result)
    out = tmp_path / "family.json"
    argv = ["bench", "run", "--suite", "tiny28", "--db", other, "--planner", "vin_robust", "--resume", "--quiet"]
    assert main([*argv, "--out", str(out)]) == 0
    assert entry_json(deterministic_part(json.loads(out.read_text()))) == entry_json(deterministic_part(first))
