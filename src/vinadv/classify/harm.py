"""Harm of a path pair (DESIGN.md, "Harm"): did the attack make the planner's path worse, or only different?

Beside the paper's label, for a pair on the original map `o` and the adversarial map `a` (same start and goal):

- `opt_cost_o`, `opt_cost_a`: exact shortest-path costs start -> goal (the moves and costs of the pairs' movement
  model, `vinadv.grid.moves`: octile, moore or news);
- `cost_o`, `cost_a`: the cost of the planner's path on each map (same model) when it reaches the goal, else NaN;
- `regret_x = cost_x - opt_cost_x` (NaN when the path misses the goal);
- `expert_label`: the paper's rule (`vinadv.classify.rule`) applied to the two expert paths (optimal paths, ties
  to the lowest action index, as `vinadv.grid.shortest_paths.expert_paths`): did the optimal route itself change?
- `harm`: `invalid` for an invalid pair, `harmful` for UrP or when `regret_a > regret_o + tol + rtol * opt_cost_a`,
  `harmless` otherwise. A fork onto another optimal route is harmless: a perfect planner does the same.

Speed (`perf/harm.py`). One compiled kernel, parallel over blocks of pairs, does per pair:
1. the original map: an A* search from the goal with the model's distance to the start as heuristic (octile,
   Chebyshev on moore, Manhattan on news: consistent, with or without corner cutting), run until every cell on an
   optimal path is settled, so the expert path can be walked from the start with the exact tie-break. Consecutive
   pairs of one original map (a map attacked several times) share that search, and the generator's expert paths
   can be passed in (`expert_o`) to skip it;
2. the adversarial map adds obstacles only, so its paths are a subset of the original's: when the original expert
   path uses no move the added obstacles remove, it is also the adversarial map's expert path (every cell on it
   keeps its cost, and no lower action becomes optimal, as costs only grow) and `opt_cost_a = opt_cost_o`, the
   expert label UcP. Only the other pairs search the adversarial map, and only they run the rule's distances.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from vinadv.classify.rule import default_threshold, distances_kernel, is_fork
from vinadv.errors import InputError
from vinadv.grid.columns import Columns
from vinadv.grid.moves import DEFAULT_MOVES, move_model
from vinadv.grid.paths import PackedPaths
from vinadv.grid.shortest_paths import COST_TOL, heap_pop, heap_push, legal_move
from vinadv.vocabulary import HARMS, LABELS

#: default absolute tolerance of the harm test (cost units: one orthogonal move = 1)
DEFAULT_TOL = 1e-6
#: pairs per block of the kernel (a block runs on one thread, its pairs in order, so a shared original is seen)
_BLOCK = 256

# expert-label codes written by the kernel
_E_INVALID, _E_URP, _E_UCP, _E_CHANGED = 0, 1, 2, 3


@dataclass(kw_only=True, eq=False)
class PairHarm(Columns):
    """Harm of `n` pairs (see the module doc). Costs are in the movement model's units (a straight move costs 1; a
    diagonal sqrt 2 on octile, 1 on moore).

    Attributes:
        opt_cost_o, opt_cost_a: `(n,)` float64, exact optimal cost start -> goal; NaN where the goal is unreachable.
        cost_o, cost_a: `(n,)` float64, cost of the planner's path; NaN where it does not reach the goal.
        regret_o, regret_a: `(n,)` float64, `cost_x - opt_cost_x` (>= 0 up to float error); NaN where unreached.
        expert_label: `(n,)` str, the rule label of the two expert paths: 'UcP' | 'DP' | 'FP' ('invalid' / 'UrP'
            only where the goal is unreachable on the original / adversarial map).
        harm: `(n,)` str, 'harmful' | 'harmless' | 'invalid'.
        tol, rtol: the absolute and relative tolerance used for `harm` (settings, not rows: `Columns.META`).
    """

    META = ("tol", "rtol")

    opt_cost_o: np.ndarray
    opt_cost_a: np.ndarray
    cost_o: np.ndarray
    cost_a: np.ndarray
    regret_o: np.ndarray
    regret_a: np.ndarray
    expert_label: np.ndarray
    harm: np.ndarray
    tol: float = DEFAULT_TOL
    rtol: float = 0.0


def harm_summary(table: dict[str, dict[str, int]]) -> dict:
    """The harm figures of a summary from a `cross_table`: pairs per harm value, harmful pairs, the harmful rate
    (harmful over valid pairs, as the paper's success rate) and the table itself."""
    counts = {value: sum(row[value] for row in table.values()) for value in HARMS}
    valid = counts["harmful"] + counts["harmless"]
    return {
        "harm_counts": counts,
        "harmful": counts["harmful"],
        "harmful_rate": counts["harmful"] / valid if valid else None,
        "label_x_harm": {label: dict(row) for label, row in table.items()},
    }


def cross_table(labels, harm) -> dict[str, dict[str, int]]:
    """Pairs per (paper label, harm): `{label: {harm: count}}`, every label and harm value present."""
    labels = np.asarray(labels)
    harm = np.asarray(harm)
    return {label: {value: int(np.sum((labels == label) & (harm == value))) for value in HARMS} for label in LABELS}


def harm_decision(labels, regret_o, regret_a, opt_cost_a, tol: float = DEFAULT_TOL, rtol: float = 0.0) -> np.ndarray:
    """`harm` from the paper's labels and the regrets, `(n,)` str (DESIGN.md): invalid for 'invalid', harmful for
    'UrP' or `regret_a > regret_o + tol + rtol * opt_cost_a`, harmless otherwise."""
    labels = np.asarray(labels)
    with np.errstate(invalid="ignore"):
        worse = np.asarray(regret_a) > np.asarray(regret_o) + tol + rtol * np.asarray(opt_cost_a)
    harm = np.where(worse | (labels == "UrP"), "harmful", "harmless").astype("<U8")
    harm[labels == "invalid"] = "invalid"
    return harm


def pair_harm(
    obstacles_o: np.ndarray,
    obstacles_a: np.ndarray,
    starts: np.ndarray,
    goals: np.ndarray,
    path_o: PackedPaths,
    path_a: PackedPaths,
    labels: np.ndarray,
    corner_cutting: bool = True,
    *,
    tol: float = DEFAULT_TOL,
    rtol: float = 0.0,
    t: int | None = None,
    expert_o: tuple[np.ndarray, PackedPaths] | None = None,
    moves: str = DEFAULT_MOVES,
) -> PairHarm:
    """Harm of `n` pairs.

    Args:
        obstacles_o: `(n, N, N)` bool, True = obstacle: the original maps.
        obstacles_a: `(n, N, N)` bool: the adversarial maps, which add obstacles to `obstacles_o` (a pair where they
            do not is still right, only slower).
        starts: `(n, 2)` int `(row, col)`.
        goals: `(n, 2)` int `(row, col)`.
        path_o: `PackedPaths` of n paths, the planner's paths on the original maps.
        path_a: `PackedPaths` of n paths, the planner's paths on the adversarial maps.
        labels: `(n,)` str, the paper's label of each pair ('invalid' | 'UrP' | 'UcP' | 'DP' | 'FP').
        corner_cutting: the run's corner-cutting setting (the moves of the optimal paths).
        tol: absolute tolerance of the harm test (cost units), >= 0.
        rtol: relative tolerance of the harm test (times `opt_cost_a`), >= 0.
        t: the rule's FP/DP threshold for `expert_label` (default `round(4 * N / 28)`).
        expert_o: optional expert data of the original maps already computed (the generator's `expert_costs[:, 0]`
            and expert paths, one per pair): `(costs (n,), PackedPaths of n paths)`.
        moves: the pairs' movement model (`vinadv.grid.moves`): the moves and costs of the optimal paths and of the
            planner's paths.
    """
    model = move_model(moves)
    obstacles_o = np.ascontiguousarray(obstacles_o, dtype=np.bool_)
    obstacles_a = np.ascontiguousarray(obstacles_a, dtype=np.bool_)
    if obstacles_o.ndim != 3 or obstacles_o.shape[1] != obstacles_o.shape[2]:
        raise InputError(f"obstacles_o: expected shape (n, N, N), got {obstacles_o.shape}")
    n, size = obstacles_o.shape[:2]
    if obstacles_a.shape != obstacles_o.shape:
        raise InputError(f"obstacles_a: expected shape {obstacles_o.shape}, got {obstacles_a.shape}")
    starts = _cells(starts, "starts", n, size)
    goals = _cells(goals, "goals", n, size)
    labels = np.asarray(labels).astype(str)
    if labels.shape != (n,):
        raise InputError(f"labels: expected shape ({n},), got {labels.shape}")
    check_tolerances(tol, rtol, ("tol", "rtol"))
    t = default_threshold(size) if t is None else int(t)
    if t < 0:
        raise InputError(f"threshold t must be >= 0, got {t}")
    given = None if expert_o is None else expert_o[1]
    for name, paths in (("path_o", path_o), ("path_a", path_a), ("expert_o", given)):
        if paths is not None and len(paths) != n:
            raise InputError(f"{name}: {len(paths)} paths for {n} pairs", name)

    if expert_o is None:
        given_cost, given_cells, given_offsets = np.zeros(0), np.zeros((0, 2), np.int16), np.zeros(1, np.int64)
    else:
        given_cost = np.ascontiguousarray(expert_o[0], dtype=np.float64).reshape(-1)
        given_cells, given_offsets = expert_o[1].cells, expert_o[1].offsets
        if len(given_cost) != n:
            raise InputError(f"expert_o: {len(given_cost)} costs for {n} pairs", "expert_o")
        if len(given_cells) and (given_cells.min() < 0 or given_cells.max() >= size):
            raise InputError(f"expert_o: cells outside the {size}x{size} grid", "expert_o")
    opt_o = np.empty(n)
    opt_a = np.empty(n)
    code = np.empty(n, dtype=np.int8)
    dh = np.zeros(n, dtype=np.int64)
    dv = np.zeros(n, dtype=np.int64)
    if n:
        flat_o, flat_a = (m.reshape(n, -1).view(np.uint8) for m in (obstacles_o, obstacles_a))
        _harm_kernel(
            obstacles_o,
            obstacles_a,
            flat_o,
            flat_a,
            starts,
            goals,
            bool(corner_cutting),
            model.deltas,
            model.costs,
            model.diagonal_cost,
            expert_o is not None,
            given_cost,
            given_cells,
            given_offsets,
            opt_o,
            opt_a,
            code,
            dh,
            dv,
        )
    expert_label = np.where(is_fork(dh, dv, t), "FP", "DP").astype("<U7")
    expert_label[code == _E_UCP] = "UcP"
    expert_label[code == _E_URP] = "UrP"
    expert_label[code == _E_INVALID] = "invalid"

    cost_o = _reached_costs(path_o, goals, model.diagonal_cost)
    cost_a = _reached_costs(path_a, goals, model.diagonal_cost)
    opt_o[~np.isfinite(opt_o)] = np.nan
    opt_a[~np.isfinite(opt_a)] = np.nan
    regret_o = cost_o - opt_o
    regret_a = cost_a - opt_a
    return PairHarm(
        opt_cost_o=opt_o,
        opt_cost_a=opt_a,
        cost_o=cost_o,
        cost_a=cost_a,
        regret_o=regret_o,
        regret_a=regret_a,
        expert_label=expert_label,
        harm=harm_decision(labels, regret_o, regret_a, opt_a, tol, rtol),
        tol=float(tol),
        rtol=float(rtol),
    )


def check_tolerances(tol: float, rtol: float, names=("harm_tolerance", "harm_rtol")) -> None:
    """InputError naming the bad one (as the parameter `names`) unless both are finite numbers >= 0."""
    for name, value in zip(names, (tol, rtol)):
        if not np.isfinite(value) or value < 0:
            raise InputError(f"{name}: must be a finite number >= 0, got {value}", name)


def pairset_harm(
    pairs, labels: np.ndarray, *, tol: float = DEFAULT_TOL, rtol: float = 0.0, t: int | None = None, expert_o=None
) -> PairHarm:
    """`pair_harm` of a `vinadv.attacks.pairs.PairSet`-like object (read by field name) and its labels."""
    return pair_harm(
        pairs.obstacles_o,
        pairs.obstacles_a,
        pairs.starts,
        pairs.goals,
        pairs.path_o,
        pairs.path_a,
        labels,
        pairs.corner_cutting,
        tol=tol,
        rtol=rtol,
        t=t,
        expert_o=expert_o,
        moves=getattr(pairs, "moves", DEFAULT_MOVES),
    )


def _cells(value, name: str, n: int, size: int) -> np.ndarray:
    arr = np.ascontiguousarray(value, dtype=np.int64)
    if arr.shape != (n, 2):
        raise InputError(f"{name}: expected shape ({n}, 2), got {arr.shape}")
    if n and (arr.min() < 0 or arr.max() >= size):
        raise InputError(f"{name}: cells outside the {size}x{size} grid")
    return arr


def _reached_costs(paths: PackedPaths, goals, diagonal_cost: float) -> np.ndarray:
    """Cost of each path that ends on its goal (1 per straight move, `diagonal_cost` per diagonal: sqrt 2 on octile
    as `PackedPaths.costs`, 1 on moore; news paths have none), in one compiled pass, NaN for the others: `(n,)`
    float64."""
    out = np.empty(len(paths))
    _reached_costs_kernel(paths.cells, paths.offsets, goals, diagonal_cost, out)
    return out


@numba.njit(cache=True, nogil=True)
def _reached_costs_kernel(cells, offsets, goals, diagonal_cost, out):
    for i in range(len(out)):
        lo, hi = offsets[i], offsets[i + 1]
        if hi == lo or cells[hi - 1, 0] != goals[i, 0] or cells[hi - 1, 1] != goals[i, 1]:
            out[i] = np.nan
            continue
        total = 0.0
        for j in range(lo + 1, hi):
            step = abs(cells[j, 0] - cells[j - 1, 0]) + abs(cells[j, 1] - cells[j - 1, 1])
            total += diagonal_cost if step == 2 else step
        out[i] = total


# --------------------------------------------------------------------------------------------- the kernel


@numba.njit(cache=True, nogil=True)
def _load_padded(obs, pad, w):
    """Copy the map `obs` (N, N) into the interior of `pad`, a flat `(N + 2)^2` map whose one-cell border is
    obstacle: moves then need no bounds checks, and off-grid counts as an obstacle, as for `legal_move`."""
    n = obs.shape[0]
    for r in range(n):
        base = (r + 1) * w + 1
        for c in range(n):
            pad[base + c] = obs[r, c]


@numba.njit(cache=True, nogil=True, inline="always")
def _padded_legal(pad, p, a, step, side_r, side_c, corner_cutting):
    """Whether action `a` from the cell `p` of the padded flat map is legal (as `legal_move`)."""
    if pad[p + step[a]]:
        return False
    if not corner_cutting and side_r[a] != 0 and side_c[a] != 0:
        if pad[p + side_r[a]] or pad[p + side_c[a]]:
            return False
    return True


@numba.njit(cache=True, nogil=True, inline="always")
def _distance(p, w, sr, sc, diag):
    """The model's distance on an open map from the cell `p` of a padded flat map (row width `w`) to the cell
    `(sr, sc)` (padded): `diag` per diagonal step (`MoveModel.diagonal_cost`: octile sqrt 2, Chebyshev 1,
    Manhattan 2)."""
    r = p // w
    dr = abs(r - sr)
    dc = abs(p - r * w - sc)
    return min(dr, dc) * (diag - 1.0) + max(dr, dc)


@numba.njit(cache=True, nogil=True)
def _search(pad, w, s, goal, corner_cutting, step, side_r, side_c, costs, diag, g, stamp, epoch, heap_key, heap_val):
    """A* on the padded flat map `pad` (row width `w`) from the cell `goal` toward the cell `s` over the moves
    `step` (heuristic: the model's distance to `s`, `_distance`, consistent on any of these maps), run until every
    cell with `g + h <= optimum` is settled: those are all the cells of optimal paths, with their exact cost-to-goal
    in `g` (`stamp == epoch` marks a settled cell, `-epoch` one only reached). Returns the optimal cost, inf when
    `s` cannot be reached."""
    if pad[goal] or pad[s]:
        return np.inf
    sr = s // w
    sc = s - sr * w
    best = np.inf
    g[goal] = 0.0
    stamp[goal] = -epoch
    size = heap_push(heap_key, heap_val, 0, _distance(goal, w, sr, sc, diag), goal)
    while size > 0:
        f, p, size = heap_pop(heap_key, heap_val, size)
        if f > best + COST_TOL:
            break
        if stamp[p] == epoch:
            continue
        stamp[p] = epoch
        gv = g[p]
        if p == s:
            best = gv
        for a in range(step.shape[0]):
            if not _padded_legal(pad, p, a, step, side_r, side_c, corner_cutting):
                continue
            q = p + step[a]
            st = stamp[q]
            if st == epoch:
                continue
            nd = gv + costs[a]
            if st != -epoch or nd < g[q] - COST_TOL:
                g[q] = nd
                stamp[q] = -epoch
                size = heap_push(heap_key, heap_val, size, nd + _distance(q, w, sr, sc, diag), q)
    return best


@numba.njit(cache=True, nogil=True)
def _walk(pad, w, s, goal, corner_cutting, step, side_r, side_c, costs, g, stamp, epoch, out):
    """The expert path from `s` after `_search`: at each cell the lowest-index legal action onto a settled cell
    whose cost plus the move's equals the cell's (as `shortest_paths.optimal_actions`). Writes the `(row, col)`
    cells (unpadded) to `out` and returns their number."""
    p = s
    k = 0
    while True:
        r = p // w
        out[k, 0] = r - 1
        out[k, 1] = p - r * w - 1
        k += 1
        if p == goal:
            return k
        moved = False
        for a in range(step.shape[0]):
            q = p + step[a]
            if not _padded_legal(pad, p, a, step, side_r, side_c, corner_cutting):
                continue
            if stamp[q] == epoch and abs(costs[a] + g[q] - g[p]) <= COST_TOL:
                p = q
                moved = True
                break
        if not moved:  # cannot happen after a search that reached `s`; a guard against a silent loop
            return k


@numba.njit(cache=True, nogil=True)
def _same_original(obstacles_o, starts, goals, i):
    """Whether pair `i` has the original map, start and goal of pair `i - 1`."""
    if starts[i, 0] != starts[i - 1, 0] or starts[i, 1] != starts[i - 1, 1]:
        return False
    if goals[i, 0] != goals[i - 1, 0] or goals[i, 1] != goals[i - 1, 1]:
        return False
    a = obstacles_o[i]
    b = obstacles_o[i - 1]
    for r in range(a.shape[0]):
        for c in range(a.shape[1]):
            if a[r, c] != b[r, c]:
                return False
    return True


@numba.njit(cache=True, nogil=True)
def _only_adds(flat_o, flat_a):
    """Whether map `a` only adds obstacles to map `o` (both flat uint8 0/1): then every cost-to-goal can only grow.
    Branch-free, so the compiler vectorises it (a branch per cell cost ~5 us per 28x28 map)."""
    acc = np.uint8(0)
    for j in range(flat_o.shape[0]):
        acc |= flat_o[j] & ~flat_a[j]
    return acc == 0


@numba.njit(cache=True, nogil=True)
def _route_survives(obs_a, path, k, corner_cutting):
    """Whether the path `path[:k]` is still legal on `obs_a` (then, with `_only_adds`, it keeps its cost)."""
    for i in range(k):
        r = path[i, 0]
        c = path[i, 1]
        if obs_a[r, c]:
            return False
        if i > 0:
            pr = path[i - 1, 0]
            pc = path[i - 1, 1]
            if not legal_move(obs_a, pr, pc, r - pr, c - pc, corner_cutting):
                return False
    return True


@numba.njit(cache=True, parallel=True)
def _harm_kernel(
    obstacles_o,
    obstacles_a,
    flat_o,
    flat_a,
    starts,
    goals,
    corner_cutting,
    deltas,
    costs,
    diag,
    have_o,
    given_cost,
    given_cells,
    given_offsets,
    opt_o,
    opt_a,
    code,
    dh,
    dv,
):
    n_pairs, n = obstacles_o.shape[0], obstacles_o.shape[1]
    n_blocks = (n_pairs + _BLOCK - 1) // _BLOCK
    for block in numba.prange(n_blocks):
        w = n + 2
        pad = np.ones(w * w, dtype=np.uint8)
        n_act = deltas.shape[0]
        step = np.empty(n_act, dtype=np.int64)
        side_r = np.empty(n_act, dtype=np.int64)
        side_c = np.empty(n_act, dtype=np.int64)
        for a in range(n_act):
            side_r[a] = deltas[a, 0] * w
            side_c[a] = deltas[a, 1]
            step[a] = side_r[a] + side_c[a]
        g = np.empty(w * w, dtype=np.float64)
        stamp = np.zeros(w * w, dtype=np.int64)
        heap_key = np.empty(8 * w * w + 1, dtype=np.float64)
        heap_val = np.empty(8 * w * w + 1, dtype=np.int64)
        path_o = np.empty((n * n, 2), dtype=np.int16)
        path_a = np.empty((n * n, 2), dtype=np.int16)
        off_o = np.zeros(2, dtype=np.int64)
        off_a = np.zeros(2, dtype=np.int64)
        one_dh = np.zeros(1, dtype=np.int64)
        one_dv = np.zeros(1, dtype=np.int64)
        epoch = 0
        k_o = 0
        lo = block * _BLOCK
        hi = min(lo + _BLOCK, n_pairs)
        for i in range(lo, hi):
            s = (starts[i, 0] + 1) * w + starts[i, 1] + 1
            goal = (goals[i, 0] + 1) * w + goals[i, 1] + 1
            if have_o:
                opt_o[i] = given_cost[i]
                k_o = given_offsets[i + 1] - given_offsets[i]
                for j in range(k_o):
                    path_o[j, 0] = given_cells[given_offsets[i] + j, 0]
                    path_o[j, 1] = given_cells[given_offsets[i] + j, 1]
            elif i > lo and _same_original(obstacles_o, starts, goals, i):
                opt_o[i] = opt_o[i - 1]  # path_o and k_o are still pair i - 1's
            else:
                epoch += 1
                _load_padded(obstacles_o[i], pad, w)
                opt_o[i] = _search(
                    pad,
                    w,
                    s,
                    goal,
                    corner_cutting,
                    step,
                    side_r,
                    side_c,
                    costs,
                    diag,
                    g,
                    stamp,
                    epoch,
                    heap_key,
                    heap_val,
                )
                k_o = 0
                if opt_o[i] < np.inf:
                    k_o = _walk(pad, w, s, goal, corner_cutting, step, side_r, side_c, costs, g, stamp, epoch, path_o)
            if (
                opt_o[i] < np.inf
                and _only_adds(flat_o[i], flat_a[i])
                and _route_survives(obstacles_a[i], path_o, k_o, corner_cutting)
            ):
                opt_a[i] = opt_o[i]
                code[i] = _E_UCP
                continue
            epoch += 1
            _load_padded(obstacles_a[i], pad, w)
            opt_a[i] = _search(
                pad, w, s, goal, corner_cutting, step, side_r, side_c, costs, diag, g, stamp, epoch, heap_key, heap_val
            )
            if not opt_o[i] < np.inf:
                code[i] = _E_INVALID
                continue
            if not opt_a[i] < np.inf:
                code[i] = _E_URP
                continue
            k_a = _walk(pad, w, s, goal, corner_cutting, step, side_r, side_c, costs, g, stamp, epoch, path_a)
            off_o[1] = k_o
            off_a[1] = k_a
            distances_kernel(path_o[:k_o], off_o, path_a[:k_a], off_a, n, one_dh, one_dv)
            dh[i] = one_dh[0]
            dv[i] = one_dv[0]
            code[i] = _E_CHANGED
