import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.grid.oracle import MOVES, brute_distances, legal, step_cost
from vinadv.grid import (
    ACTION_DELTAS,
    expert_paths,
    optimal_actions,
    shortest_distances,
    valid_moves,
)
from vinadv.grid.moves import move_model
from vinadv.grid.shortest_paths import dijkstra_batch


@st.composite
def small_maps(draw):
    n = draw(st.integers(3, 8))
    m = draw(st.integers(3, 8))
    cells = draw(st.lists(st.booleans(), min_size=n * m, max_size=n * m))
    obstacles = np.array(cells, dtype=bool).reshape(n, m)
    goal = (draw(st.integers(0, n - 1)), draw(st.integers(0, m - 1)))
    obstacles[goal] = False
    return obstacles, np.array(goal)


@settings(max_examples=120, deadline=None)
@given(small_maps(), st.booleans(), st.sampled_from(MOVES))
def test_dijkstra_matches_brute_force(case, corner_cutting, moves):
    obstacles, goal = case
    dist, counts = shortest_distances(obstacles[None], goal[None], corner_cutting, moves)
    best = brute_distances(obstacles.tolist(), goal, corner_cutting, moves)
    for (r, c), (cost, n_moves) in best.items():
        assert math.isclose(dist[0, r, c], cost, abs_tol=1e-9) or (math.isinf(cost) and math.isinf(dist[0, r, c]))
        assert counts[0, r, c] == n_moves
        if moves != "octile" and math.isfinite(cost):  # every move costs 1: the move count is the cost
            assert counts[0, r, c] == dist[0, r, c]


@settings(max_examples=60, deadline=None)
@given(small_maps(), st.booleans(), st.sampled_from(MOVES))
def test_optimal_actions_are_exactly_the_cost_preserving_legal_moves(case, corner_cutting, moves):
    obstacles, goal = case
    dist, _ = shortest_distances(obstacles[None], goal[None], corner_cutting, moves)
    opt = optimal_actions(dist, obstacles[None], corner_cutting, moves)[0]
    legal_np = valid_moves(obstacles[None], corner_cutting, moves)[0]
    best = brute_distances(obstacles.tolist(), goal, corner_cutting, moves)
    for (r, c), (cost, _) in best.items():
        for a, (dr, dc) in enumerate(ACTION_DELTAS):
            is_legal = legal(obstacles.tolist(), r, c, a, corner_cutting, moves)
            if not obstacles[r, c]:
                assert legal_np[r, c, a] == is_legal
            expected = (
                not obstacles[r, c]
                and math.isfinite(cost)
                and cost > 0
                and is_legal
                and math.isclose(best[(r + dr, c + dc)][0] + step_cost(a, moves), cost, abs_tol=1e-9)
            )
            assert opt[r, c, a] == expected


def test_batches_agree_with_single_maps():
    rng = np.random.default_rng(3)
    obstacles = rng.random((20, 12, 12)) < 0.3
    goals = rng.integers(0, 12, (20, 2))
    obstacles[np.arange(20), goals[:, 0], goals[:, 1]] = False
    obstacles[[4, 5], goals[[4, 5], 0], goals[[4, 5], 1]] = True  # goals on an obstacle: nothing reaches them
    dist, moves = shortest_distances(obstacles, goals)
    assert np.isinf(dist[4]).all() and (moves[5] == -1).all()
    for i in range(20):
        d1, m1 = shortest_distances(obstacles[i : i + 1], goals[i : i + 1])
        np.testing.assert_array_equal(d1[0], dist[i])
        np.testing.assert_array_equal(m1[0], moves[i])
    # the kernel's runs of maps share their scratch: any cut of the batch gives the same maps
    model = move_model("octile")
    for pieces in (1, 3, 20):
        d, m = np.empty_like(dist), np.empty_like(moves)
        dijkstra_batch(obstacles, goals.astype(np.int64), False, model.deltas, model.costs, d, m, pieces)
        d1, m1 = shortest_distances(obstacles, goals, corner_cutting=False)
        np.testing.assert_array_equal(d, d1)
        np.testing.assert_array_equal(m, m1)


def test_corner_cutting_option_blocks_squeezing_between_two_obstacles():
    obstacles = np.zeros((3, 3), dtype=bool)
    obstacles[0, 1] = obstacles[1, 0] = True  # (0,0) -> (1,1) passes between them
    goal = np.array([[0, 0]])
    dist_cut, _ = shortest_distances(obstacles[None], goal, corner_cutting=True)
    dist_nocut, _ = shortest_distances(obstacles[None], goal, corner_cutting=False)
    assert math.isclose(dist_cut[0, 1, 1], math.sqrt(2))
    assert math.isinf(dist_nocut[0, 1, 1])


@settings(max_examples=40, deadline=None)
@given(small_maps(), st.booleans(), st.integers(0, 2**31), st.sampled_from(MOVES))
def test_expert_paths_are_legal_and_optimal(case, corner_cutting, seed, moves):
    obstacles, goal = case
    best = brute_distances(obstacles.tolist(), goal, corner_cutting, moves)
    reachable = [cell for cell, (cost, _) in best.items() if math.isfinite(cost)]
    rng = np.random.default_rng(seed)
    starts = np.array([reachable[i] for i in rng.integers(0, len(reachable), 3)])
    costs, paths = expert_paths(obstacles[None], goal[None], starts[None], corner_cutting, moves)
    for s, path in enumerate(paths.unpack()):
        assert tuple(path[0]) == tuple(starts[s]) and tuple(path[-1]) == tuple(goal)
        cost = 0.0
        for (r, c), (r2, c2) in zip(path[:-1], path[1:]):
            a = [tuple(d) for d in ACTION_DELTAS.tolist()].index((r2 - r, c2 - c))
            assert legal(obstacles.tolist(), r, c, a, corner_cutting, moves)
            cost += step_cost(a, moves)
        assert math.isclose(costs[0, s], best[tuple(starts[s])][0], abs_tol=1e-9)
        assert math.isclose(cost, costs[0, s], abs_tol=1e-9)
        assert len(path) - 1 == best[tuple(starts[s])][1]
    if moves == "octile":
        np.testing.assert_allclose(paths.costs(), costs[0], atol=1e-9)


def test_movement_models_on_an_open_map():
    """From the corner of an open 5x5 map to the opposite one: 4 diagonals (octile 4 sqrt 2, moore 4), or 8 straight
    moves (news); the news expert path never moves diagonally."""
    obstacles = np.zeros((1, 5, 5), dtype=bool)
    goal, start = np.array([[4, 4]]), np.array([[[0, 0]]])
    want = {"octile": (4 * math.sqrt(2), 4), "moore": (4.0, 4), "news": (8.0, 8)}
    for moves, (cost, count) in want.items():
        dist, counts = shortest_distances(obstacles, goal, moves=moves)
        assert math.isclose(dist[0, 0, 0], cost) and counts[0, 0, 0] == count
        costs, paths = expert_paths(obstacles, goal, start, moves=moves)
        steps = np.abs(np.diff(paths[0], axis=0))
        assert math.isclose(costs[0, 0], cost) and len(paths[0]) == count + 1
        assert (steps.sum(axis=1) == 1).all() if moves == "news" else (steps.sum(axis=1) == 2).all()
    assert not valid_moves(obstacles, moves="news")[..., 4:].any()
