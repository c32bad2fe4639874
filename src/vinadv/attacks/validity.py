"""Which cells may take an added obstacle (DESIGN.md): a free cell, not the start or the goal, and only where the
goal stays reachable from the start.

Only a cell on *every* start-goal path can disconnect them. Where diagonal moves may cut corners (the default),
an added obstacle removes just its cell from the move graph, and those cells are the cut vertices between start
and goal: one depth-first search from the start per map finds them all (Tarjan's low links: an ancestor v of the
goal in the search tree separates them exactly when the subtree holding the goal has no edge climbing above v).
Without corner cutting an obstacle also removes the diagonal moves past its corners, so there each cell of one
start-goal path (the expert path) is checked by a breadth-first search with it blocked. Both are compiled with
Numba and run in parallel over maps. They follow the map set's movement model (`vinadv.grid.moves`): reachability
depends only on which moves exist, so `octile` and `moore` have the same valid cells, and `news` (4 moves, no
diagonal to cut) takes the cut-vertex search over its 4 moves.

Which cells may be freed (edit `remove`, DESIGN.md "Obstacle removal"): an obstacle cell that is not a border wall
(`vinadv.grid.checks.border_walls`: the outer ring of a map whose ring is all obstacles), on a map whose goal is
reachable from the start. Freeing a cell only adds moves, so the goal stays reachable, and K cells are valid exactly
when each is a valid one-cell removal of the map with the cells before it freed (`valid_removals`).

Frozen cells (a map set's `frozen` mask, DESIGN.md "Several obstacles" and "Obstacle removal": the padding an
importer added around a map that was not square): no attack may add an obstacle to one or free one. Every function
here takes `frozen` (`(B, N, N)` bool, or None for none) and leaves those cells out; the attack strategies draw
every candidate from `valid_cells` or `removable_cells`, so none ever edits a frozen cell. Without a mask (or an
all-False one) every result is the same as before, bit for bit.

K obstacles (`valid_additions`): K distinct cells, each free on the original map and neither the start nor the
goal, with the goal still reachable from the start once all K are added. Adding obstacles only removes paths, so a
set is valid exactly when each of its cells, added one after the other in any order, is a valid cell
(`valid_cells`) of the map with the cells before it added: the greedy multi-obstacle attacks rely on this.
"""

from __future__ import annotations

import numba
import numpy as np

from vinadv.grid.checks import border_walls
from vinadv.grid.moves import DEFAULT_MOVES, move_model
from vinadv.grid.shortest_paths import expert_paths
from vinadv.planners.batching import over_maps


@numba.njit(cache=True, nogil=True)
def _reachable(obstacles, blocked_r, blocked_c, start, goal, corner_cutting, deltas, seen, queue):
    """Whether a breadth-first search from `start` reaches `goal` with the cell (blocked_r, blocked_c) blocked too.
    start, goal: `(2,)`; seen `(N, N)` bool and queue `(N * N,)` int64 scratch."""
    n, m = obstacles.shape
    sr, sc, gr, gc = start[0], start[1], goal[0], goal[1]
    seen[:, :] = False
    seen[sr, sc] = True
    queue[0] = sr * m + sc
    head, tail = 0, 1
    while head < tail:
        node = queue[head]
        head += 1
        r = node // m
        c = node - r * m
        if r == gr and c == gc:
            return True
        for a in range(deltas.shape[0]):
            nr = r + deltas[a, 0]
            nc = c + deltas[a, 1]
            if nr < 0 or nr >= n or nc < 0 or nc >= m or seen[nr, nc] or obstacles[nr, nc]:
                continue
            if nr == blocked_r and nc == blocked_c:
                continue
            if not corner_cutting and deltas[a, 0] != 0 and deltas[a, 1] != 0:
                if (
                    obstacles[nr, c]
                    or obstacles[r, nc]
                    or (nr == blocked_r and c == blocked_c)
                    or (r == blocked_r and nc == blocked_c)
                ):
                    continue
            seen[nr, nc] = True
            queue[tail] = nr * m + nc
            tail += 1
    return False


