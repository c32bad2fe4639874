"""Exact shortest paths on grid worlds under a movement model (`vinadv.grid.moves`), batched over many maps.

Dijkstra from the goal (the move graph is undirected: a move needs its destination free, and, without corner
cutting, both cells beside a diagonal too, which is symmetric), compiled with Numba and run in parallel over
maps; the model's actions and costs are the kernel's arguments. Besides the cost of every cell it returns the
number of moves of an optimal path, the same for every optimal path: on `octile` an optimal cost `a + b*sqrt(2)`
fixes the integers `a` and `b`, so `L = a + b`; on `moore` and `news` every move costs 1, so `L` is the cost.

Per-action outputs (`valid_moves`, `optimal_actions`) always have the 8 actions of `ACTION_DELTAS`: an action
outside the model (a diagonal on `news`) is never legal, so action indices mean the same move in every model.
"""

from __future__ import annotations

import numba
import numpy as np

from vinadv.grid.actions import N_ACTIONS
from vinadv.grid.moves import DEFAULT_MOVES, MoveModel, move_model
from vinadv.grid.paths import PackedPaths

# Costs are sums of 1 and sqrt(2); two different sums of up to a few thousand terms differ by far more.
COST_TOL = 1e-9


def valid_moves(
    obstacles: np.ndarray, corner_cutting: bool = True, moves: str | MoveModel = DEFAULT_MOVES
) -> np.ndarray:
    """Which of the 8 actions from each cell are legal moves: `(B, N, N, 8)` bool.

    A move is legal when it is one of the model's (`moves`), its destination is on the grid and free; without
    `corner_cutting`, a diagonal move also needs both orthogonal cells it passes between to be free. The origin
    cell itself is not checked.
    """
    model = move_model(moves)
    obstacles = np.asarray(obstacles, dtype=bool)
    b, n, m = obstacles.shape
    padded = np.ones((b, n + 2, m + 2), dtype=bool)
    padded[:, 1:-1, 1:-1] = obstacles
    free = ~padded
    out = np.zeros((b, n, m, N_ACTIONS), dtype=bool)
    for a, (dr, dc) in enumerate(model.deltas):
        ok = free[:, 1 + dr : 1 + dr + n, 1 + dc : 1 + dc + m]
        if not corner_cutting and dr != 0 and dc != 0:
            ok = ok & free[:, 1 + dr : 1 + dr + n, 1 : 1 + m] & free[:, 1 : 1 + n, 1 + dc : 1 + dc + m]
        out[..., a] = ok
    return out


@numba.njit(cache=True, nogil=True, inline="always")
def heap_push(keys, values, size, key, value):
    """Push `(key, value)` on the binary min-heap held in `keys[:size]`, `values[:size]`; returns the new size."""
    i = size
    while i > 0:
        parent = (i - 1) // 2
        if keys[parent] <= key:
            break
        keys[i] = keys[parent]
        values[i] = values[parent]
        i = parent
    keys[i] = key
    values[i] = value
    return size + 1


@numba.njit(cache=True, nogil=True, inline="always")
def heap_pop(keys, values, size):
    """Pop the smallest key of the heap `keys[:size]`; returns `(key, value, new size)`."""
    top_key, top_value = keys[0], values[0]
    size -= 1
    last_key, last_value = keys[size], values[size]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= size:
            break
        if child + 1 < size and keys[child + 1] < keys[child]:
            child += 1
        if keys[child] < last_key:
            keys[i] = keys[child]
            values[i] = values[child]
            i = child
        else:
            break
    keys[i] = last_key
    values[i] = last_value
    return top_key, top_value, size


@numba.njit(cache=True, nogil=True)
def _dijkstra_maps(lo, hi, obstacles, goals, corner_cutting, deltas, costs, dist, moves):
    """Dijkstra from the goal of maps `lo..hi-1` (see `dijkstra_batch`), on a copy of each map inside a ring of
    obstacles with cells as flat indices: no move needs a bounds check, and the scratch is allocated once."""
    n, m = obstacles.shape[1], obstacles.shape[2]
    w = m + 2
    n_act = deltas.shape[0]
    step = np.empty(n_act, dtype=np.int64)
    for a in range(n_act):
        step[a] = deltas[a, 0] * w + deltas[a, 1]
    blocked = np.ones((n + 2) * w, dtype=np.bool_)
    d = np.empty((n + 2) * w, dtype=np.float64)
    count = np.empty((n + 2) * w, dtype=np.int32)
    cap = n_act * n * m + 1  # a cell is pushed at most once per neighbour
    heap_key = np.empty(cap, dtype=np.float64)
    heap_val = np.empty(cap, dtype=np.int64)
    for b in range(lo, hi):
        for r in range(n):
            for c in range(m):
                blocked[(r + 1) * w + c + 1] = obstacles[b, r, c]
        d[:] = np.inf
        count[:] = -1
        gr, gc = goals[b, 0], goals[b, 1]
        if not obstacles[b, gr, gc]:
            goal = (gr + 1) * w + gc + 1
            d[goal] = 0.0
            count[goal] = 0
            size = heap_push(heap_key, heap_val, 0, 0.0, goal)
            while size > 0:
                key, node, size = heap_pop(heap_key, heap_val, size)
                if key > d[node]:  # a stale entry: each push lowers its cell's cost, so only the last one is not
                    continue
                for a in range(n_act):
                    nb = node + step[a]
                    if blocked[nb]:
                        continue
                    if not corner_cutting and deltas[a, 0] != 0 and deltas[a, 1] != 0:
                        if blocked[node + deltas[a, 0] * w] or blocked[node + deltas[a, 1]]:
                            continue
                    # a cell already settled never passes: its cost is at most `key`
                    nd = key + costs[a]
                    if nd < d[nb] - 1e-9:
                        d[nb] = nd
                        count[nb] = count[node] + 1
                        size = heap_push(heap_key, heap_val, size, nd, nb)
        for r in range(n):
            for c in range(m):
                dist[b, r, c] = d[(r + 1) * w + c + 1]
                moves[b, r, c] = count[(r + 1) * w + c + 1]


