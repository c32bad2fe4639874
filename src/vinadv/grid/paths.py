"""Paths as flat arrays: varying-length paths stored as `cells (total, 2)` plus `offsets (n + 1,)`.

Path `i` is `cells[offsets[i]:offsets[i + 1]]`, a sequence of `(row, col)` cells, start first.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vinadv.grid.actions import SQRT2


def pack_paths(paths: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Pack a list of `(L_i, 2)` cell arrays into `(cells int16 (sum L_i, 2), offsets int64 (n + 1,))`."""
    lengths = np.array([len(p) for p in paths], dtype=np.int64)
    offsets = np.zeros(len(paths) + 1, dtype=np.int64)
    np.cumsum(lengths, out=offsets[1:])
    if len(paths) == 0 or offsets[-1] == 0:
        return np.zeros((0, 2), dtype=np.int16), offsets
    cells = np.concatenate([np.asarray(p, dtype=np.int16).reshape(-1, 2) for p in paths])
    return cells, offsets


def unpack_paths(cells: np.ndarray, offsets: np.ndarray) -> list[np.ndarray]:
    """The inverse of `pack_paths`: a list of `(L_i, 2)` views into `cells`."""
    return [cells[offsets[i] : offsets[i + 1]] for i in range(len(offsets) - 1)]


def path_costs(cells: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Cost of each packed path (1 per orthogonal move, sqrt(2) per diagonal move), shape (n,).

    Every path needs at least one cell.
    """
    n = len(offsets) - 1
    if n == 0:
        return np.zeros(0)
    cells = np.asarray(cells, dtype=np.int64)
    move = np.abs(np.diff(cells, axis=0))
    step = move[:, 0] + move[:, 1]  # not .sum(axis=1): NumPy's reduction over a length-2 axis is ~50x slower
    # cost[k] is the move from cell k to cell k + 1; the last cell of each path makes no move.
    cost = np.append(np.where(step == 2, SQRT2, step.astype(np.float64)), 0.0)
    cost[offsets[1:] - 1] = 0.0
    return np.add.reduceat(cost, offsets[:-1])


def take_paths(cells: np.ndarray, offsets: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The packed paths at `idx` (int array), repacked as `(cells, offsets)`; no Python loop over paths."""
    lengths = np.diff(offsets)[idx]
    new_offsets = np.zeros(len(idx) + 1, dtype=np.int64)
    np.cumsum(lengths, out=new_offsets[1:])
    # position j of the output takes cell offsets[idx[p]] + (j - new_offsets[p]) for the path p holding j
    owner = np.repeat(np.arange(len(idx)), lengths)
    src = offsets[idx][owner] + np.arange(new_offsets[-1]) - new_offsets[:-1][owner]
    return cells[src], new_offsets
