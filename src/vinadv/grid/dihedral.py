"""The 8 flips/rotations of the square (the dihedral group), for cells, NumPy arrays and PyTorch tensors.

Transform ids (cells are `(row, col)`; "clockwise" as an image is displayed):
`0` identity, `1` rotate 90 clockwise, `2` rotate 180, `3` rotate 270 clockwise, `4` flip horizontally
(left-right), `5` flip vertically (up-down), `6` transpose, `7` anti-transpose.

Each id is written once, in `STEPS`, as "transpose?, then flip the rows?, then flip the columns?"; cells and
grids both follow that table, so they cannot disagree. The FP/DP rule is invariant under all 8 (DESIGN.md).
"""

from __future__ import annotations

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.actions import ACTION_DELTAS

NAMES = ("identity", "rot90", "rot180", "rot270", "flip_h", "flip_v", "transpose", "antitranspose")
#: (transpose, flip rows, flip columns) of each transform id, applied in that order.
STEPS = (
    (False, False, False),
    (True, False, True),
    (False, True, True),
    (True, True, False),
    (False, False, True),
    (False, True, False),
    (True, False, False),
    (True, True, True),
)
_STEPS = np.array(STEPS, dtype=bool)  # (8, 3)
#: the id of each transform's inverse (rot90 and rot270 undo each other; every flip and transpose undoes itself)
INVERSE = (0, 3, 2, 1, 4, 5, 6, 7)


def _check(transform) -> np.ndarray:
    transform = np.asarray(transform, dtype=np.int64)
    if np.any((transform < 0) | (transform >= len(STEPS))):
        bad = transform[(transform < 0) | (transform >= len(STEPS))].reshape(-1)[0]
        raise InputError(f"transform: dihedral transform ids are 0-7, got {bad}", "transform")
    return transform


def transform_cells(cells: np.ndarray, size: int, transform) -> np.ndarray:
    """`(row, col)` cells `(m, 2)` of a `size x size` grid moved by transform id(s) `transform` (scalar or `(m,)`):
    `(m, 2)` int64."""
    cells = np.asarray(cells, dtype=np.int64).reshape(-1, 2)
    steps = _STEPS[np.broadcast_to(_check(transform), (len(cells),))]  # (m, 3)
    last = int(size) - 1
    r = np.where(steps[:, 0], cells[:, 1], cells[:, 0])
    c = np.where(steps[:, 0], cells[:, 0], cells[:, 1])
    r = np.where(steps[:, 1], last - r, r)
    c = np.where(steps[:, 2], last - c, c)
    return np.stack([r, c], axis=1)


def transform_actions(transform: int) -> np.ndarray:
    """`(8,)` int64: entry `a` is the action whose move is action `a`'s move under transform id `transform`
    (moves in `vinadv.grid.actions`' order), so a policy on a transformed map reads action `perm[a]` at a cell
    where the original map's policy reads `a`."""
    transpose, flip_rows, flip_cols = STEPS[int(_check(transform))]
    moved = ACTION_DELTAS[:, ::-1] if transpose else ACTION_DELTAS
    moved = moved * np.array([-1 if flip_rows else 1, -1 if flip_cols else 1])
    match = np.all(moved[:, None, :] == ACTION_DELTAS[None, :, :], axis=-1)  # (8, 8): moved a == action b
    return match.argmax(axis=1)


def transform_grids(grids, transform: int, axes: tuple[int, int] = (1, 2)):
    """Grids (a NumPy array or a PyTorch tensor) with the row and column axes `axes` under one transform id.

    NumPy arrays come back contiguous; tensors as PyTorch's `transpose`/`flip` return them.
    """
    transpose, flip_rows, flip_cols = STEPS[int(_check(transform))]
    rows, cols = axes
    flips = tuple(axis for axis, flip in ((rows, flip_rows), (cols, flip_cols)) if flip)
    if isinstance(grids, np.ndarray):
        out = np.swapaxes(grids, rows, cols) if transpose else grids
        return np.ascontiguousarray(np.flip(out, flips) if flips else out)
    out = grids.transpose(rows, cols) if transpose else grids
    return out.flip(flips) if flips else out
