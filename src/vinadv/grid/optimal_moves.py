"""The optimal move count L from one start to its goal, by A* under a movement model: what a rollout's step limit
2L needs.

`shortest_distances` gives L for every cell of a map at once (Dijkstra from the goal); a planner needs it for
a few starts only (a rollout needs L only once it has made more moves than a lower bound of 2L, which few do), so
it searches from each start to its goal and stops there.
"""

from __future__ import annotations

import numba
import numpy as np

from vinadv.grid.moves import DEFAULT_MOVES, MoveModel, move_model
from vinadv.grid.shortest_paths import heap_pop, heap_push

__all__ = ["optimal_moves", "optimal_moves_kernel"]


def optimal_moves(
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    map_index: np.ndarray,
    corner_cutting: bool = True,
    moves: str | MoveModel = DEFAULT_MOVES,
) -> np.ndarray:
    """Moves of an optimal path from `starts (R, 2)` to the goal of map `map_index (R,)` under the movement model
    `moves`: `(R,)` int64, -1 where the goal cannot be reached. obstacles `(B, N, N)` bool, goals `(B, 2)`."""
    model = move_model(moves)
    out = np.empty(len(starts), dtype=np.int64)
    optimal_moves_kernel(
        np.ascontiguousarray(obstacles, dtype=bool),
        np.ascontiguousarray(goals, dtype=np.int64),
        np.ascontiguousarray(starts, dtype=np.int64).reshape(-1, 2),
        np.ascontiguousarray(map_index, dtype=np.int64),
        bool(corner_cutting),
        model.deltas,
        model.diagonal_cost,
        out,
    )
    return out


@numba.njit(cache=True, nogil=True)
def optimal_moves_kernel(obstacles, goals, starts, map_index, corner_cutting, deltas, diagonal_cost, out):
    """A* from each start to its goal, stopping at the goal: the move count of an optimal path, -1 when unreachable.

    `deltas (A, 2)`: the model's moves (`MoveModel.deltas`); a straight move costs 1, a diagonal `diagonal_cost`
    (`MoveModel.diagonal_cost`: sqrt 2 on octile, 1 on moore; news has no diagonal move, and its 2 makes the
    heuristic Manhattan). The heuristic `(max - min) + min * diagonal_cost` over the row and column distances (octile,
    Chebyshev, Manhattan distance) is consistent. Costs are kept as integer pairs (a straight, b diagonal moves) and
    compared as a + b * diagonal_cost: on octile an optimal cost fixes a and b, on the unit-cost models the cost is
    a + b, so the move count a + b is that of every optimal path."""
    n = obstacles.shape[1]
    cap = 8 * n * n + 1
    heap_key = np.empty(cap)
    heap_cell = np.empty(cap, dtype=np.int64)
    g_a = np.empty(n * n, dtype=np.int64)
    g_b = np.empty(n * n, dtype=np.int64)
    seen = np.zeros(n * n, dtype=np.int64)  # stamp: t + 1 once the cell has a tentative cost in this search
    done = np.zeros(n * n, dtype=np.int64)
    for t in range(len(starts)):
        m = map_index[t]
        sr, sc = starts[t, 0], starts[t, 1]
        gr, gc = goals[m, 0], goals[m, 1]
        stamp = t + 1
        if obstacles[m, sr, sc] or obstacles[m, gr, gc]:  # as shortest_distances: obstacles are unreachable
            out[t] = -1
            continue
        start = sr * n + sc
        g_a[start] = 0
        g_b[start] = 0
        seen[start] = stamp
        size = heap_push(heap_key, heap_cell, 0, 0.0, start)
        result = -1
        while size > 0:
            _, cell, size = heap_pop(heap_key, heap_cell, size)
            if done[cell] == stamp:
                continue
            done[cell] = stamp
            r, c = cell // n, cell % n
            if r == gr and c == gc:
                result = g_a[cell] + g_b[cell]
                break
            for a in range(deltas.shape[0]):
                dr, dc = deltas[a, 0], deltas[a, 1]
                nr, nc = r + dr, c + dc
                if nr < 0 or nr >= n or nc < 0 or nc >= n or obstacles[m, nr, nc]:
                    continue
                diag = dr != 0 and dc != 0
                if diag and not corner_cutting and (obstacles[m, nr, c] or obstacles[m, r, nc]):
                    continue
                nb = nr * n + nc
                if done[nb] == stamp:
                    continue
                na = g_a[cell] + (0 if diag else 1)
                nbb = g_b[cell] + (1 if diag else 0)
                g = na + nbb * diagonal_cost
                if seen[nb] == stamp and g_a[nb] + g_b[nb] * diagonal_cost <= g:
                    continue
                seen[nb] = stamp
                g_a[nb] = na
                g_b[nb] = nbb
                dy, dx = abs(nr - gr), abs(nc - gc)
                key = g + (max(dy, dx) - min(dy, dx)) + min(dy, dx) * diagonal_cost
                size = heap_push(heap_key, heap_cell, size, key, nb)
        out[t] = result