@numba.njit(cache=True, parallel=True)
def _mark_separators(obstacles, starts, goals, cells, offsets, corner_cutting, deltas, separator):
    n, m = obstacles.shape[1], obstacles.shape[2]
    for b in numba.prange(obstacles.shape[0]):
        seen = np.empty((n, m), dtype=np.bool_)
        queue = np.empty(n * m, dtype=np.int64)
        # the path's first and last cells are the start and the goal, which are never candidates
        for i in range(offsets[b] + 1, offsets[b + 1] - 1):
            r, c = cells[i, 0], cells[i, 1]
            if not _reachable(obstacles[b], r, c, starts[b], goals[b], corner_cutting, deltas, seen, queue):
                separator[b, r, c] = True


@numba.njit(cache=True, nogil=True)
def _cut_vertices(obstacles, start, goal, deltas, disc, low, parent, stack, moves, separator):
    """Mark in `separator (N, N)` the cells whose removal disconnects the goal from the start, where moves join any
    two free neighbours (corner cutting); False if the goal is not reachable. disc, low, parent, stack, moves:
    `(N * N,)` int64 scratch."""
    n, m = obstacles.shape
    disc[:] = -1
    s, t = start[0] * m + start[1], goal[0] * m + goal[1]
    disc[s], low[s], parent[s] = 0, 0, -1
    clock, top = 1, 0
    stack[0], moves[0] = s, 0
    while top >= 0:  # iterative DFS; moves[top]: the next action to try from stack[top]
        u = stack[top]
        a = moves[top]
        if a < deltas.shape[0]:
            moves[top] = a + 1
            r = u // m
            nr, nc = r + deltas[a, 0], u - r * m + deltas[a, 1]
            if nr < 0 or nr >= n or nc < 0 or nc >= m or obstacles[nr, nc]:
                continue
            v = nr * m + nc
            if disc[v] < 0:
                disc[v], low[v], parent[v] = clock, clock, u
                clock += 1
                top += 1
                stack[top], moves[top] = v, 0
            elif v != parent[u]:
                low[u] = min(low[u], disc[v])
        else:
            top -= 1
            if top >= 0:
                low[stack[top]] = min(low[stack[top]], low[u])
    if disc[t] < 0:
        return False
    if t == s:
        return True
    child, v = t, parent[t]
    while v != s:  # the goal's ancestors: v separates when nothing below `child` climbs above v
        if low[child] >= disc[v]:
            separator[v // m, v - (v // m) * m] = True
        child, v = v, parent[v]
    return True


@numba.njit(cache=True, nogil=True)
def _cut_vertices_batch(lo, hi, obstacles, starts, goals, deltas, separator, reachable):
    size = obstacles.shape[1] * obstacles.shape[2]
    disc, low, parent = np.empty(size, np.int64), np.empty(size, np.int64), np.empty(size, np.int64)
    stack, moves = np.empty(size, np.int64), np.empty(size, np.int64)
    for b in range(lo, hi):
        reachable[b] = _cut_vertices(
            obstacles[b], starts[b], goals[b], deltas, disc, low, parent, stack, moves, separator[b]
        )


def _contiguous(obstacles, starts, goals) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The kernels' inputs: `obstacles` as C-contiguous bool, `starts` and `goals` as C-contiguous int64."""
    return (
        np.ascontiguousarray(obstacles, dtype=bool),
        np.ascontiguousarray(starts, dtype=np.int64),
        np.ascontiguousarray(goals, dtype=np.int64),
    )


def valid_cells(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
    frozen: np.ndarray | None = None,
) -> np.ndarray:
    """Cells where one added obstacle makes a valid adversarial map: `(B, N, N)` bool.

    Args:
        obstacles: `(B, N, N)` bool.
        starts: `(B, 2)` `(row, col)`.
        goals: `(B, 2)` `(row, col)`; the goal must be reachable from the start.
        corner_cutting: the maps' move rule (whether a diagonal move may cut a corner).
        moves: the maps' movement model (`vinadv.grid.moves`).
        frozen: `(B, N, N)` bool, cells no attack may edit (never valid), or None.
    """
    deltas = move_model(moves).deltas
    obstacles, starts, goals = _contiguous(obstacles, starts, goals)
    b = len(obstacles)
    idx = np.arange(b)
    valid = ~obstacles
    valid[idx, starts[:, 0], starts[:, 1]] = False
    valid[idx, goals[:, 0], goals[:, 1]] = False
    if b == 0:
        return valid
    separator = np.zeros_like(valid)
    if corner_cutting or len(deltas) == 4:  # an obstacle removes only its own cell from the move graph
        reachable = np.zeros(b, dtype=bool)
        over_maps(
            b,
            lambda lo, hi: _cut_vertices_batch(lo, hi, obstacles, starts, goals, deltas, separator, reachable),
        )
    else:
        costs, paths = expert_paths(obstacles, goals, starts[:, None, :], corner_cutting, moves)
        reachable = np.isfinite(costs[:, 0])
        _mark_separators(
            obstacles,
            starts,
            goals,
            paths.cells.astype(np.int64),
            paths.offsets,
            bool(corner_cutting),
            deltas,
            separator,
        )
    valid &= ~separator
    # a start that cannot reach its goal has no valid cell at all (the map is not a solvable map)
    valid[~reachable] = False
    return _unfrozen(valid, frozen)


def _unfrozen(cells: np.ndarray, frozen: np.ndarray | None) -> np.ndarray:
    """`cells (B, N, N)` bool without the `frozen` cells (None: none are)."""
    if frozen is None:
        return cells
    frozen = np.asarray(frozen, dtype=bool)
    if frozen.shape != cells.shape:
        raise ValueError(f"frozen has shape {frozen.shape}, the maps {cells.shape}")
    return cells & ~frozen


def _touches_frozen(cells: np.ndarray, frozen: np.ndarray | None) -> np.ndarray:
    """`(B,)` bool: whether any of each map's `cells (B, K, 2)` is frozen (None: none is)."""
    if frozen is None:
        return np.zeros(len(cells), dtype=bool)
    frozen = np.asarray(frozen, dtype=bool)
    idx = np.arange(len(cells))[:, None]
    return frozen[idx, cells[..., 0], cells[..., 1]].any(axis=1)


@numba.njit(cache=True, parallel=True)
def _reachable_all(obstacles, starts, goals, corner_cutting, deltas, out):
    n, m = obstacles.shape[1], obstacles.shape[2]
    for b in numba.prange(obstacles.shape[0]):
        seen = np.empty((n, m), dtype=np.bool_)
        queue = np.empty(n * m, dtype=np.int64)
        out[b] = _reachable(obstacles[b], -1, -1, starts[b], goals[b], corner_cutting, deltas, seen, queue)


def valid_additions(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    added: np.ndarray,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
    frozen: np.ndarray | None = None,
) -> np.ndarray:
    """Whether adding the cells `added` to each map makes a valid adversarial map: `(B,)` bool.

    Args:
        obstacles: `(B, N, N)` bool, the original maps.
        starts: `(B, 2)` `(row, col)`.
        goals: `(B, 2)` `(row, col)`.
        added: `(B, K, 2)` (or `(B, 2)`, K = 1) cells: valid when they are K distinct cells on the grid, each free
            on the original map and neither the start nor the goal, and the goal is reachable from the start
            (and from a start on an obstacle nothing is) with all K added.
        corner_cutting: the maps' move rule (whether a diagonal move may cut a corner).
        moves: the maps' movement model (`vinadv.grid.moves`).
        frozen: `(B, N, N)` bool, cells no attack may edit (a set with one is never valid), or None.
    """
    obstacles, starts, goals = _contiguous(obstacles, starts, goals)
    ok, cells = _distinct_cells(obstacles, added)
    ok &= ~_touches_frozen(cells, frozen)
    idx = np.arange(len(obstacles))[:, None]
    ok &= ~obstacles[idx, cells[..., 0], cells[..., 1]].any(axis=1)
    ok &= ~((cells == starts[:, None]).all(axis=2) | (cells == goals[:, None]).all(axis=2)).any(axis=1)
    blocked = obstacles.copy()
    blocked[idx, cells[..., 0], cells[..., 1]] = True
    return ok & solvable(blocked, starts, goals, corner_cutting, moves)


def _distinct_cells(obstacles: np.ndarray, cells) -> tuple[np.ndarray, np.ndarray]:
    """`(ok (B,), cells (B, K, 2))`: whether each map's K cells are distinct cells on the grid, and the cells as int64
    (a map's cells set to (0, 0) where one is off the grid, so they index safely)."""
    b, n = obstacles.shape[0], obstacles.shape[1]
    cells = np.asarray(cells, dtype=np.int64).reshape(b, -1, 2)
    on_grid = ((cells >= 0) & (cells < n)).all(axis=(1, 2))
    cells = np.where(on_grid[:, None, None], cells, 0)
    flat = np.sort(cells[..., 0] * n + cells[..., 1], axis=1)
    return on_grid & ~(np.diff(flat, axis=1) == 0).any(axis=1), cells


def solvable(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
) -> np.ndarray:
    """`(B,)` bool: the goal is reachable from the start on each map (`obstacles (B, N, N)`, starts/goals `(B, 2)`);
    never from a start or to a goal on an obstacle."""
    obstacles, starts, goals = _contiguous(obstacles, starts, goals)
    idx = np.arange(len(obstacles))
    reach = np.zeros(len(obstacles), dtype=bool)
    if len(obstacles):
        _reachable_all(obstacles, starts, goals, bool(corner_cutting), move_model(moves).deltas, reach)
    return reach & ~obstacles[idx, starts[:, 0], starts[:, 1]] & ~obstacles[idx, goals[:, 0], goals[:, 1]]


def removable_cells(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
    frozen: np.ndarray | None = None,
) -> np.ndarray:
    """Cells where freeing one obstacle makes a valid adversarial map (edit `remove`): `(B, N, N)` bool, the obstacle
    cells that are not border walls nor frozen, on the maps whose goal is reachable from the start (arguments as for
    `valid_cells`)."""
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    ok = solvable(obstacles, starts, goals, corner_cutting, moves)
    return _unfrozen(obstacles & ~border_walls(obstacles) & ok[:, None, None], frozen)


def valid_removals(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    removed: np.ndarray,
    corner_cutting: bool = True,
    moves: str = DEFAULT_MOVES,
    frozen: np.ndarray | None = None,
) -> np.ndarray:
    """Whether freeing the cells `removed` (`(B, K, 2)`, or `(B, 2)` for K = 1) of each map makes a valid adversarial
    map: `(B,)` bool. Valid when they are K distinct cells on the grid, each an obstacle of the original map, not a
    border wall and not `frozen` (`(B, N, N)` bool or None), and the goal is reachable from the start on the
    original map (so on the edited one too)."""
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    ok, cells = _distinct_cells(obstacles, removed)
    idx = np.arange(len(obstacles))[:, None]
    ok &= obstacles[idx, cells[..., 0], cells[..., 1]].all(axis=1)
    ok &= ~border_walls(obstacles)[idx, cells[..., 0], cells[..., 1]].any(axis=1)
    ok &= ~_touches_frozen(cells, frozen)
    return ok & solvable(obstacles, starts, goals, corner_cutting, moves)
