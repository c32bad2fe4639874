"""Best-first grid search with the Neural A* authors' arithmetic, and the `astar` and `wastar` search planners.

One compiled kernel, `best_first_search`, batched over rows (one search per row, rows in parallel), serves vanilla
A* (`astar`), weighted A* (`wastar`) and Neural A* (a learned cost map in place of the unit one). It follows the
differentiable A* of Yonetani et al. (ICML 2021; omron-sinicx/neural-astar, `differentiable_astar.py`), step by
step, at evaluation (no gradients, one selected cell per step):

- per-cell cost `cost (B, N, N)` (vanilla A*: 1 on free cells); heuristic `h = d(cell, goal) + tb * euclid(cell,
  goal) + cost[cell]` with `tb = 0.001`, `d` the distance of the movement model (Chebyshev on `moore`, which the
  authors compute as `dx + dy - min(dx, dy)`; octile on `octile`; Manhattan on `news`);
- `g` of the start 0; the cell selected (closed, "expanded") is the open cell of the largest float32
  `exp(-f / sqrt(N))`, `f = g_ratio * g + (1 - g_ratio) * h`, the FIRST such cell in row-major order on ties;
- the selected cell's free neighbours (its movement model's moves; without corner cutting a diagonal also needs
  both cells beside it free) get `g2 = g[selected] + cost[selected] * move_cost` (the cost of the cell LEFT, as the
  authors charge it; `move_cost` is 1 on `moore` and `news`, sqrt 2 for a diagonal on `octile`) when they are
  neither open nor closed, or when they are open and `g > g2`; then they are open with the selected cell as parent.
  A closed cell is never reopened;
- the search stops when the goal is selected (termination `goal`; the path is the parents' chain from the start to
  the goal), when the open list is empty (the goal cannot be reached) or after `int(tmax * N * N)` selections (the
  authors' budget `Tmax * size * size`); both of the latter end as `step_limit` with the one-cell path `[start]`.
  The expanded cells are the selected ones, start and goal included: the authors' `histories`.

Arithmetic (`exact=False`, the replica): as PyTorch computes the authors' code in float32 on the CPU: `h`, `g`, `f`,
`x = (-f) / float32(sqrt N)` and `exp(x)` all float32, each operation rounded to float32 in the authors' order, so
two cells tie exactly when their float32 `exp` values are equal, and the row-major first of them wins, as with
their `argmax`. Two differences, both documented, neither seen on the MP maps: (1) `exp` is computed in float64 and
rounded once to float32 (the correctly rounded float32 `exp` but for rare double roundings; PyTorch's vectorised
float32 `exp` is within one unit in the last place of it), and the authors divide the values by their sum before the
`argmax`, which can merge two values one unit apart; (2) where `exp(x)` is subnormal or underflows to 0 (`f / sqrt
N` above about 87: long searches on large maps), cells of different `f` tie (and where every open value is 0 the
authors' division gives NaN and an arbitrary cell): the replica orders such cells by `f` (smallest first), then by
row-major index.

Arithmetic (`exact=True`): float64 `g`, `h`, `f`; ties of `f` go to the smaller `tb * euclid` term, then to the
row-major first cell, and `g` improves only by more than 1e-9 (`COST_TOL`). The tie term then only breaks ties and
the search is exact A* whatever the move costs: on `octile` two path costs `a + b sqrt 2` can differ by less than
the `tb` term (or than float32 rounding), which would make the replica suboptimal there.

The planners: `astar` is vanilla A* (`g_ratio` 0.5, unit cost on free cells) on the maps' movement model: the
replica on `moore` and `news` (exact there: every move costs 1 and the tie term stays below 1/2 for N <= 354, so
it never outweighs a move; larger maps use `exact`), `exact` on `octile`. On `moore` maps it is the authors' vanilla A*,
expansions included. `wastar:w=W` is weighted A*, `f = g + W h` (as `g_ratio = 1 / (1 + W)`), suboptimal for
`W > 1`, with the same arithmetic rule.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from vinadv.errors import InputError
from vinadv.grid.moves import DEFAULT_MOVES, check_moves, move_model
from vinadv.grid.shortest_paths import COST_TOL, legal_move
from vinadv.planners.interface import Capabilities, PlannerError
from vinadv.planners.result import GOAL, STEP_LIMIT, PlanResult, check_plan_inputs
from vinadv.planners.search import SearchPlanner, SearchResult

__all__ = [
    "TIE_BREAK",
    "AStarPlanner",
    "WeightedAStarPlanner",
    "best_first_search",
    "replica_is_exact",
]

#: the weight of the Euclidean tie-break term of the heuristic (the authors' `tb_factor`)
TIE_BREAK = 0.001
#: the smallest normal float32: below it `exp` loses precision (subnormal), so the replica orders by `f` there
FLOAT32_TINY = np.float32(np.finfo(np.float32).tiny)


def replica_is_exact(moves: str, size: int) -> bool:
    """Whether the float32 replica arithmetic is exact A* for unit costs on `size x size` maps of the movement model
    `moves`: every move costs 1 (path costs are integers) and the tie term `TIE_BREAK * euclid` stays below 1/2 over
    the grid, so it never outweighs a move."""
    return move_model(moves).unit_costs and TIE_BREAK * math.sqrt(2.0) * max(int(size) - 1, 0) < 0.5


# ------------------------------------------------------------------------------------------------ the heap


@numba.njit(cache=True, nogil=True, inline="always")
def _heap_less(k1, k2, cell, i, j):
    """Entry i before entry j of the heap arrays: `(k1, k2, cell)` lexicographic, smallest first."""
    if k1[i] != k1[j]:
        return k1[i] < k1[j]
    if k2[i] != k2[j]:
        return k2[i] < k2[j]
    return cell[i] < cell[j]


@numba.njit(cache=True, nogil=True, inline="always")
def _heap_swap(k1, k2, cell, i, j):
    k1[i], k1[j] = k1[j], k1[i]
    k2[i], k2[j] = k2[j], k2[i]
    cell[i], cell[j] = cell[j], cell[i]


@numba.njit(cache=True, nogil=True)
def _heap_push(k1, k2, cell, size, a, b, c):
    """Push `(a, b, c)` on the heap held in the first `size` entries; returns the new size."""
    k1[size], k2[size], cell[size] = a, b, c
    i = size
    while i > 0:
        parent = (i - 1) // 2
        if not _heap_less(k1, k2, cell, i, parent):
            break
        _heap_swap(k1, k2, cell, i, parent)
        i = parent
    return size + 1


@numba.njit(cache=True, nogil=True)
def _heap_pop(k1, k2, cell, size):
    """Remove the first entry (moved to index `size - 1`); returns the new size."""
    size -= 1
    _heap_swap(k1, k2, cell, 0, size)
    i = 0
    while True:
        child = 2 * i + 1
        if child >= size:
            break
        if child + 1 < size and _heap_less(k1, k2, cell, child + 1, child):
            child += 1
        if not _heap_less(k1, k2, cell, child, i):
            break
        _heap_swap(k1, k2, cell, i, child)
        i = child
    return size


# ---------------------------------------------------------------------------------------------- the kernel


@numba.njit(cache=True, nogil=True)
def _replica_key(g, h, g_ratio32, h_ratio32, sqrt_n32):
    """`(k1, k2)` of a cell in the replica: minus the float32 `exp(-f / sqrt N)` (largest first), and `f` where
    that `exp` is subnormal or 0 (else 0): the order of the authors' `argmax`, the cell index breaking the ties."""
    f = np.float32(np.float32(g_ratio32 * g) + np.float32(h_ratio32 * h))
    x = np.float32(np.float32(-f) / sqrt_n32)
    e = np.float32(math.exp(np.float64(x)))  # float64 exp, rounded once: the float32 exp (module doc)
    return -np.float64(e), (np.float64(f) if e < FLOAT32_TINY else 0.0)


