"""The evaluation stage's measurements of a stored run (planner quality, processing time), as stored."""

from __future__ import annotations

import numpy as np
import pytest

from vinadv.evaluation import evaluate_planner_quality, evaluate_timing
from vinadv.evaluation.planner_quality import run_maps
from vinadv.evaluation.timing import timing_pairs
from vinadv.pipeline import RunConfig, run_pipeline
from vinadv.store import Store
from vinadv.vocabulary import PLANNER_QUALITY, TIMING


@pytest.fixture(scope="module")
def optimal_run(tmp_path_factory):
    """(URL, run id): 40 pairs of the exact `optimal` planner on 8x8 maps."""
    url = f"sqlite:///{tmp_path_factory.mktemp('evaluation') / 'e.db'}"
    config = RunConfig(n=40, size=8, attack="key-points", seed=1, shard_size=40, planner="optimal")
    return url, run_pipeline(config, db=url, name="optimal", progress=False).run_id


def test_the_optimal_planner_is_measured_optimal_on_the_runs_maps_and_the_result_is_stored(optimal_run):
    url, run_id = optimal_run
    with Store.open(url) as store:
        result = evaluate_planner_quality(store, run_id)
        assert store.read_measurement(run_id, PLANNER_QUALITY) == result
        pairs = store.read_pairs(run_id)
    metrics = result["metrics"]
    distinct = {(p.tobytes(), tuple(s), tuple(g)) for p, s, g in zip(pairs.obstacles_o, pairs.starts, pairs.goals)}
    assert metrics["success_rate"] == metrics["optimal_rate"] == 1.0 and metrics["maps"] == len(distinct)
    assert metrics["action_accuracy"] == 1.0  # `optimal` declares a policy: its optimal action at every cell
    assert result["capabilities"] == {
        "policy": True,
        "value_maps": True,
        "gradients": False,
        "expansions": False,
        "start_values": False,
    }
    assert result["search"] is None and result["planner"]["name"] == "optimal"
    assert len(result["value_map"]["values"]) == 8  # its value map of the first map, 8x8
    assert result["source"].startswith(f"measured by vinadv evaluate on the first {len(distinct)} distinct maps")


def test_the_maps_are_the_runs_distinct_original_maps_first_by_pair_index(tmp_path):
    """Three pairs per map: each map once, with the start its pairs used, in pair-index order, capped."""
    url = f"sqlite:///{tmp_path / 'm.db'}"
    config = RunConfig(n=6, size=8, attack="random", seed=2, shard_size=6, planner="astar", per_map=3)
    run_id = run_pipeline(config, db=url, progress=False).run_id
    with Store.open(url) as store:
        pairs = store.read_pairs(run_id)
        maps, first = run_maps(store, run_id, True, limit=4)
    assert len(pairs) == 18 and len(maps) == 4 and maps.n_starts == 1
    np.testing.assert_array_equal(first, pairs.pair_index[[0, 3, 6, 9]])  # per_map 3: a new map every 3 pairs
    np.testing.assert_array_equal(maps.obstacles, pairs.obstacles_o[[0, 3, 6, 9]])
    np.testing.assert_array_equal(maps.starts[:, 0], pairs.starts[[0, 3, 6, 9]])
    # the expert costs are the optimal costs the run stored with each pair's original map
    np.testing.assert_allclose(maps.expert_costs[:, 0], pairs.opt_cost_o[[0, 3, 6, 9]])


def test_a_run_whose_weights_are_gone_is_stored_as_not_available(optimal_run, tmp_path):
    url, _ = optimal_run
    missing = tmp_path / "gone.pt"
    with Store.open(url) as store:
        run_id = store.create_run("gone", config={"planner": "vin", "size": 8, "weights": str(missing)})
        store.write_pairs(run_id, store.read_pairs(optimal_run[1]))  # maps to measure on
        result = evaluate_planner_quality(store, run_id)
    assert result["metrics"] == {} and result["capabilities"] is None
    assert result["source"] == f"not available: the run's weights file {missing} is not on this machine"


def test_timing_is_measured_on_the_papers_mix_of_the_run(optimal_run):
    url, run_id = optimal_run
    with Store.open(url) as store:
        index, labels = store.pair_labels(run_id)
        result = evaluate_timing(store, run_id)
        assert store.read_measurement(run_id, TIMING) == result
    mix = timing_pairs(index, labels)
    chosen = labels[np.searchsorted(index, mix)]
    assert result["pairs"] == len(mix) == min(len(index), 100)
    assert result["counts"] == {lab: int(np.sum(chosen == lab)) for lab in result["counts"]}
    assert sum(result["counts"].values()) == result["pairs"]
    assert result["read_s"] > 0 and result["rule_s"] > 0 and result["repeats"] >= 1
    assert "CPUs, Python" in result["machine"]
