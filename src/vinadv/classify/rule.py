"""The exact FP/DP rule (DESIGN.md, category 4) and the full five-way labeller.

`Do` = cells of the original path not on the adversarial path, `Da` the reverse (as sets of cells).
`dh = max |col_i - col_j|` over `i in Do, j in Da` with equal rows, `dv = max |row_i - row_j|` over pairs with
equal columns, 0 where no such pair exists. `DP` when `dh <= t and dv <= t`, else `FP`. `t` defaults to
`round(4 * N / 28)` (4 at 28x28).

Vectorised with one Numba kernel over the packed cells: O(total cells) time, O(N^2) scratch memory.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from vinadv.classify.features import path_features
from vinadv.errors import InputError
from vinadv.grid.paths import PackedPaths


def default_threshold(size: int) -> int:
    """The FP/DP threshold `t` for `size x size` maps: `round(4 * size / 28)` (4 at 28x28)."""
    return int(round(4 * int(size) / 28))


@numba.njit(cache=True, nogil=True)
def _distances_kernel(o_cells, o_offsets, a_cells, a_offsets, size, dh, dv):  # pragma: no cover - compiled
    mark = np.zeros((size, size), dtype=np.uint8)  # bit 1: on the original path, bit 2: on the adversarial
    # per row: min/max column of Do and of Da cells in it; per column: min/max row. -1 = none yet.
    row_min_o = np.full(size, -1, np.int64)
    row_max_o = np.full(size, -1, np.int64)
    row_min_a = np.full(size, -1, np.int64)
    row_max_a = np.full(size, -1, np.int64)
    col_min_o = np.full(size, -1, np.int64)
    col_max_o = np.full(size, -1, np.int64)
    col_min_a = np.full(size, -1, np.int64)
    col_max_a = np.full(size, -1, np.int64)
    n = len(o_offsets) - 1
    for p in range(n):
        for i in range(o_offsets[p], o_offsets[p + 1]):
            mark[o_cells[i, 0], o_cells[i, 1]] |= 1
        for i in range(a_offsets[p], a_offsets[p + 1]):
            mark[a_cells[i, 0], a_cells[i, 1]] |= 2
        for i in range(o_offsets[p], o_offsets[p + 1]):
            r = o_cells[i, 0]
            c = o_cells[i, 1]
            if mark[r, c] & 2 == 0:
                if row_min_o[r] < 0 or c < row_min_o[r]:
                    row_min_o[r] = c
                if c > row_max_o[r]:
                    row_max_o[r] = c
                if col_min_o[c] < 0 or r < col_min_o[c]:
                    col_min_o[c] = r
                if r > col_max_o[c]:
                    col_max_o[c] = r
        for i in range(a_offsets[p], a_offsets[p + 1]):
            r = a_cells[i, 0]
            c = a_cells[i, 1]
            if mark[r, c] & 1 == 0:
                if row_min_a[r] < 0 or c < row_min_a[r]:
                    row_min_a[r] = c
                if c > row_max_a[r]:
                    row_max_a[r] = c
                if col_min_a[c] < 0 or r < col_min_a[c]:
                    col_min_a[c] = r
                if r > col_max_a[c]:
                    col_max_a[c] = r
        h = 0
        v = 0
        # max |x - y| over two sets = max(max X - min Y, max Y - min X)
        for i in range(o_offsets[p], o_offsets[p + 1]):
            r = o_cells[i, 0]
            c = o_cells[i, 1]
            if row_max_o[r] >= 0 and row_max_a[r] >= 0:
                h = max(h, row_max_o[r] - row_min_a[r], row_max_a[r] - row_min_o[r])
            if col_max_o[c] >= 0 and col_max_a[c] >= 0:
                v = max(v, col_max_o[c] - col_min_a[c], col_max_a[c] - col_min_o[c])
        dh[p] = h
        dv[p] = v
        # reset only what this pair touched, so the scratch costs O(path length) per pair
        for i in range(o_offsets[p], o_offsets[p + 1]):
            r = o_cells[i, 0]
            c = o_cells[i, 1]
            mark[r, c] = 0
            row_min_o[r] = -1
            row_max_o[r] = -1
            col_min_o[c] = -1
            col_max_o[c] = -1
            row_min_a[r] = -1
            row_max_a[r] = -1
            col_min_a[c] = -1
            col_max_a[c] = -1
        for i in range(a_offsets[p], a_offsets[p + 1]):
            r = a_cells[i, 0]
            c = a_cells[i, 1]
            mark[r, c] = 0
            row_min_o[r] = -1
            row_max_o[r] = -1
            col_min_o[c] = -1
            col_max_o[c] = -1
            row_min_a[r] = -1
            row_max_a[r] = -1
            col_min_a[c] = -1
            col_max_a[c] = -1


def path_distances(path_o: PackedPaths, path_a: PackedPaths, size: int) -> tuple[np.ndarray, np.ndarray]:
    """`(dh, dv)`, each `(n,)` int64 cells: the horizontal and vertical distances of the rule, for n pairs of
    original and adversarial paths on `size x size` maps."""
    size = int(size)
    path_o.check_grid(size, "original paths")
    path_a.check_grid(size, "adversarial paths")
    if len(path_o) != len(path_a):
        raise InputError(f"{len(path_o)} original paths but {len(path_a)} adversarial paths")
    dh = np.zeros(len(path_o), dtype=np.int64)
    dv = np.zeros(len(path_o), dtype=np.int64)
    _distances_kernel(path_o.cells, path_o.offsets, path_a.cells, path_a.offsets, size, dh, dv)
    return dh, dv


def is_fork(dh: np.ndarray, dv: np.ndarray, t: int) -> np.ndarray:
    """FP (True) or DP (False) from the distances: DP iff `dh <= t and dv <= t`."""
    return (np.asarray(dh) > t) | (np.asarray(dv) > t)


@dataclass(frozen=True)
class PairLabels:
    """Rule labels of `n` pairs: `labels` `(n,)` str (one of `LABELS`), `dh`, `dv` `(n,)` int64, threshold `t`.

    `dh`/`dv` are computed for every pair (0 for identical paths), whatever its label.
    """

    labels: np.ndarray
    dh: np.ndarray
    dv: np.ndarray
    t: int


def label_pairs(path_o: PackedPaths, path_a: PackedPaths, goals, size: int, t: int | None = None) -> PairLabels:
    """The full DESIGN.md label of each pair (original and adversarial paths, goals `(n, 2)`, `size x size`
    maps): invalid, UrP, UcP, then DP/FP by the rule with threshold `t`."""
    size = int(size)
    t = default_threshold(size) if t is None else int(t)
    if t < 0:
        raise InputError(f"threshold t must be >= 0, got {t}")
    dh, dv = path_distances(path_o, path_a, size)
    goals = np.asarray(goals, dtype=np.int64).reshape(-1, 2)
    if len(goals) != len(dh):
        raise InputError(f"{len(goals)} goals for {len(dh)} path pairs")
    features = path_features(path_o, path_a, goals)
    labels = np.where(is_fork(dh, dv, t), "FP", "DP").astype("<U7")
    labels[features.unchanged] = "UcP"
    labels[features.unreached] = "UrP"
    labels[features.invalid] = "invalid"
    return PairLabels(labels, dh, dv, t)


def label_batch(batch, t: int | None = None) -> PairLabels:
    """`label_pairs` of a `PathPairBatch`."""
    return label_pairs(batch.path_o, batch.path_a, batch.goals, batch.size, t)
