"""The evaluation stage's measurements of a stored run (planner quality, processing time), as stored."""

from __future__ import annotations

import numpy as np
import pytest

from vinadv.evaluation import evaluate_planner_quality, evaluate_timing
from vinadv.evaluation.planner_quality import QUICK_EVAL_MAPS, find_metrics
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


def test_the_optimal_planner_is_measured_optimal_and_the_result_is_stored(optimal_run):
    url, run_id = optimal_run
    with Store.open(url) as store:
        result = evaluate_planner_quality(store, run_id)
        assert store.read_measurement(run_id, PLANNER_QUALITY) == result
    metrics = result["metrics"]
    assert metrics["success_rate"] == metrics["optimal_rate"] == 1.0 and metrics["maps"] == QUICK_EVAL_MAPS
    assert result["source"].startswith("quick evaluation of planner 'optimal'")


def test_a_run_whose_weights_are_gone_is_stored_as_not_available(optimal_run, tmp_path):
    url, _ = optimal_run
    missing = tmp_path / "gone.pt"
    with Store.open(url) as store:
        run_id = store.create_run("gone", config={"planner": "vin", "size": 8, "weights": str(missing)})
        result = evaluate_planner_quality(store, run_id)
    assert result == {
        "metrics": {},
        "source": f"not available: the run's weights file {missing} is not on this machine",
    }


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


def test_metrics_are_found_nested_in_a_record_the_latest_first():
    record = {"epochs": [{"success_rate": 0.5, "optimal_rate": 0.4}, {"success_rate": 0.9, "optimal_rate": 0.8}]}
    assert find_metrics(record) == {"success_rate": 0.9, "optimal_rate": 0.8}
    assert find_metrics({"loss": [1.0, 0.5]}) is None
