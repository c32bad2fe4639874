"""`vinadv.jobs.attack`: the config refuses a bad value naming the field; the job makes the pairs of the attack call
itself (`attack_maps`), on the maps file's first starts."""

import re

import numpy as np
import pytest

from tests.jobs.optimal_attack import random_attack_on_optimal
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.jobs.attack import AttackConfig, run


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("seed", -1, "seed"),
        ("shard_size", 0, "shard_size must be >= 1, got 0"),
        ("harm_rtol", float("nan"), "harm_rtol: must be a finite number >= 0"),
        ("objective", "fast", "objective: 'fast' is not one of"),
    ],
)
def test_a_config_refuses_a_bad_value_naming_the_field(field, value, message):
    with pytest.raises(InputError, match=re.escape(message)) as info:
        AttackConfig("maps.npz", "random", **{field: value})
    assert field in info.value.parameters


def test_the_job_makes_the_pairs_of_the_attack_call(tmp_path):
    maps = generate_maps(6, 10, seed=2, n_starts=2)
    maps.save(tmp_path / "m.npz")
    outcome = run(AttackConfig(str(tmp_path / "m.npz"), "random", per_map=2, seed=5, planner="optimal"))
    direct = random_attack_on_optimal(maps, seed=5)
    assert np.array_equal(outcome.pairs.added, direct.pairs.added) and outcome.pairs.path_a == direct.pairs.path_a
    summary = outcome.to_dict()
    assert summary["pairs"] == len(direct.pairs) and summary["strategy"] == "random" and summary["maps"] == 6
