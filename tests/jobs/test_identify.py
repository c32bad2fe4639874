"""`vinadv.identify` as a job: the config refuses a bad value naming the field; `run` labels the pairs as `identify`
does, after planning them again with the config's planner, and stores them."""

import re

import numpy as np
import pytest

from tests.jobs.optimal_attack import random_attack_on_optimal
from vinadv.attacks.pairs import PairSet
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.identify import IdentifyConfig, identify, replan, run
from vinadv.planners.registry import load_planner
from vinadv.store import Store


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("shard_size", 0, "shard_size must be >= 1, got 0"),
        ("harm_tolerance", float("nan"), "harm_tolerance: must be a finite number >= 0"),
        ("classifier", "no-such-model.joblib", "neither a built-in classifier"),
    ],
)
def test_a_config_refuses_a_bad_value_naming_the_field(field, value, message):
    with pytest.raises(InputError, match=re.escape(message)) as info:
        IdentifyConfig("pairs.npz", **{field: value})
    assert field in info.value.parameters


def test_a_device_without_a_planner_is_refused_before_the_file_is_read(tmp_path):
    with pytest.raises(InputError, match="device: only with planner or weights"):
        run(IdentifyConfig(str(tmp_path / "absent.npz")), device="cpu")


def test_the_job_labels_the_replanned_pairs_and_stores_them(tmp_path):
    maps = generate_maps(8, 10, seed=4, n_starts=1)
    made = random_attack_on_optimal(maps, seed=1)
    made.pairs.save(tmp_path / "p.npz")
    db = str(tmp_path / "i.db")
    done = run(IdentifyConfig(str(tmp_path / "p.npz"), planner="optimal", shard_size=3), db=db, name="transfer")
    pairs = PairSet.load(tmp_path / "p.npz")
    direct = identify(replan(pairs, load_planner("optimal", 10)))
    assert np.array_equal(done.identification.labels, direct.labels)
    summary = done.to_dict()
    assert summary["pairs"] == len(pairs) and summary["run_id"] == done.run_id
    assert summary["adversarial"] == int(direct.attack.sum())
    with Store.open(db, create=False) as store:
        assert store.resolve_run("transfer") == done.run_id
        assert store.run_info(done.run_id)["config"]["planner"] == "optimal"
