"""Every attack strategy on a search planner (paths, no policy): what each uses, and the saliency fallback recorded."""

from pathlib import Path

import numpy as np
import pytest
import torch

from tests.attacks.test_strategies import assert_valid
from vinadv.attacks.strategies import STRATEGIES, AttackContext, KeyPointsAttack, SaliencyAttack, make_attack
from vinadv.attacks.validity import valid_cells
from vinadv.grid import generate_maps
from vinadv.identify import rule_strength
from vinadv.planners.classical.optimal import OptimalPlanner
from vinadv.planners.registry import load_planner
from vinadv.planners.search import UserSearchPlanner
from vinadv.testing.planners import planning_vin

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "my_search_planner.py"
SIZE = 10


@pytest.fixture(scope="module")
def maps():
    return generate_maps(12, SIZE, seed=3, n_starts=1)


def bfs():
    return load_planner(f"{EXAMPLE}:make", SIZE)


def context(planner, maps):
    """The first step's `AttackContext` of `planner` on `maps` (first start each)."""
    obstacles, starts, goals = maps.obstacles, maps.starts[:, 0], maps.goals
    return AttackContext(
        obstacles,
        starts,
        goals,
        valid_cells(obstacles, starts, goals, True),
        planner.plan(obstacles, starts, goals),
        planner,
        np.random.default_rng(0),
    )


@pytest.mark.parametrize("strategy", list(STRATEGIES))
def test_every_strategy_runs_on_a_search_planner(strategy, maps):
    planner = bfs()
    result = make_attack(strategy, per_map=1, seed=5, budget=4).attack(
        maps.obstacles, maps.starts[:, 0], maps.goals, planner, strength=rule_strength
    )
    pairs = result.pairs
    assert len(pairs) > 0
    assert_valid(pairs, maps)
    assert pairs.params["planner"] == planner.spec()
    again = planner.plan(pairs.obstacles_a, pairs.starts, pairs.goals)
    assert again.paths == pairs.path_a  # the planner's own paths on the adversarial maps
    # saliency without gradients is ranked as key-points, and the pairs say so; no other strategy falls back
    assert pairs.params.get("ranked_as") == ("key-points" if strategy == "saliency" else None)


def test_the_saliency_fallback_is_recorded_for_optimal_too_and_not_for_the_vin(maps):
    args = (maps.obstacles[:4], maps.starts[:4, 0], maps.goals[:4])
    optimal = SaliencyAttack(budget=2).attack(*args, OptimalPlanner(SIZE)).pairs
    vin = SaliencyAttack(budget=2).attack(*args, planning_vin(SIZE, seed=1, noise=0.1)).pairs
    assert optimal.params["ranked_as"] == "key-points" and "ranked_as" not in vin.params


def test_saliency_without_gradients_ranks_a_search_planner_as_key_points(maps):
    ctx = context(bfs(), maps)
    np.testing.assert_array_equal(SaliencyAttack().candidate_scores(ctx), KeyPointsAttack().candidate_scores(ctx))


class Flat:
    """The example's search with a value map of its own, constant: no cell is steeper than another."""

    def __init__(self):
        self.inner = load_planner(f"{EXAMPLE}:make", SIZE).impl

    def plan_paths(self, *args):
        return self.inner.plan_paths(*args)

    def value_maps(self, obstacles, goals):
        return np.zeros(obstacles.shape)


def test_key_points_ranks_by_the_planner_s_own_value_map_else_the_cost_to_go(maps):
    ctx_default = context(bfs(), maps)
    ctx_flat = context(UserSearchPlanner(Flat(), "flat.py:make", SIZE), maps)
    default = KeyPointsAttack().candidate_scores(ctx_default)
    flat = KeyPointsAttack().candidate_scores(ctx_flat)
    tier3 = (default >= 1) & (default < 2)
    assert tier3.any()
    # a flat value map: every tier-3 cell scores exactly 1; the cost-to-go spreads them
    np.testing.assert_array_equal(flat[tier3], 1.0)
    assert len(np.unique(default[tier3])) > 1
    np.testing.assert_array_equal(flat[~tier3], default[~tier3])  # the other tiers do not read the value map


class SoftPaths(torch.nn.Module):
    """A differentiable stand-in path map: a fixed smoothing of the obstacles, the start and the goal."""

    def __init__(self):
        super().__init__()
        torch.manual_seed(0)
        self.conv = torch.nn.Conv2d(2, 1, 3, padding=1)

    def forward(self, obstacles, starts, goals):
        ends = torch.zeros_like(obstacles)
        rows = torch.arange(len(obstacles))
        ends[rows, starts[:, 0], starts[:, 1]] = 1.0
        ends[rows, goals[:, 0], goals[:, 1]] = 1.0
        return torch.sigmoid(self.conv(torch.stack([obstacles, ends], dim=1)))[:, 0] * obstacles.square().add(1)


class Differentiable(Flat):
    def __init__(self):
        super().__init__()
        self.differentiable_paths = SoftPaths()


def test_saliency_on_a_differentiable_search_planner_is_the_path_map_gradient(maps):
    planner = UserSearchPlanner(Differentiable(), "soft.py:make", SIZE)
    ctx = context(planner, maps)
    scores = SaliencyAttack().candidate_scores(ctx)
    module = planner.differentiable_paths
    # oracle: one map at a time, the path map summed over the path's cells, differentiated by autograd
    for b in range(4):
        x = torch.tensor(maps.obstacles[b : b + 1], dtype=torch.float32, requires_grad=True)
        path_map = module(x, torch.tensor(ctx.starts[b : b + 1]), torch.tensor(ctx.goals[b : b + 1]))[0]
        total = sum(path_map[r, c] for r, c in ctx.plans.paths[b].tolist())
        (grad,) = torch.autograd.grad(total, x)
        np.testing.assert_allclose(scores[b], -grad[0].numpy(), rtol=1e-5, atol=1e-7)
    pairs = SaliencyAttack(budget=2).attack(maps.obstacles[:4], maps.starts[:4, 0], maps.goals[:4], planner).pairs
    assert "ranked_as" not in pairs.params
