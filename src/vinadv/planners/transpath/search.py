"""TransPath's search (their `modules/planners.py`, `DifferentiableDiagAstar` at evaluation) as a compiled best-first
search: the compiled replica, float32 as theirs, batched over rows.

It is the shared best-first kernel of `vinadv.planners.classical.astar` (its heap, its float32 key of a cell,
`legal_move` of the maps' rule) with the authors' TransPath heuristics and selection:

- octile moves (orthogonal cost 1, diagonal cost float32 sqrt 2) to the free neighbours; g of the start 0; a selected
  cell's neighbour gets `g2 = g[selected] + move cost` when it is neither open nor closed, or open with `g > g2`
  (float32); a closed cell is never reopened; the search stops when the goal is selected (the path: the parents'
  chain), when no cell is open, or after N * N selections (`[start]`, termination `step_limit`).
- the heuristic, in the authors' float32 order: `octile = min(dr, dc) * float32(sqrt 2) + |dr - dc|`;
- `cf` (mode 'k' in their code): `h = octile / max(k, 0.1)` with k the network's correction factor of the cell,
  `f = 0.5 g + 0.501 h` (float32(0.501): their `1 - g_ratio + 0.001`); the selected cell is the open cell of the
  largest float32 `exp(-f / 8)` (8 = sqrt 64), the first in row-major order on ties (their argmax). The `exp` is the
  float64 one rounded once to float32, as in `astar`'s replica (PyTorch's vectorised float32 exp is within one unit
  of it; their division by the sum before the argmax can merge two values one unit apart): where the authors' code
  and the replica can part, `tests/planners/transpath` counts it.
- `f` (focal search, `f_w`): `f = 0.5 g + 0.5 octile`; the focal list is the open cells with `f <= min f * f_w`
  (the minimum over the open cells, times `f_w` in float32); the selected cell is the one of the focal list with
  the largest float32 `exp(focal value)`, the first in row-major order on ties. The exps are PyTorch's, computed by
  the caller (`focal_exp`), as the authors compute them: only the division by the sum is not replayed.

Corner cutting: the authors' search cuts corners (a diagonal needs only its destination free). On maps without
corner cutting this search keeps the maps' rule: a diagonal also needs both cells beside it free.

Where every open cell's `exp(-f / 8)` underflows (f above about 700: paths of several hundred cells on mazes), the
authors' division gives NaN and an arbitrary cell; the replica orders such cells by f, as `astar` does.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from vinadv.errors import InputError
from vinadv.grid.moves import move_model
from vinadv.planners.classical.astar import _close, _heap_pop, _heap_push, _pop_current, _replica_key, _successor
from vinadv.planners.result import GOAL, STEP_LIMIT, PlanResult, check_plan_inputs
from vinadv.planners.search import SearchResult

__all__ = ["CF_H_RATIO", "F_W", "K_FLOOR", "cf_heuristic", "octile_heuristic", "transpath_search"]

#: the weight of h in the `cf` search's f (the authors' `1 - g_ratio + 0.001`, in float32 when it multiplies)
CF_H_RATIO = 0.501
#: the floor of the correction factor (the authors' threshold 0.1)
K_FLOOR = np.float32(0.1)
#: the focal weight of the authors' evaluation
F_W = 100.0
SQRT2_32 = np.float32(math.sqrt(2.0))


def octile_heuristic(goals: np.ndarray, size: int) -> np.ndarray:
    """`(B, N, N)` float32 octile distance to each row's goal in the authors' float32 arithmetic: `min(dr, dc) *
    float32(sqrt 2) + |dr - dc|`."""
    idx = np.arange(size, dtype=np.float32)
    dr = np.abs(idx[None, :, None] - goals[:, 0, None, None].astype(np.float32))
    dc = np.abs(idx[None, None, :] - goals[:, 1, None, None].astype(np.float32))
    dr, dc = np.broadcast_arrays(dr, dc)
    return (np.minimum(dr, dc) * SQRT2_32 + np.abs(dr - dc)).astype(np.float32)


def cf_heuristic(factors: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """`(B, N, N)` float32: the octile heuristic divided by `max(k, 0.1)` (the authors' `where(k > 0.1, k, 0.1)`)."""
    k = np.asarray(factors, dtype=np.float32)
    return (octile_heuristic(goals, k.shape[-1]) / np.where(k > K_FLOOR, k, K_FLOOR)).astype(np.float32)


@numba.njit(cache=True, nogil=True)
def _search_one(h32, focal_exp, obstacles, sr, sc, gr, gc, params, cells_out, expanded):
    """One search (module doc) on the float32 heuristic map `h32` (and `focal_exp` in focal mode); fills `cells_out`
    (the path, start first) and `expanded`; returns `(path length, termination)`."""
    focal, deltas, move_costs, corner_cutting, f_w, budget = params
    n = obstacles.shape[0]
    m = obstacles.shape[1]
    cells = n * m
    g32 = np.zeros(cells, dtype=np.float32)
    f32 = np.zeros(cells, dtype=np.float32)  # focal mode: the current f of each open cell
    state = np.zeros(cells, dtype=np.int8)  # 0 new, 1 open, 2 closed
    parent = np.full(cells, -1, dtype=np.int64)
    key1 = np.zeros(cells, dtype=np.float64)  # cf: the cell's current key, to skip stale heap entries
    cap = deltas.shape[0] * cells + 1
    hk1 = np.empty(cap, dtype=np.float64)  # cf: the replica's keys; focal: (f, cell), the smallest f first
    hk2 = np.empty(cap, dtype=np.float64)
    hcell = np.empty(cap, dtype=np.int64)
    fk1 = np.empty(cells + 1, dtype=np.float64)  # focal: (-exp(focal value), cell), the largest value first
    fk2 = np.zeros(cells + 1, dtype=np.float64)
    fcell = np.empty(cells + 1, dtype=np.int64)
    stash = np.empty(cells + 1, dtype=np.int64)
    half32 = np.float32(0.5)
    h_ratio32 = np.float32(CF_H_RATIO)
    sqrt_n32 = np.float32(math.sqrt(m))
    f_w32 = np.float32(f_w)
    start = sr * m + sc
    goal = gr * m + gc
    state[start] = 1
    size = 0
    fsize = 0
    if focal:
        f32[start] = np.float32(np.float32(half32 * g32[start]) + np.float32(half32 * h32[sr, sc]))
        size = _heap_push(hk1, hk2, hcell, size, np.float64(f32[start]), 0.0, start)
        fsize = _heap_push(fk1, fk2, fcell, fsize, -np.float64(focal_exp[sr, sc]), 0.0, start)
    else:
        a, b = _replica_key(g32[start], h32[sr, sc], half32, h_ratio32, sqrt_n32)
        size = _heap_push(hk1, hk2, hcell, size, a, b, start)
        key1[start] = a
    for _ in range(budget):
        sel = -1
        if focal:
            while size > 0:  # the smallest f of the open cells: drop stale entries at the top
                i = hcell[0]
                if state[i] == 1 and hk1[0] == np.float64(f32[i]):
                    break
                size = _heap_pop(hk1, hk2, hcell, size)
            if size == 0:
                return 1, STEP_LIMIT
            bound = np.float32(np.float32(hk1[0]) * f_w32)
            stashed = 0
            while fsize > 0:  # the largest focal value among the open cells with f <= bound
                fsize = _heap_pop(fk1, fk2, fcell, fsize)
                i = fcell[fsize]
                if state[i] != 1:
                    continue
                if f32[i] <= bound:
                    sel = i
                    break
                stash[stashed] = i
                stashed += 1
            for s in range(stashed):
                i = stash[s]
                fsize = _heap_push(fk1, fk2, fcell, fsize, -np.float64(focal_exp[i // m, i - (i // m) * m]), 0.0, i)
        else:
            sel, size = _pop_current(hk1, hk2, hcell, size, state, key1)  # the best open cell
        length, term = _close(sel, goal, state, parent, expanded, cells_out)
        if length > 0:
            return length, term
        for a_ in range(deltas.shape[0]):
            j = _successor(obstacles, state, sel, deltas[a_, 0], deltas[a_, 1], corner_cutting)
            if j < 0:
                continue
            g2 = np.float32(g32[sel] + np.float32(move_costs[a_]))
            if state[j] == 1 and not g32[j] > g2:
                continue
            g32[j] = g2
            parent[j] = sel
            rj = j // m
            cj = j - rj * m
            if focal:
                if state[j] == 0:
                    fsize = _heap_push(fk1, fk2, fcell, fsize, -np.float64(focal_exp[rj, cj]), 0.0, j)
                f32[j] = np.float32(np.float32(half32 * g2) + np.float32(half32 * h32[rj, cj]))
                size = _heap_push(hk1, hk2, hcell, size, np.float64(f32[j]), 0.0, j)
            else:
                k1, k2 = _replica_key(g2, h32[rj, cj], half32, h_ratio32, sqrt_n32)
                key1[j] = k1
                size = _heap_push(hk1, hk2, hcell, size, k1, k2, j)
            state[j] = 1
    return 1, STEP_LIMIT  # the budget is spent


@numba.njit(cache=True, parallel=True)
def _search_batch(h32, focal_exp, obstacles, starts, goals, params, cells_out, lengths, termination, expanded):
    for b in numba.prange(obstacles.shape[0]):
        length, term = _search_one(
            h32[b],
            focal_exp[b],
            obstacles[b],
            starts[b, 0],
            starts[b, 1],
            goals[b, 0],
            goals[b, 1],
            params,
            cells_out[b],
            expanded[b],
        )
        if term != GOAL:
            cells_out[b, 0, 0] = starts[b, 0]
            cells_out[b, 0, 1] = starts[b, 1]
        lengths[b] = length
        termination[b] = term


def transpath_search(
    outputs: np.ndarray,
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    mode: str,
    corner_cutting: bool = True,
    f_w: float = F_W,
    focal_exp: np.ndarray | None = None,
) -> SearchResult:
    """One TransPath search per row (module doc), compiled, rows in parallel.

    Args:
        outputs: `(B, N, N)` float32, the network's `(output + 1) / 2`: the correction factors (`mode` "cf") or the
            focal values (`mode` "f").
        obstacles, starts, goals: the rows' maps `(B, N, N)` bool, starts and goals `(B, 2)`.
        corner_cutting: the maps' rule (the authors': True).
        f_w: the focal weight (mode "f").
        focal_exp: `(B, N, N)` float32 `exp(outputs)` as PyTorch computes it (mode "f"; None: NumPy's float32 exp).

    Returns `SearchResult`: the paths, terminations and the selected cells (`expanded`, the authors' histories).
    """
    obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
    if mode not in ("cf", "f"):
        raise InputError(f"mode {mode!r}: expected cf or f", "mode")
    outputs = np.ascontiguousarray(outputs, dtype=np.float32)
    if outputs.shape != obstacles.shape or not np.isfinite(outputs).all():
        raise InputError(f"outputs: expected finite float32 {obstacles.shape}, got {outputs.shape}", "outputs")
    b, n = obstacles.shape[0], obstacles.shape[1]
    focal = mode == "f"
    if focal:
        h32 = octile_heuristic(goals, n)
        if focal_exp is None:
            focal_exp = np.exp(outputs)
        focal_exp = np.ascontiguousarray(focal_exp, dtype=np.float32)
        if focal_exp.shape != obstacles.shape:
            raise InputError(f"focal_exp: expected {obstacles.shape}, got {focal_exp.shape}", "focal_exp")
        if not (math.isfinite(f_w) and f_w >= 1.0):
            raise InputError(f"f_w {f_w!r}: expected a number >= 1", "f_w")
    else:
        h32 = cf_heuristic(outputs, goals)
        focal_exp = np.zeros((b, 1, 1), dtype=np.float32)  # not read
    model = move_model("octile")
    cells = np.zeros((b, max(1, n * n), 2), dtype=np.int16)
    lengths = np.zeros(b, dtype=np.int64)
    termination = np.zeros(b, dtype=np.int8)
    expanded = np.zeros(obstacles.shape, dtype=bool)
    if b:
        params = (focal, model.deltas, model.costs, bool(corner_cutting), float(f_w), n * n)
        _search_batch(h32, focal_exp, obstacles, starts, goals, params, cells, lengths, termination, expanded)
    plan = PlanResult.from_buffers(cells, lengths, termination)
    return SearchResult(paths=plan.paths, termination=plan.termination, expanded=expanded)
