"""The fast batched planning engine: one value map per map, one action per cell, all rollouts advanced together.

Paths and termination reasons are those of `vinadv.planners.reference.plan_reference` (the ports' way: re-run the
float32 PyTorch VIN at every step). The engine gets there differently:

1. Action maps. The value map does not depend on the agent's cell, so each map's VIN runs once, and every cell
   gets its action (argmax of the logits, the lowest index on ties).
2. Near ties. The engine's arithmetic is not torch's, so logits differ by rounding; where the two best logits of a
   cell are closer than a margin that bounds that difference, the cell is marked uncertain (-1).
3. Rollouts: one compiled loop follows the action maps (DESIGN.md's rule). A rollout that steps on an uncertain
   cell is re-done with torch's own logits for that map (one batch-1 `q_values`, then `fc` at each visited cell,
   the very numbers the reference computes), so a near tie is decided as the reference decides it.
"""

from __future__ import annotations

import numba
import numpy as np
import torch

from vinadv.grid.actions import ACTION_DELTAS
from vinadv.planners.reference import rollout, torch_action_at
from vinadv.planners.result import (
    COLLISION,
    GOAL,
    LOOP,
    STEP_LIMIT,
    TERMINATIONS,
    PlanResult,
    check_plan_inputs,
)
from vinadv.planners.vin import VIN, make_input

__all__ = ["PlanResult", "TERMINATIONS", "plan_batch", "action_maps"]

#: maps per chunk: bounds the memory of the action maps, paths and torch tensors.
DEFAULT_CHUNK = 4096
#: a cell is uncertain when its two best logits are closer than REL_MARGIN * (logit scale of its map).
REL_MARGIN = 1e-4
UNDECIDED = -1  # rollout code: stepped on an uncertain cell, to be re-done with torch's logits


