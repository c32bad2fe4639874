"""Every attack strategy on TransPath, on one tiny case: a 64x64 map (the model's only size) that is all obstacles but
a 2x3 room, so that each strategy plans a handful of maps. Saliency takes the differentiable search's gradient,
key-points the planner's own value maps, exhaustive every valid cell."""

from types import SimpleNamespace

import numpy as np
import pytest
import torch

from tests.attacks.test_strategies import assert_valid
from vinadv.attacks.strategies import STRATEGIES, AttackContext, KeyPointsAttack, SaliencyAttack, make_attack
from vinadv.attacks.validity import valid_cells
from vinadv.identify import rule_strength
from vinadv.planners.registry import load_planner

pytestmark = pytest.mark.slow  # a TransPath forward is about 0.15 s a map on the CPU: some 20 here


@pytest.fixture(scope="module")
def room():
    obstacles = np.ones((1, 64, 64), dtype=bool)
    obstacles[0, 20:22, 20:23] = False
    return SimpleNamespace(obstacles=obstacles, starts=np.array([[[20, 20]]]), goals=np.array([[21, 22]]))


@pytest.fixture(scope="module")
def planners():
    torch.set_num_threads(1)
    return {name: load_planner(name, 64) for name in ("transpath-cf", "transpath-focal")}


def attack(strategy, planner, room, **kwargs):
    return make_attack(strategy, per_map=kwargs.pop("per_map", 1), seed=3, budget=2, **kwargs).attack(
        room.obstacles, room.starts[:, 0], room.goals, planner, strength=rule_strength
    )


@pytest.mark.parametrize("strategy", list(STRATEGIES))
def test_every_strategy_runs_on_transpath_cf(strategy, planners, room):
    planner = planners["transpath-cf"]
    pairs = attack(strategy, planner, room, per_map=0 if strategy == "exhaustive" else 1).pairs
    assert len(pairs) > 0
    assert_valid(pairs, room)
    again = planner.plan(pairs.obstacles_a, pairs.starts, pairs.goals)
    assert again.paths == pairs.path_a
    assert "ranked_as" not in pairs.params  # saliency ranks by its own gradients
    if strategy == "exhaustive":  # every valid cell of the room: its 4 cells but the start and the goal
        valid = valid_cells(room.obstacles, room.starts[:, 0], room.goals)
        assert sorted(map(tuple, pairs.added[:, 0].tolist())) == sorted(map(tuple, np.argwhere(valid[0]).tolist()))


@pytest.mark.parametrize("name", ["transpath-cf", "transpath-focal"])
def test_saliency_ranks_by_the_differentiable_search_s_gradient(name, planners, room):
    """Saliency's scores are the differentiable search's gradient, not key-points' tiers (its fallback)."""
    planner = planners[name]
    obstacles, starts, goals = room.obstacles, room.starts[:, 0], room.goals
    valid = valid_cells(obstacles, starts, goals)
    ctx = AttackContext(
        obstacles, starts, goals, valid, planner.plan(obstacles, starts, goals), planner, np.random.default_rng(0)
    )
    saliency = SaliencyAttack().candidate_scores(ctx)[valid]
    assert np.isfinite(saliency).all() and len(np.unique(saliency)) > 1
    assert not np.array_equal(saliency, KeyPointsAttack().candidate_scores(ctx)[valid])
    pairs = attack("saliency", planner, room).pairs
    assert len(pairs) == 1 and "ranked_as" not in pairs.params
