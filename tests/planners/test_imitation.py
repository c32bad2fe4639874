"""The imitation loop's pieces (`vinadv.planners.imitation`): the optimal-set loss against brute force, the
supervision against the oracle, the settings' checks. Runs of the loop: `tests/planners/vin/test_training.py`,
`tests/planners/gppn/test_training.py`, `tests/test_hardening.py`."""

import math

import numpy as np
import pytest
import torch

from tests.grid.oracle import optimal_action_mask
from vinadv.errors import InputError
from vinadv.grid import generate_maps
from vinadv.planners.imitation import TrainConfig, bits_to_mask, optimal_action_bits, optimal_set_loss


def test_optimal_set_loss_matches_brute_force():
    rng = np.random.default_rng(0)
    logits = rng.normal(scale=3.0, size=(50, 8))
    mask = rng.random((50, 8)) < 0.3
    mask[np.arange(50), rng.integers(0, 8, 50)] = True  # at least one optimal action per row
    expected = []
    for row, opt in zip(logits, mask):
        total = sum(math.exp(v) for v in row)
        expected.append(-math.log(sum(math.exp(v) for v, o in zip(row, opt) if o) / total))
    got = optimal_set_loss(torch.tensor(logits), torch.tensor(mask))
    assert float(got) == pytest.approx(np.mean(expected), rel=1e-9)
    # one optimal action: plain cross-entropy
    single = np.zeros((50, 8), dtype=bool)
    single[np.arange(50), np.argmax(logits, axis=1)] = True
    ce = torch.nn.functional.cross_entropy(torch.tensor(logits), torch.tensor(np.argmax(logits, axis=1)))
    assert float(optimal_set_loss(torch.tensor(logits), torch.tensor(single))) == pytest.approx(float(ce))


def test_optimal_action_bits_match_the_brute_force_oracle():
    maps = generate_maps(4, 8, seed=2, n_starts=1)
    bits = optimal_action_bits(maps)
    mask = bits_to_mask(torch.from_numpy(bits)).numpy()
    for i in range(len(maps)):
        want = optimal_action_mask(maps.obstacles[i].tolist(), tuple(maps.goals[i]))
        np.testing.assert_array_equal(mask[i], np.array(want), err_msg=f"map {i}")


@pytest.mark.parametrize(
    ("fields", "names"),
    [
        ({"vi_init": "identity"}, ("vi_init",)),
        ({"vi_init": "shift", "planner": "gppn"}, ("vi_init",)),
        ({"vi_init": "shift", "init": "w.pt"}, ("vi_init", "init")),
    ],
)
def test_vi_init_is_checked(fields, names):
    with pytest.raises(InputError) as err:
        TrainConfig(**fields).validate()
    assert err.value.parameters == names