#: pieces of a batch per thread in `dijkstra_batch`, and the fewest maps in a piece (about a millisecond of work;
#: fewer maps are done in the calling thread)
PIECES_PER_THREAD = 4
MIN_PIECE = 16


@numba.njit(cache=True, parallel=True)
def dijkstra_batch(obstacles, goals, corner_cutting, deltas, costs, dist, moves, pieces):
    """Dijkstra from each goal, in parallel over maps in `pieces` runs of maps, with any move costs: obstacles
    `(B, N, N)` bool, goals `(B, 2)` int64, moves `deltas (A, 2)` costing `costs (A,)`; fills `dist (B, N, N)`
    float64 (inf: unreachable) and `moves (B, N, N)` int32 (-1: unreachable). `shortest_distances` is it with the
    action costs of DESIGN.md."""
    b = obstacles.shape[0]
    for p in numba.prange(pieces):
        lo, hi = b * p // pieces, b * (p + 1) // pieces
        _dijkstra_maps(lo, hi, obstacles, goals, corner_cutting, deltas, costs, dist, moves)


def shortest_distances(
    obstacles: np.ndarray, goals: np.ndarray, corner_cutting: bool = True, moves: str | MoveModel = DEFAULT_MOVES
) -> tuple[np.ndarray, np.ndarray]:
    """Optimal cost-to-goal and optimal move count of every cell, for a batch of maps.

    Args:
        obstacles: `(B, N, N)` bool, True = obstacle.
        goals: `(B, 2)` int, `(row, col)` of each goal.
        corner_cutting: whether a diagonal move may pass between two obstacles.
        moves: the movement model (`vinadv.grid.moves`): its moves and their costs.

    Returns:
        `dist (B, N, N) float64` (inf where the goal cannot be reached, obstacles included) and
        `counts (B, N, N) int32` (moves of an optimal path, -1 where unreachable).
    """
    obstacles = np.ascontiguousarray(obstacles, dtype=np.bool_)
    goals = np.ascontiguousarray(goals, dtype=np.int64)
    dist = np.empty(obstacles.shape, dtype=np.float64)
    model = move_model(moves)
    counts = np.empty(obstacles.shape, dtype=np.int32)
    if len(obstacles):
        args = (obstacles, goals, bool(corner_cutting), model.deltas, model.costs, dist, counts)
        pieces = min(len(obstacles) // MIN_PIECE, PIECES_PER_THREAD * numba.get_num_threads())
        if pieces > 1:
            dijkstra_batch(*args, pieces)
        else:  # a few maps: starting the threads would cost more than they save
            _dijkstra_maps(0, len(obstacles), *args)
    return dist, counts


def negative_cost_to_go(
    obstacles: np.ndarray, goals: np.ndarray, corner_cutting: bool = True, moves: str | MoveModel = DEFAULT_MOVES
) -> np.ndarray:
    """Minus the optimal cost-to-goal of every cell, `(B, N, N)` float64, NaN where the goal cannot be reached
    (obstacles included): the exact value map, the ranking signal of planners without one of their own."""
    dist, _ = shortest_distances(obstacles, np.asarray(goals, dtype=np.int64), corner_cutting, moves)
    return np.where(np.isfinite(dist), -dist, np.nan)


def optimal_actions(
    dist: np.ndarray, obstacles: np.ndarray, corner_cutting: bool = True, moves: str | MoveModel = DEFAULT_MOVES
) -> np.ndarray:
    """Which actions are optimal at each cell: `(B, N, N, 8)` bool, for `dist` of `shortest_distances` (same
    `moves`).

    An action is optimal at a reachable, non-goal cell when it is a legal move of the model and its cost plus the
    neighbour's cost-to-goal equals the cell's cost-to-goal. The goal, obstacles and unreachable cells have none.
    """
    model = move_model(moves)
    b, n, m = dist.shape
    padded = np.full((b, n + 2, m + 2), np.inf)
    padded[:, 1:-1, 1:-1] = dist
    legal = valid_moves(obstacles, corner_cutting, model.name)
    out = np.zeros((b, n, m, N_ACTIONS), dtype=bool)
    target = np.where(np.isfinite(dist) & (dist > 0), dist, np.nan)
    for a, (dr, dc) in enumerate(model.deltas):
        via = padded[:, 1 + dr : 1 + dr + n, 1 + dc : 1 + dc + m] + model.costs[a]
        out[..., a] = legal[..., a] & (np.abs(via - target) <= COST_TOL)
    return out


def first_optimal_action(optimal: np.ndarray) -> np.ndarray:
    """The lowest-index optimal action of each cell, `-1` where there is none: `(B, N, N)` int8."""
    first = np.argmax(optimal, axis=-1).astype(np.int8)
    first[~optimal.any(axis=-1)] = -1
    return first


@numba.njit(cache=True, nogil=True, inline="always")
def legal_move(obstacles, r, c, dr, dc, corner_cutting):
    """Whether the move (r, c) -> (r + dr, c + dc) is legal on `obstacles` (N, M) (as `valid_moves`; the origin is
    not checked)."""
    nr, nc = r + dr, c + dc
    if nr < 0 or nr >= obstacles.shape[0] or nc < 0 or nc >= obstacles.shape[1] or obstacles[nr, nc]:
        return False
    return corner_cutting or dr == 0 or dc == 0 or not (obstacles[nr, c] or obstacles[r, nc])


@numba.njit(cache=True, nogil=True, inline="always")
def _first_optimal_move(dist, obstacles, r, c, corner_cutting, deltas, costs):
    """The lowest-index optimal action at `(r, c)` (as `first_optimal_action(optimal_actions(...))` there), -1 if
    none: at the goal, an obstacle or an unreachable cell."""
    d = dist[r, c]
    if not (d > 0.0 and d < np.inf):
        return -1
    for a in range(deltas.shape[0]):
        dr, dc = deltas[a, 0], deltas[a, 1]
        if legal_move(obstacles, r, c, dr, dc, corner_cutting) and abs(dist[r + dr, c + dc] + costs[a] - d) <= COST_TOL:
            return a
    return -1


@numba.njit(cache=True)
def _follow_policy(dist, obstacles, corner_cutting, starts, goals, deltas, costs, lengths, cells, fill):
    # Two passes share this code: with fill False only `lengths` is written. The action at each cell is found
    # there, so only the path's cells are looked at.
    n_maps, n_starts = starts.shape[0], starts.shape[1]
    pos = 0
    for b in range(n_maps):
        for s in range(n_starts):
            r = starts[b, s, 0]
            c = starts[b, s, 1]
            count = 0
            while True:
                if fill:
                    cells[pos, 0] = r
                    cells[pos, 1] = c
                pos += 1
                count += 1
                if r == goals[b, 0] and c == goals[b, 1]:
                    break
                a = _first_optimal_move(dist[b], obstacles[b], r, c, corner_cutting, deltas, costs)
                if a < 0:
                    break
                r += deltas[a, 0]
                c += deltas[a, 1]
            lengths[b * n_starts + s] = count


def expert_paths(
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    corner_cutting: bool = True,
    moves: str | MoveModel = DEFAULT_MOVES,
) -> tuple[np.ndarray, PackedPaths]:
    """Optimal paths from every start to the goal under the movement model `moves` (ties broken by the lowest
    action index).

    Args:
        obstacles: `(B, N, N)` bool. goals: `(B, 2)`. starts: `(B, S, 2)`, each able to reach its goal.

    Returns:
        `costs (B, S) float64`, and the paths, `PackedPaths` of B * S paths, path `b * S + s` from start `s` of
        map `b`. A start that cannot reach the goal gets cost inf and a one-cell path.
    """
    dist, _ = shortest_distances(obstacles, goals, corner_cutting, moves)
    return expert_paths_from(dist, obstacles, goals, starts, corner_cutting, moves)


def expert_paths_from(
    dist: np.ndarray,
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    corner_cutting: bool = True,
    moves: str | MoveModel = DEFAULT_MOVES,
) -> tuple[np.ndarray, PackedPaths]:
    """`expert_paths` for distances already computed by `shortest_distances` (same `moves`)."""
    model = move_model(moves)
    starts = np.ascontiguousarray(starts, dtype=np.int64)
    goals = np.ascontiguousarray(goals, dtype=np.int64)
    dist = np.ascontiguousarray(dist, dtype=np.float64)
    obstacles = np.ascontiguousarray(obstacles, dtype=np.bool_)
    b, s = starts.shape[:2]
    lengths = np.zeros(b * s, dtype=np.int64)
    walk = (dist, obstacles, bool(corner_cutting), starts, goals, model.deltas, model.costs, lengths)
    _follow_policy(*walk, np.zeros((0, 2), dtype=np.int16), False)
    offsets = np.zeros(b * s + 1, dtype=np.int64)
    np.cumsum(lengths, out=offsets[1:])
    cells = np.empty((offsets[-1], 2), dtype=np.int16)
    _follow_policy(*walk, cells, True)
    costs = dist[np.arange(b)[:, None], starts[..., 0], starts[..., 1]]
    return costs, PackedPaths(cells, offsets)