@numba.njit(cache=True, nogil=True)
def _pop_current(hk1, hk2, hcell, size, state, key1):
    """Pop the heap until an entry that is current (its cell open, its key the cell's key in `key1`); returns
    `(cell, new size)`, the cell -1 where the heap runs out."""
    while size > 0:
        size = _heap_pop(hk1, hk2, hcell, size)
        i = hcell[size]
        if state[i] == 1 and hk1[size] == key1[i]:
            return i, size
    return -1, size


@numba.njit(cache=True, nogil=True)
def _close(sel, goal, state, parent, expanded, cells_out):
    """Close the selected cell `sel` and mark it expanded. Returns `(path length, termination)` where the search
    ends: no cell to select (`sel` -1: `(1, STEP_LIMIT)`) or the goal (its parents' chain written into `cells_out`,
    start first: `(length, GOAL)`); elsewhere `(0, STEP_LIMIT)`, the search goes on."""
    if sel < 0:
        return 1, STEP_LIMIT  # open list empty: the goal cannot be reached
    m = expanded.shape[1]
    state[sel] = 2
    expanded[sel // m, sel - (sel // m) * m] = True
    if sel != goal:
        return 0, STEP_LIMIT
    length = 0
    i = goal
    while i >= 0:
        length += 1
        i = parent[i]
    i = goal
    for k in range(length - 1, -1, -1):
        cells_out[k, 0] = i // m
        cells_out[k, 1] = i - (i // m) * m
        i = parent[i]
    return length, GOAL


@numba.njit(cache=True, nogil=True)
def _successor(obstacles, state, sel, dr, dc, corner_cutting):
    """The index of the cell one move `(dr, dc)` from the cell `sel` where the move is legal (the maps' rule) and
    that cell is not closed; else -1."""
    m = obstacles.shape[1]
    r = sel // m
    c = sel - r * m
    if not legal_move(obstacles, r, c, dr, dc, corner_cutting):
        return -1
    j = (r + dr) * m + (c + dc)
    return -1 if state[j] == 2 else j


@numba.njit(cache=True, nogil=True)
def _search_one(cost, obstacles, sr, sc, gr, gc, params, cells_out, expanded):
    """One search (see the module doc) from `(sr, sc)` to `(gr, gc)` with the parameters `params` that
    `best_first_search` packs; fills `cells_out` (the path, start first) and `expanded`; returns
    `(path length, termination)`."""
    g_ratio, deltas, move_costs, diagonal_cost, tie_break, corner_cutting, exact, budget = params
    n = obstacles.shape[0]
    m = obstacles.shape[1]
    cells = n * m
    g32 = np.zeros(cells, dtype=np.float32)
    g64 = np.zeros(cells, dtype=np.float64)
    h32 = np.zeros(cells, dtype=np.float32)
    h64 = np.zeros(cells, dtype=np.float64)
    tb64 = np.zeros(cells, dtype=np.float64)
    state = np.zeros(cells, dtype=np.int8)  # 0 new, 1 open, 2 closed
    parent = np.full(cells, -1, dtype=np.int64)
    key1 = np.zeros(cells, dtype=np.float64)  # the cell's current key, to skip stale heap entries
    cap = deltas.shape[0] * cells + 1
    hk1 = np.empty(cap, dtype=np.float64)
    hk2 = np.empty(cap, dtype=np.float64)
    hcell = np.empty(cap, dtype=np.int64)
    g_ratio32 = np.float32(g_ratio)
    h_ratio32 = np.float32(1.0 - g_ratio)
    sqrt_n32 = np.float32(math.sqrt(m))
    tb32 = np.float32(tie_break)
    for r in range(n):  # the heuristic h = d + tb * euclid + cost, in the arithmetic of the mode
        for c in range(m):
            dr = abs(r - gr)
            dc = abs(c - gc)
            lo = min(dr, dc)
            d = (max(dr, dc) - lo) + lo * diagonal_cost
            i = r * m + c
            if exact:
                tb64[i] = tie_break * math.sqrt(dr * dr + dc * dc)
                h64[i] = d + np.float64(cost[r, c])
            else:
                euc = np.float32(math.sqrt(np.float32(dr * dr + dc * dc)))
                h = np.float32(np.float32(d) + np.float32(tb32 * euc))
                h32[i] = np.float32(h + cost[r, c])
    start = sr * m + sc
    goal = gr * m + gc
    state[start] = 1
    if exact:
        a = (1.0 - g_ratio) * h64[start]
        size = _heap_push(hk1, hk2, hcell, 0, a, tb64[start], start)
        key1[start] = a
    else:
        a, b = _replica_key(g32[start], h32[start], g_ratio32, h_ratio32, sqrt_n32)
        size = _heap_push(hk1, hk2, hcell, 0, a, b, start)
        key1[start] = a
    for _ in range(budget):
        sel, size = _pop_current(hk1, hk2, hcell, size, state, key1)  # the best open cell
        length, term = _close(sel, goal, state, parent, expanded, cells_out)
        if length > 0:
            return length, term
        r = sel // m
        c = sel - r * m
        for a_ in range(deltas.shape[0]):
            j = _successor(obstacles, state, sel, deltas[a_, 0], deltas[a_, 1], corner_cutting)
            if j < 0:
                continue
            if exact:
                g2_64 = g64[sel] + np.float64(cost[r, c]) * move_costs[a_]
                if state[j] == 1 and not g2_64 < g64[j] - COST_TOL:
                    continue
                g64[j] = g2_64
                k1 = g_ratio * g2_64 + (1.0 - g_ratio) * h64[j]
                k2 = tb64[j]
            else:
                g2_32 = np.float32(g32[sel] + np.float32(cost[r, c] * np.float32(move_costs[a_])))
                if state[j] == 1 and not g32[j] > g2_32:
                    continue
                g32[j] = g2_32
                k1, k2 = _replica_key(g2_32, h32[j], g_ratio32, h_ratio32, sqrt_n32)
            state[j] = 1
            parent[j] = sel
            key1[j] = k1
            size = _heap_push(hk1, hk2, hcell, size, k1, k2, j)
    return 1, STEP_LIMIT  # the budget is spent


@numba.njit(cache=True, nogil=True)
def _search_row(b, inputs, params, outputs):
    """Search row `b` of the batch into row `b` of the outputs (`[start]` where the goal is not reached); the
    arguments are the tuples `_search` packs."""
    cost, obstacles, starts, goals = inputs
    cells_out, lengths, termination, expanded = outputs
    length, term = _search_one(
        cost[b], obstacles[b], starts[b, 0], starts[b, 1], goals[b, 0], goals[b, 1], params, cells_out[b], expanded[b]
    )
    if term != GOAL:
        cells_out[b, 0, 0] = starts[b, 0]
        cells_out[b, 0, 1] = starts[b, 1]
    lengths[b] = length
    termination[b] = term


@numba.njit(cache=True, parallel=True)
def _search_batch(inputs, params, outputs):
    """Every row, in parallel over rows (Numba threads)."""
    for b in numba.prange(inputs[0].shape[0]):
        _search_row(b, inputs, params, outputs)


@numba.njit(cache=True, nogil=True)
def _search_rows(inputs, params, outputs):
    """Every row on the calling thread: for a few rows, where waking `_search_batch`'s threads costs more."""
    for b in range(inputs[0].shape[0]):
        _search_row(b, inputs, params, outputs)


#: batches of fewer rows are searched on the calling thread (`_search_rows`)
PARALLEL_FROM = 4


def best_first_search(
    cost: np.ndarray,
    obstacles: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    g_ratio: float = 0.5,
    moves: str = "moore",
    corner_cutting: bool = True,
    tmax: float = 1.0,
    exact: bool | None = None,
) -> SearchResult:
    """One best-first search per row with the Neural A* authors' arithmetic (module doc), batched and compiled.

    Args:
        cost: `(B, N, N)` float, finite, >= 0: the cost of each cell (charged when the search leaves it, and added to
            the heuristic): 1 on free cells for vanilla A* and a guidance map otherwise (the encoder output of
            Neural A*).
        obstacles: `(B, N, N)` bool, True = obstacle: never opened.
        starts: `(B, 2)` int `(row, col)` of each start.
        goals: `(B, 2)` int `(row, col)` of each goal.
        g_ratio: `f = g_ratio * g + (1 - g_ratio) * h`, in [0, 1]: 0.5 is A*, `1 / (1 + w)` weighted A* with weight
            `w`, 0 greedy best-first.
        moves: the movement model (`vinadv.grid.moves`): the moves, their costs, and the distance of the heuristic
            (Chebyshev on `moore`, octile on `octile`, Manhattan on `news`).
        corner_cutting: whether a diagonal move may pass between two obstacles (the authors' search allows it);
            without it a diagonal needs both cells beside it free.
        tmax: the budget is `int(tmax * N * N)` selections (the authors' `Tmax`), in (0, 1].
        exact: the arithmetic: False, the float32 replica of the authors'; True, float64 with the tie term only
            breaking ties (exact A* on any costs); None: the replica where it is exact for unit costs
            (`replica_is_exact`), else exact.

    Returns:
        `SearchResult`: per row the path (start to goal, or `[start]` where the goal was not reached), the
        termination (`goal`, or `step_limit`: open list empty or budget spent) and `expanded (B, N, N)` bool, the
        selected cells (the authors' `histories`).

    Raises InputError naming the argument for inputs of the wrong shape or value.
    """
    obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
    model = move_model(check_moves(moves, corner_cutting))
    cost = np.asarray(cost)
    if cost.shape != obstacles.shape or cost.dtype.kind not in "fiub":
        raise InputError(
            f"cost has shape {cost.shape} and dtype {cost.dtype}, expected float {obstacles.shape}", "cost"
        )
    cost = np.ascontiguousarray(cost, dtype=np.float32)
    if not np.isfinite(cost).all() or (cost < 0).any():
        raise InputError("cost has a negative, NaN or infinite value: expected finite costs >= 0", "cost")
    g_ratio = float(g_ratio)
    if not 0.0 <= g_ratio <= 1.0:
        raise InputError(f"g_ratio {g_ratio!r}: expected a number in [0, 1]", "g_ratio")
    tmax = float(tmax)
    if not 0.0 < tmax <= 1.0:
        raise InputError(f"tmax {tmax!r}: expected a number in (0, 1]", "tmax")
    b, n = obstacles.shape[0], obstacles.shape[1]
    if exact is None:
        exact = not replica_is_exact(model.name, n)
    budget = int(tmax * n * n)
    cells = np.zeros((b, max(1, n * n), 2), dtype=np.int16)
    lengths = np.zeros(b, dtype=np.int64)
    termination = np.zeros(b, dtype=np.int8)
    expanded = np.zeros(obstacles.shape, dtype=bool)
    if b:
        search = _search_batch if b >= PARALLEL_FROM else _search_rows
        search(
            (cost, obstacles, starts, goals),
            (
                g_ratio,
                model.deltas,
                model.costs,
                float(model.diagonal_cost),
                TIE_BREAK,
                bool(corner_cutting),
                bool(exact),
                budget,
            ),
            (cells, lengths, termination, expanded),
        )
    plan = PlanResult.from_buffers(cells, lengths, termination)
    return SearchResult(paths=plan.paths, termination=plan.termination, expanded=expanded)


def reference_expansions(
    obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool, moves: str
) -> np.ndarray:
    """`(B,)` int64: the cells the exact A* (`AStarPlanner`) of the movement model `moves` expands from each start
    to its goal, the reference a search planner's expansions are judged against (`vinadv.classify.effort`)."""
    obstacles = np.asarray(obstacles, dtype=bool)
    planner = AStarPlanner(obstacles.shape[-1], moves)
    return planner.plan(obstacles, starts, goals, corner_cutting, moves).expansions


class AStarPlanner(SearchPlanner):
    """Vanilla A* on the maps' movement model (`g_ratio` 0.5, cost 1 on free cells; module doc): exact shortest
    paths, with the cells it expanded; on `moore` maps the Neural A* authors' vanilla A*, expansion for expansion.
    Capabilities: expansions (its value maps are the stand-in, minus the exact cost-to-go; no gradients)."""

    capabilities = Capabilities(expansions=True)
    g_ratio = 0.5

    def __init__(self, size: int, moves: str = DEFAULT_MOVES):
        self.name, self.size = "astar", int(size)
        self.moves = move_model(moves).name

    @property
    def config(self) -> dict:
        # octile, the default, is left out, as for `optimal`
        return {} if self.moves == DEFAULT_MOVES else {"moves": self.moves}

    def for_moves(self, moves: str) -> SearchPlanner:
        model = move_model(moves)
        return self if model.name == self.moves else self._with_moves(model.name)

    def _with_moves(self, moves: str) -> SearchPlanner:
        return AStarPlanner(self.size, moves)

    def plan_paths(
        self, obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool = True
    ) -> SearchResult:
        obstacles, starts, goals = check_plan_inputs(obstacles, starts, goals)
        self._check_size(obstacles)
        return best_first_search(
            (~obstacles).astype(np.float32), obstacles, starts, goals, self.g_ratio, self.moves, corner_cutting
        )


class WeightedAStarPlanner(AStarPlanner):
    """Weighted A*: `f = g + w * h` (`g_ratio = 1 / (1 + w)`), the heuristic of `astar`; suboptimal for `w > 1`, with
    fewer expansions. `w = 1` is `astar`."""

    def __init__(self, size: int, moves: str = DEFAULT_MOVES, w: float = 2.0):
        super().__init__(size, moves)
        w = float(w)
        if not (math.isfinite(w) and w >= 1.0):
            raise PlannerError(f"w {w!r}: the weight of weighted A* is a number >= 1", "w")
        self.name, self.w = "wastar", w
        self.g_ratio = 1.0 / (1.0 + w)

    @property
    def config(self) -> dict:
        return {**super().config, "w": self.w}

    def _with_moves(self, moves: str) -> SearchPlanner:
        return WeightedAStarPlanner(self.size, moves, self.w)
