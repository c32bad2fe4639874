"""The `k` smallest keys of each row, in order, without sorting whole rows: how starts are drawn on a map (random
keys) and how an attack keeps its best candidates of a map (minus their scores).

`smallest_first(keys, k)` is `np.argsort(keys, axis=1, kind="stable")[:, :k]` (ties to the lower index, NaN last),
found in one pass over each row that keeps its `k` smallest so far in order: where a map's cells are the row and `k`
is a few, a small fraction of a full sort (`perf/grid.py` prints both; 1,000 rows of 784, k 1 to 8: 1-2 ms against
30-150 ms on the loaded 2-core machine).
"""

from __future__ import annotations

import numba
import numpy as np

#: above this share of a row, a full stable sort is as cheap as keeping the smallest in order
FULL_SORT_SHARE = 0.25


def smallest_first(keys: np.ndarray, k: int) -> np.ndarray:
    """Indices of the `k` smallest keys of each row of `keys` `(B, M)`, smallest first, ties to the lower index, NaN
    after every number: `(B, min(k, M))` int64, equal to `np.argsort(keys, axis=1, kind="stable")[:, :k]`."""
    keys = np.asarray(keys)
    b, m = keys.shape
    k = max(0, min(int(k), m))
    if b == 0 or k == 0 or k > FULL_SORT_SHARE * m or keys.dtype.kind != "f":
        return np.argsort(keys, axis=1, kind="stable")[:, :k]
    if k == 1 and not np.isnan(keys).any():  # argmin takes the lowest index among equals
        return np.argmin(keys, axis=1)[:, None]
    out = np.empty((b, k), dtype=np.int64)
    _smallest_first(np.ascontiguousarray(keys), out)
    return out


@numba.njit(cache=True, nogil=True)
def _before(x, y):
    """Whether key `x` sorts strictly before `y` (NaN after every number)."""
    return x < y or (np.isnan(y) and not np.isnan(x))


@numba.njit(cache=True, nogil=True)
def _smallest_first(keys, out):
    b, m = keys.shape
    k = out.shape[1]
    best = np.empty(k, dtype=keys.dtype)
    for row in range(b):
        filled = 0
        for j in range(m):
            x = keys[row, j]
            if filled == k and not _before(x, best[k - 1]):
                continue
            # after every kept key not sorting after x: equal keys keep their index order
            i = min(filled, k - 1)
            while i > 0 and _before(x, best[i - 1]):
                best[i] = best[i - 1]
                out[row, i] = out[row, i - 1]
                i -= 1
            best[i] = x
            out[row, i] = j
            filled = min(filled + 1, k)
