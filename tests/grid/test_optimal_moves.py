"""The A* optimal move count against Dijkstra's (`shortest_distances`) on random maps, walls and unreachable goals."""

import numpy as np
import pytest

from vinadv.grid import generate_maps, shortest_distances
from vinadv.grid.optimal_moves import optimal_moves


@pytest.mark.parametrize(
    "corner_cutting, moves", [(True, "octile"), (False, "octile"), (True, "moore"), (False, "moore"), (True, "news")]
)
def test_optimal_moves_match_dijkstra(corner_cutting, moves):
    maps = generate_maps(60, 16, seed=8, n_starts=4, corner_cutting=corner_cutting, moves=moves)
    obstacles = maps.obstacles.copy()
    obstacles[:10, 8, :] = True  # some goals unreachable from some starts
    obstacles[10:12, maps.goals[10:12, 0], maps.goals[10:12, 1]] = True  # goals on an obstacle: unreachable too
    starts = maps.starts.copy()
    for b in range(10):
        starts[b][obstacles[b, starts[b, :, 0], starts[b, :, 1]]] = maps.starts[b, 0]  # keep starts off the wall
    _, counts = shortest_distances(obstacles, maps.goals, corner_cutting, moves)
    want = counts[np.arange(60)[:, None], starts[..., 0], starts[..., 1]].reshape(-1)
    index = np.repeat(np.arange(60), 4)
    got = optimal_moves(obstacles, maps.goals, starts.reshape(-1, 2), index, corner_cutting=corner_cutting, moves=moves)
    np.testing.assert_array_equal(got, want)
    assert (got == -1).any() and (got > 0).any()