def action_maps(model: VIN, obstacles: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """Action of every cell, `(B, N, N)` int8 in 0..7, or -1 where the two best logits are a near tie."""
    with torch.no_grad():
        q = model.q_values(make_input(obstacles, goals))  # (B, l_q, N, N)
        logits = model.fc(q.permute(0, 2, 3, 1)).double().numpy()
    fc = model.fc.weight.detach().double().numpy()
    scale = q.abs().amax(dim=(1, 2, 3)).double().numpy() * np.abs(fc).sum(axis=1).max()
    return _decide(logits, scale)


def _decide(logits: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """`logits (B, N, N, A)`, `scale (B,)` -> actions `(B, N, N)` int8 with -1 at near ties."""
    actions = np.argmax(logits, axis=-1).astype(np.int8)
    top2 = np.partition(logits, -2, axis=-1)[..., -2:]
    gap = top2[..., 1] - top2[..., 0]
    actions[gap <= (REL_MARGIN * scale + 1e-30)[:, None, None]] = UNDECIDED
    return actions


@numba.njit(cache=True, nogil=True)
def _rollouts(actions, map_index, starts, goals, limits, obstacles, corner_cutting, deltas, cells, lengths, terms):
    """Follow action maps from each start. cells: `(R, cap, 2)` scratch; writes lengths `(R,)` and terms `(R,)`."""
    n = actions.shape[1]
    stamp = np.zeros((actions.shape[0], n, n), dtype=np.int32)
    for t in range(len(starts)):
        b = map_index[t]
        r, c = starts[t, 0], starts[t, 1]
        gr, gc = goals[t, 0], goals[t, 1]
        cells[t, 0, 0] = r
        cells[t, 0, 1] = c
        length = 1
        stamp[b, r, c] = t + 1
        term = GOAL
        while True:
            if r == gr and c == gc:
                term = GOAL
                break
            if length - 1 >= limits[t]:
                term = STEP_LIMIT
                break
            a = actions[b, r, c]
            if a < 0:
                term = UNDECIDED
                break
            dr, dc = deltas[a, 0], deltas[a, 1]
            nr, nc = r + dr, c + dc
            if nr < 0 or nr >= n or nc < 0 or nc >= n or obstacles[b, nr, nc]:
                term = COLLISION
                break
            if not corner_cutting and dr != 0 and dc != 0 and (obstacles[b, nr, c] or obstacles[b, r, nc]):
                term = COLLISION
                break
            if stamp[b, nr, nc] == t + 1:
                term = LOOP
                break
            r, c = nr, nc
            stamp[b, r, c] = t + 1
            cells[t, length, 0] = r
            cells[t, length, 1] = c
            length += 1
        lengths[t] = length
        terms[t] = term


def plan_batch(
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    model: VIN,
    corner_cutting: bool = True,
    chunk_size: int = DEFAULT_CHUNK,
    progress: bool = False,
) -> PlanResult:
    """Plan one path per map with `model`, for any batch size, `chunk_size` maps at a time.

    Args:
        obstacles: `(B, N, N)` bool, True = obstacle.
        starts, goals: `(B, 2)` int `(row, col)`.
        model: a `VIN`. corner_cutting: whether a diagonal move may pass between two obstacles.
        chunk_size: maps per chunk (bounds memory). progress: show a tqdm bar over chunks.

    Returns:
        `PlanResult`, identical to `plan_reference` on the same inputs (see the module docstring).
    """
    obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
    return plan_maps(obstacles, goals, starts[:, None, :], model, corner_cutting, chunk_size, progress)


def plan_maps(
    obstacles: np.ndarray,
    goals: np.ndarray,
    starts: np.ndarray,
    model: VIN,
    corner_cutting: bool = True,
    chunk_size: int = DEFAULT_CHUNK,
    progress: bool = False,
) -> PlanResult:
    """Plan from S starts per map: `starts (B, S, 2)`; path `i * S + s` is from start `s` of map `i`.

    The value map of each map is computed once and shared by its S rollouts.
    """
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    goals = np.ascontiguousarray(goals, dtype=np.int64)
    starts = np.ascontiguousarray(starts, dtype=np.int64)
    if starts.ndim != 3 or starts.shape[0] != len(obstacles) or starts.shape[2] != 2:
        raise ValueError(f"starts has shape {starts.shape}, expected ({len(obstacles)}, S, 2)")
    for s in range(starts.shape[1]):
        check_plan_inputs(obstacles, starts[:, s], goals)
    model.eval()
    chunk_size = max(1, int(chunk_size))
    chunks = range(0, len(obstacles), chunk_size)
    if progress:
        from tqdm import tqdm

        chunks = tqdm(chunks, unit="chunk", desc="planning")
    parts = [
        _plan_chunk(obstacles[i : i + chunk_size], goals[i : i + chunk_size], starts[i : i + chunk_size], model,
                    corner_cutting)
        for i in chunks
    ]
    return PlanResult.concatenate(parts)


def _plan_chunk(obstacles, goals, starts, model, corner_cutting) -> PlanResult:
    b, s = starts.shape[0], starts.shape[1]
    n = obstacles.shape[1]
    actions = action_maps(model, obstacles, goals)
    map_index = np.repeat(np.arange(b), s)
    flat_starts = starts.reshape(-1, 2)
    flat_goals = goals[map_index]
    limits = _limits_multi(obstacles, goals, starts, corner_cutting)
    cap = int(min(limits.max(initial=0) + 1, n * n))
    cells = np.empty((len(flat_starts), cap, 2), dtype=np.int16)
    lengths = np.empty(len(flat_starts), dtype=np.int64)
    terms = np.empty(len(flat_starts), dtype=np.int8)
    _rollouts(actions, map_index, flat_starts, flat_goals, limits, obstacles, bool(corner_cutting),
              ACTION_DELTAS, cells, lengths, terms)
    paths = [cells[t, : lengths[t]] for t in range(len(flat_starts))]
    for t in np.flatnonzero(terms == UNDECIDED):
        m = map_index[t]
        x = make_input(obstacles[m : m + 1], goals[m : m + 1])
        with torch.no_grad():
            q = model.q_values(x)
        path, term = rollout(torch_action_at(model, x, q), obstacles[m], flat_starts[t], flat_goals[t],
                             int(limits[t]), corner_cutting)
        paths[t] = np.array(path, dtype=np.int16).reshape(-1, 2)
        terms[t] = term
    return PlanResult.from_paths(paths, terms)


def _limits_multi(obstacles, goals, starts, corner_cutting) -> np.ndarray:
    from vinadv.grid.shortest_paths import shortest_distances

    _, moves = shortest_distances(obstacles, goals, corner_cutting)
    n = obstacles.shape[1]
    idx = np.arange(len(obstacles))[:, None]
    lengths = moves[idx, starts[..., 0], starts[..., 1]].astype(np.int64).reshape(-1)
    return 2 * np.where(lengths < 0, n * n, lengths)
