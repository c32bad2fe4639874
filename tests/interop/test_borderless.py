"""Maps without a border wall (GPPN mazes): the grid edge is the wall for Dijkstra, the engine, attacks, eval."""

from __future__ import annotations

import numpy as np
import pytest

from tests.grid.oracle import brute_distances
from tests.interop.conftest import borderless
from vinadv.attacks.strategies import make_attack
from vinadv.attacks.validity import valid_cells
from vinadv.evaluation.planner_metrics import evaluate_vin
from vinadv.grid import generate_maps, shortest_distances
from vinadv.grid.mapset import MapSet
from vinadv.grid.shortest_paths import expert_paths
from vinadv.planners.vin.engine import plan_maps
from vinadv.planners.vin.reference import plan_reference
from vinadv.testing.planners import planning_vin


@pytest.fixture(scope="module")
def edge_maps():
    """Maps with random free edge cells; goals moved to a free edge cell on half of them; starts on the edge."""
    base = generate_maps(16, 10, seed=9, n_starts=1)
    obstacles = borderless(base, seed=2)
    rng = np.random.default_rng(3)
    goals = base.goals.copy()
    starts = []
    for i in range(len(obstacles)):
        edge = [(r, c) for r in range(10) for c in range(10) if (r in (0, 9) or c in (0, 9)) and not obstacles[i, r, c]]
        if i % 2 and edge:
            goals[i] = edge[rng.integers(len(edge))]
        dist = brute_distances(obstacles[i].tolist(), tuple(goals[i]))
        reach = [cell for cell in edge if dist[cell][1] >= 2] or [c for c, (d, m) in dist.items() if m >= 2]
        starts.append(reach[rng.integers(len(reach))])
    return obstacles, goals, np.array(starts)


def test_free_edge_cells_exist(edge_maps):
    obstacles, goals, starts = edge_maps
    assert (~obstacles[:, 0, :]).any() and (~obstacles[:, :, -1]).any()
    assert sum(g[0] in (0, 9) or g[1] in (0, 9) for g in goals) >= 4


@pytest.mark.parametrize("corner_cutting", [True, False])
def test_dijkstra_matches_brute_force_without_a_border(edge_maps, corner_cutting):
    obstacles, goals, _ = edge_maps
    dist, moves = shortest_distances(obstacles, goals, corner_cutting)
    for i in range(len(obstacles)):
        want = brute_distances(obstacles[i].tolist(), tuple(goals[i]), corner_cutting)
        for (r, c), (cost, n_moves) in want.items():
            assert dist[i, r, c] == pytest.approx(cost) and moves[i, r, c] == n_moves


@pytest.mark.parametrize("corner_cutting", [True, False])
def test_engine_matches_the_reference_planner_without_a_border(edge_maps, corner_cutting):
    obstacles, goals, starts = edge_maps
    model = planning_vin(10, seed=5)
    fast = plan_maps(obstacles, goals, starts[:, None, :], model, corner_cutting)
    ref = plan_reference(obstacles, starts, goals, model, corner_cutting)
    assert fast.paths == ref.paths
    np.testing.assert_array_equal(fast.termination, ref.termination)
    cells = fast.paths.cells
    assert cells.min() >= 0 and cells.max() < 10


def test_attacks_and_eval_without_a_border(edge_maps):
    obstacles, goals, starts = edge_maps
    model = planning_vin(10, seed=5)
    for name in ("random", "near-path", "key-points"):
        pairs = make_attack(name, per_map=2, seed=1).attack(obstacles, starts, goals, model).pairs
        assert len(pairs)
        valid = valid_cells(obstacles, starts, goals)
        added = pairs.added[:, 0]
        assert valid[pairs.map_index, added[:, 0], added[:, 1]].all()
        # the adversarial map is the original plus the added cell, edge cells included
        diff = pairs.obstacles_a ^ pairs.obstacles_o
        assert (diff.reshape(len(pairs), -1).sum(axis=1) == 1).all()
    costs, expert = expert_paths(obstacles, goals, starts[:, None, :])
    maps = MapSet(obstacles=obstacles, goals=goals, starts=starts[:, None, :], expert_costs=costs, expert=expert)
    metrics = evaluate_vin(model, maps)
    assert metrics["rollouts"] == len(obstacles)
    assert sum(metrics["terminations"].values()) == len(obstacles)
