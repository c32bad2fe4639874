"""The `optimal` planner against brute-force shortest paths and `expert_paths`."""

import math

import numpy as np
import pytest

from tests.grid.oracle import brute_distances
from vinadv.grid import expert_paths, generate_maps
from vinadv.planners.classical.optimal import ILLEGAL, OptimalPlanner
from vinadv.planners.interface import PlannerError
from vinadv.planners.registry import PlannerRef, load_planner

DELTAS = [(-1, 0), (1, 0), (0, 1), (0, -1), (-1, 1), (-1, -1), (1, 1), (1, -1)]


def legal(obs, r, c, a, corner_cutting):
    n = len(obs)
    dr, dc = DELTAS[a]
    nr, nc = r + dr, c + dc
    if not (0 <= nr < n and 0 <= nc < n) or obs[nr][nc]:
        return False
    return corner_cutting or not (dr and dc) or not (obs[nr][c] or obs[r][nc])


def brute_cost_to_go(obs, goal, corner_cutting):
    """Relax every move until nothing changes (Bellman-Ford): slow and obviously right."""
    n = len(obs)
    best = {(r, c): math.inf for r in range(n) for c in range(n)}
    best[goal] = 0.0
    changed = True
    while changed:
        changed = False
        for (r, c), _cost in list(best.items()):
            if obs[r][c] or (r, c) == goal:
                continue
            for a, (dr, dc) in enumerate(DELTAS):
                if legal(obs, r, c, a, corner_cutting):
                    via = best[(r + dr, c + dc)] + (math.sqrt(2) if dr and dc else 1.0)
                    if via < best[(r, c)] - 1e-9:
                        best[(r, c)] = via
                        changed = True
    return best


def brute_path(obs, start, goal, corner_cutting):
    """Follow, from the start, the lowest-index move that keeps the path optimal (DESIGN.md's tie-break)."""
    best = brute_cost_to_go(obs, goal, corner_cutting)
    cell, path = start, [start]
    while cell != goal:
        r, c = cell
        for a, (dr, dc) in enumerate(DELTAS):
            step = math.sqrt(2) if dr and dc else 1.0
            if legal(obs, r, c, a, corner_cutting) and abs(step + best[(r + dr, c + dc)] - best[cell]) <= 1e-9:
                cell = (r + dr, c + dc)
                break
        path.append(cell)
    return path, best[start]


@pytest.mark.parametrize("corner_cutting", [True, False])
def test_paths_equal_brute_force_shortest_paths(corner_cutting):
    maps = generate_maps(25, 9, seed=4, n_starts=3, corner_cutting=corner_cutting)
    result = OptimalPlanner(9, corner_cutting).plan(maps.obstacles, maps.starts, maps.goals, corner_cutting)
    assert result.reached.all()
    for b in range(len(maps)):
        obs = maps.obstacles[b].tolist()
        for s in range(3):
            want, cost = brute_path(
                obs, tuple(map(int, maps.starts[b, s])), tuple(map(int, maps.goals[b])), corner_cutting
            )
            np.testing.assert_array_equal(result.paths[b * 3 + s], np.array(want))
            assert cost == pytest.approx(maps.expert_costs[b, s], abs=1e-9)


@pytest.mark.parametrize("corner_cutting", [True, False])
def test_paths_equal_expert_paths_at_28(corner_cutting):
    maps = generate_maps(200, 28, seed=8, n_starts=4, corner_cutting=corner_cutting)
    result = OptimalPlanner(28, corner_cutting).plan(maps.obstacles, maps.starts, maps.goals, corner_cutting)
    _, expert = expert_paths(maps.obstacles, maps.goals, maps.starts, corner_cutting)
    assert result.paths == expert
    assert result.reached.all()


def test_a_start_cut_off_from_the_goal_does_not_reach_it():
    obstacles = np.zeros((1, 6, 6), bool)
    obstacles[0, :, 3] = True  # a wall between the two halves
    result = OptimalPlanner(6).plan(obstacles, np.array([[[2, 1]]]), np.array([[2, 5]]))
    assert not result.reached[0] and result.termination_names[0] in ("loop", "step_limit", "collision")


def test_refuses_another_move_rule():
    maps = generate_maps(2, 8, seed=1, n_starts=1)
    with pytest.raises(ValueError, match="corner_cutting=True"):
        OptimalPlanner(8, True).plan(maps.obstacles, maps.starts, maps.goals, corner_cutting=False)


@pytest.mark.parametrize("moves", ["moore", "news"])
def test_follows_the_movement_model(moves):
    """On the maps' model: value map minus the model's cost-to-go (plain-Python oracle), the expert paths of that
    model, and on `news` every diagonal illegal; `for_moves` gives the planner of another model, and the ref a
    worker loads keeps it."""
    maps = generate_maps(20, 10, seed=6, n_starts=2, moves=moves)
    planner = load_planner("optimal", 10, moves=moves)
    assert planner.moves == moves and planner.config == {"corner_cutting": True, "moves": moves}
    assert OptimalPlanner(10).for_moves(moves).moves == moves and planner.for_moves(moves) is planner
    values = planner.value_maps(maps.obstacles, maps.goals)
    for b in range(3):
        best = brute_distances(maps.obstacles[b].tolist(), tuple(maps.goals[b]), True, moves)
        for (r, c), (cost, _) in best.items():
            assert (math.isnan(values[b, r, c]) and math.isinf(cost)) or math.isclose(-values[b, r, c], cost)
    result = planner.plan(maps.obstacles, maps.starts, maps.goals)
    assert result.paths == maps.expert and result.reached.all()
    logits = planner.logits(maps.obstacles, maps.goals)
    assert (logits[:, 4:] == ILLEGAL).all() if moves == "news" else (logits[:, 4:] > ILLEGAL).any()
    assert PlannerRef.of(planner, "optimal", None, True).load().moves == moves
    with pytest.raises(PlannerError, match=f"planner 'vin' plans octile moves .*the maps use '{moves}' moves"):
        load_planner("vin", 28, moves=moves)
