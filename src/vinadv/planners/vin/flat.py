"""The flat zero-padded map layout of the compiled kernels (the planning engine and the PyTorch replay).

A map lives in a flat array: row stride W, the smallest multiple of 8 above N (so every row starts on a vector
boundary), cell (i, j) at p0 + i * W + j with p0 = 2 * W, zeros around (two rows above, the W - N cells after each
row, two rows below). The 3x3 neighbours of every cell are then the same nine offsets, and one loop of
(N - 1) * W + N cells covers the map (the padding cells between rows are computed and thrown away, then put back to
0 by `zero_row_gaps`), so the vector loops run long, not N cells at a time.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def layout(n):
    """(W, p0, length, size) of an N x N map: row stride, index of cell (0, 0), cells one loop covers, array
    length."""
    width = (n + 8) // 8 * 8
    return width, 2 * width, (n - 1) * width + n, (n + 4) * width


@numba.njit(cache=True, nogil=True)
def zero_row_gaps(flat, n):
    """Set the padding cells between rows of a flat map (computed and thrown away by the long loops) back to 0."""
    width, p0 = layout(n)[:2]
    for i in range(n - 1):
        for j in range(n, width):  # (a slice assignment per row costs more than the whole row of stores)
            flat[p0 + i * width + j] = 0.0


@numba.njit(inline="always")
def kernel_taps(w):
    """The nine taps of a 3x3 kernel `w (3, 3)`, row by row, as nine scalars: a kernel loads them once per channel and
    keeps them in registers through its long loop over cells. Inlined into the caller: `w.ravel()` unpacked into
    nine names instead measured 6-12% slower in the engine's planning (single thread)."""
    return w[0, 0], w[0, 1], w[0, 2], w[1, 0], w[1, 1], w[1, 2], w[2, 0], w[2, 1], w[2, 2]


def to_flat(maps: np.ndarray) -> np.ndarray:
    """`(C, N, N)` -> `(C, size)` float32 in the flat layout."""
    c, n = maps.shape[0], maps.shape[1]
    width, p0, _, size = layout(n)
    out = np.zeros((c, size), dtype=np.float32)
    out[:, p0 : p0 + n * width].reshape(c, n, width)[:, :, :n] = maps
    return out


def from_flat(flat: np.ndarray, n: int) -> np.ndarray:
    """`(C, size)` in the flat layout -> `(C, N, N)`."""
    width, p0 = layout(n)[:2]
    return np.ascontiguousarray(flat[:, p0 : p0 + n * width].reshape(len(flat), n, width)[:, :, :n])
