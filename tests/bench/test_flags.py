"""Each flag on a constructed planner: zero gradients are flagged as masking (and a planner with real gradients is
not), two forward passes that differ as non-determinism, a planner that mostly fails on clean maps as too weak; and
the exhaustive-versus-ranking rule against its documented threshold."""

from __future__ import annotations

import pytest
import torch
from torch import nn

from vinadv.bench.flags import differs_between_passes, gradient_is_masked, raise_flags
from vinadv.bench.suites import get_suite
from vinadv.grid import generate_maps
from vinadv.planners.classical.optimal import OptimalPlanner
from vinadv.planners.interface import TorchPlanner
from vinadv.planners.vin.planner import as_planner
from vinadv.testing.planners import planning_vin

SIZE = 10


class Constant(nn.Module):
    """Logits that do not depend on the map: every gradient is exactly zero (a masked planner)."""

    def forward(self, obstacles, goals):
        b, n, _ = obstacles.shape
        logits = torch.zeros(b, 8, n, n) + torch.arange(8.0)[None, :, None, None]
        return logits + 0.0 * obstacles.sum()  # in the graph, with a zero gradient


class Noisy(nn.Module):
    """A VIN-shaped planner with dropout left on: two passes differ."""

    def __init__(self):
        super().__init__()
        self.inner = Constant()

    def forward(self, obstacles, goals):
        return self.inner(obstacles, goals) + torch.randn(obstacles.shape[0], 8, *obstacles.shape[1:])


def _maps():
    maps = generate_maps(6, SIZE, seed=2, n_starts=1)
    return maps.obstacles, maps.starts[:, 0], maps.goals


def test_zero_gradients_are_flagged_as_masking():
    masked = TorchPlanner(Constant(), "constant", SIZE)
    assert gradient_is_masked(masked, *_maps()) is True
    assert gradient_is_masked(OptimalPlanner(SIZE), *_maps()) is None  # no gradient, nothing masked
    flags = raise_flags(get_suite("vin28-quick-v1"), {"gradient_masked": True}, 0.9, {})
    assert flags["gradient_masking"]["raised"] and "zero" in flags["gradient_masking"]["why"]


@pytest.mark.slow
def test_a_vin_with_gradients_is_not_masked():
    assert gradient_is_masked(as_planner(planning_vin(SIZE, seed=1, noise=0.1), SIZE), *_maps()) is False


def test_two_passes_that_differ_are_flagged():
    torch.manual_seed(0)
    assert differs_between_passes(TorchPlanner(Noisy(), "noisy", SIZE), *_maps())
    assert not differs_between_passes(TorchPlanner(Constant(), "constant", SIZE), *_maps())
    assert not differs_between_passes(OptimalPlanner(SIZE), *_maps())
    flags = raise_flags(get_suite("vin28-quick-v1"), {"non_deterministic": True}, 0.9, {})
    assert flags["non_deterministic"]["raised"]


def test_too_weak_under_the_floor():
    suite = get_suite("vin28-quick-v1")
    assert suite.weak_clean_success == 0.5
    assert raise_flags(suite, {}, 0.49, {})["too_weak"]["raised"]
    assert not raise_flags(suite, {}, 0.5, {})["too_weak"]["raised"]
    assert raise_flags(suite, {}, None, {})["too_weak"]["raised"]


def _attacks(exhaustive: float, key_points: float, saliency: float) -> dict:
    def one(rate):
        return {"by_obstacles": [{"harmful_rate": rate}]}

    return {"add:exhaustive": one(exhaustive), "add:key-points": one(key_points), "add:saliency": one(saliency)}


def test_exhaustive_far_above_the_ranking_attacks_is_masking():
    suite = get_suite("vin28-v1")  # ratio 3, at least 10%
    flag = raise_flags(suite, {"gradient_masked": False}, 0.9, _attacks(0.31, 0.10, 0.05))["gradient_masking"]
    assert flag["raised"] and "exhaustive" in flag["why"]
    assert not raise_flags(suite, {}, 0.9, _attacks(0.30, 0.10, 0.05))["gradient_masking"]["raised"]  # not over 3x
    assert not raise_flags(suite, {}, 0.9, _attacks(0.09, 0.0, 0.0))["gradient_masking"]["raised"]  # under 10%
