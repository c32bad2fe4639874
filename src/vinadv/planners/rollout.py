"""DESIGN.md's rollout from whole-map action logits, for every planner alike, compiled and batched.

A whole-map policy planner gives one logits map `(8, N, N)` per map (it does not depend on the agent's cell); the
rollouts of all starts of all maps then follow argmax actions (lowest index on ties) in one Numba kernel, with the
rules and termination codes of `vinadv.planners.vin.reference.rollout` (the engine's and the reference's rule):
at each cell the goal ends the path ('goal'); a path that already made its step limit 2L of moves ends as
'step_limit'; otherwise the move is taken: off the grid, into an obstacle, or (without corner cutting) diagonally
past an obstacle ends it as 'collision', onto a visited cell as 'loop'.

Movement models (`vinadv.grid.moves`): the step limit's L is the optimal move count under the maps' model, and the
argmax runs over the model's actions only (on `news` the first 4 logits, N S E W): a planner whose action set does
not fit the maps is refused before planning (`vinadv.planners.registry.load_planner`), so no logit of an action
the maps lack is ever compared.
"""

from __future__ import annotations

import numba
import numpy as np

from vinadv.grid.moves import DEFAULT_MOVES, move_model
from vinadv.grid.shortest_paths import shortest_distances
from vinadv.planners.result import COLLISION, GOAL, LOOP, STEP_LIMIT, PlanResult


def multi_start_limits(
    obstacles: np.ndarray, goals: np.ndarray, starts: np.ndarray, corner_cutting: bool, moves: str = DEFAULT_MOVES
) -> np.ndarray:
    """Step limits `(B, S)` int64 of rollouts from `starts (B, S, 2)`: 2 L, L the optimal move count under `moves`
    (N * N where the goal cannot be reached), as `vinadv.planners.result.step_limits` for one start."""
    b, n = obstacles.shape[0], obstacles.shape[1]
    if b == 0:
        return np.zeros(starts.shape[:2], dtype=np.int64)
    _, counts = shortest_distances(obstacles, goals, corner_cutting, moves)
    lengths = counts[np.arange(b)[:, None], starts[..., 0], starts[..., 1]].astype(np.int64)
    return 2 * np.where(lengths < 0, n * n, lengths)


@numba.njit(cache=True, nogil=True)
def _rollout_kernel(logits, obstacles, goals, starts, limits, corner_cutting, deltas, cells, lengths, terms):
    """logits (B, 8, N, N) float; starts (B, S, 2); limits (B, S); deltas (A, 2), the model's moves (the argmax runs
    over the first A logits). Rollout b * S + s into cells[b * S + s] (`(N * N, 2)` int16: a rollout never visits a
    cell twice), its cell count into lengths, its code into terms."""
    n_maps, n_act, n = logits.shape[0], min(logits.shape[1], deltas.shape[0]), logits.shape[2]
    n_starts = starts.shape[1]
    stamp = np.zeros((n, n), dtype=np.int64)  # t + 1 on the cells rollout t has visited
    for b in range(n_maps):
        gr, gc = goals[b, 0], goals[b, 1]
        for s in range(n_starts):
            t = b * n_starts + s
            r, c = starts[b, s, 0], starts[b, s, 1]
            cells[t, 0, 0] = r
            cells[t, 0, 1] = c
            length = 1
            stamp[r, c] = t + 1
            limit = limits[b, s]
            while True:
                if r == gr and c == gc:
                    term = GOAL
                    break
                if length - 1 >= limit:
                    term = STEP_LIMIT
                    break
                a = 0
                best = logits[b, 0, r, c]
                for k in range(1, n_act):  # strict >: the lowest index wins a tie
                    if logits[b, k, r, c] > best:
                        best = logits[b, k, r, c]
                        a = k
                term, r, c, length = rollout_step(
                    obstacles, b, t, r, c, a, corner_cutting, deltas, stamp, cells, length
                )
                if term != MOVED:
                    break
            lengths[t] = length
            terms[t] = term


#: `rollout_step`'s code for a move made (every termination code is >= -1)
MOVED = -2


@numba.njit(cache=True, nogil=True, inline="always")
def rollout_step(obstacles, b, t, r, c, a, corner_cutting, deltas, stamp, cells, length):
    """One DESIGN.md move of rollout `t` on map `b` from `(r, c)` by action `a`, shared by every planner's rollout:
    `(MOVED, new r, new c, length + 1)` with the new cell stamped and written to `cells[t, length]`, or
    `(COLLISION | LOOP, r, c, length)` when the move ends the rollout (off the grid, into an obstacle, between two
    obstacles without corner cutting, or onto a cell this rollout visited: `stamp == t + 1`)."""
    n = obstacles.shape[1]
    dr, dc = deltas[a, 0], deltas[a, 1]
    nr, nc = r + dr, c + dc
    if nr < 0 or nr >= n or nc < 0 or nc >= n or obstacles[b, nr, nc]:
        return COLLISION, r, c, length
    if not corner_cutting and dr != 0 and dc != 0 and (obstacles[b, nr, c] or obstacles[b, r, nc]):
        return COLLISION, r, c, length
    if stamp[nr, nc] == t + 1:
        return LOOP, r, c, length
    stamp[nr, nc] = t + 1
    cells[t, length, 0] = nr
    cells[t, length, 1] = nc
    return MOVED, nr, nc, length + 1


def rollout_logits(
    logits: np.ndarray,
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    corner_cutting: bool = True,
    limits: np.ndarray | None = None,
    moves: str = DEFAULT_MOVES,
) -> PlanResult:
    """Paths from `starts (B, S, 2)` following the argmax of `logits (B, 8, N, N)` (one map per map).

    Args:
        logits: float32/float64, action order of DESIGN.md, finite or -inf (checked by the caller: NaN argmax is
            undefined). obstacles: `(B, N, N)` bool. goals: `(B, 2)`. starts: `(B, S, 2)`, inside the grid.
        limits: step limits `(B, S)`; default `multi_start_limits` (2L).
        moves: the maps' movement model: its actions (the argmax is over them) and the L of the step limit.

    Returns:
        `PlanResult`, path `b * S + s` from start `s` of map `b`.
    """
    logits = np.ascontiguousarray(logits)
    if logits.dtype not in (np.float32, np.float64):
        logits = logits.astype(np.float32)
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    goals = np.ascontiguousarray(goals, dtype=np.int64)
    starts = np.ascontiguousarray(starts, dtype=np.int64)
    model = move_model(moves)
    if limits is None:
        limits = multi_start_limits(obstacles, goals, starts, corner_cutting, model.name)
    limits = np.ascontiguousarray(limits, dtype=np.int64)
    b, s, n = starts.shape[0], starts.shape[1], obstacles.shape[1]
    cells = np.empty((b * s, n * n, 2), dtype=np.int16)  # np.empty: untouched pages cost nothing
    lengths = np.empty(b * s, dtype=np.int64)
    terms = np.empty(b * s, dtype=np.int8)
    if b * s:
        _rollout_kernel(
            logits, obstacles, goals, starts, limits, bool(corner_cutting), model.deltas, cells, lengths, terms
        )
    return PlanResult.from_buffers(cells, lengths, terms)
