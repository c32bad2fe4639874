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
def _record_extent(cells, lo, hi, mark, other_bit, ext):  # pragma: no cover - compiled
    """Per row the min/max column, per column the min/max row, of `cells[lo:hi]` not marked `other_bit`
    (the cells of one path not on the other): `ext` rows 0-3 = row min, row max, column min, column max."""
    for i in range(lo, hi):
        r = cells[i, 0]
        c = cells[i, 1]
        if mark[r, c] & other_bit == 0:
            if ext[0, r] < 0 or c < ext[0, r]:
                ext[0, r] = c
            if c > ext[1, r]:
                ext[1, r] = c
            if ext[2, c] < 0 or r < ext[2, c]:
                ext[2, c] = r
            if r > ext[3, c]:
                ext[3, c] = r


@numba.njit(cache=True, nogil=True)
def _reset(cells, lo, hi, mark, ext_o, ext_a):  # pragma: no cover - compiled
    """Clear what the cells `cells[lo:hi]` touched, so the scratch costs O(path length) per pair."""
    for i in range(lo, hi):
        r = cells[i, 0]
        c = cells[i, 1]
        mark[r, c] = 0
        for ext in (ext_o, ext_a):
            ext[0, r] = ext[1, r] = ext[2, c] = ext[3, c] = -1


@numba.njit(cache=True, nogil=True)
def distances_kernel(o_cells, o_offsets, a_cells, a_offsets, size, dh, dv):  # pragma: no cover - compiled
    """The rule's `(dh, dv)` of each pair of packed paths (cells and offsets of the originals and of the adversarial
    ones, on `size x size` maps) into `dh`, `dv` `(n,)` int64: `path_distances` without its checks."""
    mark = np.zeros((size, size), dtype=np.uint8)  # bit 1: on the original path, bit 2: on the adversarial
    # Do's and Da's extents (see `_record_extent`); -1 = none yet
    ext_o = np.full((4, size), -1, np.int64)
    ext_a = np.full((4, size), -1, np.int64)
    n = len(o_offsets) - 1
    for p in range(n):
        o_lo, o_hi, a_lo, a_hi = o_offsets[p], o_offsets[p + 1], a_offsets[p], a_offsets[p + 1]
        for i in range(o_lo, o_hi):
            mark[o_cells[i, 0], o_cells[i, 1]] |= 1
        for i in range(a_lo, a_hi):
            mark[a_cells[i, 0], a_cells[i, 1]] |= 2
        _record_extent(o_cells, o_lo, o_hi, mark, 2, ext_o)
        _record_extent(a_cells, a_lo, a_hi, mark, 1, ext_a)
        h = 0
        v = 0
        # max |x - y| over two sets = max(max X - min Y, max Y - min X)
        for i in range(o_lo, o_hi):
            r = o_cells[i, 0]
            c = o_cells[i, 1]
            if ext_o[1, r] >= 0 and ext_a[1, r] >= 0:
                h = max(h, ext_o[1, r] - ext_a[0, r], ext_a[1, r] - ext_o[0, r])
            if ext_o[3, c] >= 0 and ext_a[3, c] >= 0:
                v = max(v, ext_o[3, c] - ext_a[2, c], ext_a[3, c] - ext_o[2, c])
        dh[p] = h
        dv[p] = v
        _reset(o_cells, o_lo, o_hi, mark, ext_o, ext_a)
        _reset(a_cells, a_lo, a_hi, mark, ext_o, ext_a)


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
    distances_kernel(path_o.cells, path_o.offsets, path_a.cells, path_a.offsets, size, dh, dv)
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
