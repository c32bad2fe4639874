"""`PackedPaths`: n varying-length paths stored flat, `cells (total, 2)` plus `offsets (n + 1,)`.

Path `i` is `cells[offsets[i]:offsets[i + 1]]`, a sequence of `(row, col)` cells, start first. This is the
layout of every paths field in vinadv's files (`*_cells` int16, `*_offsets` int64) and of every type that holds
paths (plans, pairs, stored records); subsetting and concatenation are vectorised, never a loop over paths.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.moves import DEFAULT_MOVES, move_model
from vinadv.npzfile import check_cells_in_grid, check_offsets

#: the values a cell's row or column may hold (the int16 of vinadv's files)
CELL_RANGE = (int(np.iinfo(np.int16).min), int(np.iinfo(np.int16).max))


def _check_cell_values(cells: np.ndarray) -> None:
    """Refuse (InputError naming the value) cells that int16 would change: not numbers, floats that are not whole
    numbers (NaN and infinities included), or values outside int16's range. Checked in the cells' own dtype, before
    any cast, so `r + 65536` never wraps into the grid and `1.7` is never truncated to 1."""
    if cells.dtype == np.int16 or cells.size == 0:
        return
    if cells.dtype.kind not in "iuf":
        raise InputError(f"cells has dtype {cells.dtype}, expected integers")
    if cells.dtype.kind == "f":
        whole = np.isfinite(cells) & (cells == np.round(cells))
        if not whole.all():
            raise InputError(f"cells hold {cells[~whole][0].item()!r}, not a whole number")
    low, high = cells.min(), cells.max()
    if low < CELL_RANGE[0] or high > CELL_RANGE[1]:
        value = (low if low < CELL_RANGE[0] else high).item()
        raise InputError(f"cells hold {value!r}, outside {CELL_RANGE[0]}..{CELL_RANGE[1]} (int16)")


class PackedPaths:
    """n paths of `(row, col)` cells, packed flat.

    Attributes:
        cells: `(total, 2)` int16, all paths one after the other.
        offsets: `(n + 1,)` int64, `offsets[0] == 0`, never decreasing, `offsets[-1] == total`; path `i` is
            `cells[offsets[i]:offsets[i + 1]]` (an empty path is allowed here; files demand at least one cell).

    Construction checks the layout (InputError naming `offsets`/`cells`) and converts the dtypes (no copy when
    they already match). Instances are immutable by convention: operations return new ones.
    """

    __slots__ = ("cells", "offsets")

    def __init__(self, cells, offsets):
        cells = np.asarray(cells)
        offsets = np.asarray(offsets)
        if cells.size == 0:
            cells = cells.reshape(0, 2)
        if cells.ndim != 2 or cells.shape[1] != 2:
            raise InputError(f"cells has shape {cells.shape}, expected (total, 2)")
        if cells.size and not np.issubdtype(cells.dtype, np.integer):
            raise InputError(f"cells has dtype {cells.dtype}, expected integers")
        if offsets.ndim != 1 or len(offsets) == 0 or (offsets.size and not np.issubdtype(offsets.dtype, np.integer)):
            raise InputError(f"offsets has shape {offsets.shape} and dtype {offsets.dtype}, expected (n + 1,) integers")
        if offsets[0] != 0 or offsets[-1] != len(cells) or np.any(offsets[1:] < offsets[:-1]):
            raise InputError(f"offsets must start at 0, never decrease and end at the number of cells ({len(cells)})")
        _check_cell_values(cells)
        self.cells = np.ascontiguousarray(cells, dtype=np.int16)
        self.offsets = np.ascontiguousarray(offsets, dtype=np.int64)

    # --- construction -------------------------------------------------------------------------------------------

    @classmethod
    def pack(cls, paths: Sequence[np.ndarray]) -> PackedPaths:
        """Pack a sequence of `(L_i, 2)` cell arrays (or lists of `(row, col)`). The cells are checked in their own
        dtype before they become int16 (`_check_cell_values`): a float that is not a whole number, or a number
        outside int16, is refused, never truncated or wrapped."""
        arrays = [np.asarray(p).reshape(-1, 2) for p in paths]
        offsets = np.zeros(len(arrays) + 1, dtype=np.int64)
        np.cumsum([len(a) for a in arrays], out=offsets[1:])
        nonempty = [a for a in arrays if a.size]
        cells = np.concatenate(nonempty) if nonempty else np.zeros((0, 2), np.int16)
        if cells.dtype.kind == "f":
            _check_cell_values(cells)
            cells = cells.astype(np.int64)
        return cls(cells, offsets)

    @classmethod
    def empty(cls, n: int = 0) -> PackedPaths:
        """`n` empty paths."""
        return cls(np.zeros((0, 2), np.int16), np.zeros(n + 1, np.int64))

    @classmethod
    def concat(cls, parts: Sequence[PackedPaths]) -> PackedPaths:
        """The paths of `parts`, in order (no parts: zero paths)."""
        parts = list(parts)
        if not parts:
            return cls.empty()
        lengths = np.concatenate([p.lengths for p in parts])
        offsets = np.zeros(len(lengths) + 1, dtype=np.int64)
        np.cumsum(lengths, out=offsets[1:])
        return cls(np.concatenate([p.cells for p in parts]), offsets)

    # --- access ---------------------------------------------------------------------------------------------------

    def __len__(self) -> int:
        return len(self.offsets) - 1

    def __getitem__(self, i: int) -> np.ndarray:
        """Path `i`: a `(L_i, 2)` int16 view into `cells`."""
        i = range(len(self))[i]  # bounds check and negative indices, as for a list
        return self.cells[self.offsets[i] : self.offsets[i + 1]]

    def __eq__(self, other) -> bool:
        if not isinstance(other, PackedPaths):
            return NotImplemented
        return np.array_equal(self.offsets, other.offsets) and np.array_equal(self.cells, other.cells)

    __hash__ = None  # mutable arrays inside

    def __repr__(self) -> str:
        return f"PackedPaths({len(self)} paths, {len(self.cells)} cells)"

    def __getstate__(self):
        return self.cells, self.offsets

    def __setstate__(self, state) -> None:
        self.cells, self.offsets = state

    @property
    def lengths(self) -> np.ndarray:
        """`(n,)` int64 number of cells of each path (moves + 1 for a non-empty path)."""
        return np.diff(self.offsets)

    def unpack(self) -> list[np.ndarray]:
        """The paths as a list of `(L_i, 2)` int16 views into `cells`."""
        return [self.cells[a:b] for a, b in zip(self.offsets[:-1].tolist(), self.offsets[1:].tolist())]

    def owners(self) -> np.ndarray:
        """`(total,)` int64: the path each cell belongs to."""
        return np.repeat(np.arange(len(self)), self.lengths)

    def take(self, index) -> PackedPaths:
        """The paths at `index` (int array, bool mask or slice), in that order, repacked."""
        idx = np.arange(len(self))[index]
        return self._segments(self.offsets[:-1][idx], self.lengths[idx])

    def prefixes(self, lengths) -> PackedPaths:
        """The first `lengths[i]` cells of each path i (`(n,)` ints, each at most that path's length)."""
        lengths = np.asarray(lengths, dtype=np.int64)
        if lengths.shape != (len(self),) or np.any((lengths < 0) | (lengths > self.lengths)):
            raise InputError(f"lengths: expected {len(self)} values between 0 and each path's length")
        return self._segments(self.offsets[:-1], lengths)

    def _segments(self, starts: np.ndarray, lengths: np.ndarray) -> PackedPaths:
        """New paths `cells[starts[p]:starts[p] + lengths[p]]`, packed without a loop over paths."""
        offsets = np.zeros(len(lengths) + 1, dtype=np.int64)
        np.cumsum(lengths, out=offsets[1:])
        # output position j takes cell starts[p] + (j - offsets[p]) for the path p holding j
        gather = np.repeat(starts - offsets[:-1], lengths) + np.arange(offsets[-1])
        return PackedPaths(self.cells[gather], offsets)

    # --- figures ----------------------------------------------------------------------------------------------------

    def costs(self, moves: str = DEFAULT_MOVES) -> np.ndarray:
        """`(n,)` float64 cost of each path under the movement model `moves` (`vinadv.grid.moves`): 1 per
        orthogonal move, a diagonal move sqrt(2) on `octile` and 1 on `moore` (0 for <= 1 cell)."""
        diagonal = move_model(moves).diagonal_cost  # sqrt 2, 1 (news paths have no diagonal move)
        if len(self.cells) == 0:
            return np.zeros(len(self))
        cells = self.cells.astype(np.int64)
        move = np.abs(np.diff(cells, axis=0))
        step = move[:, 0] + move[:, 1]  # not .sum(axis=1): NumPy's reduction over a length-2 axis is ~50x slower
        # cost[k] is the move from cell k to cell k + 1; the last cell of each path makes no move
        cost = np.append(np.where(step == 2, diagonal, step.astype(np.float64)), 0.0)
        nonempty = self.lengths > 0
        cost[self.offsets[1:][nonempty] - 1] = 0.0
        out = np.zeros(len(self))
        out[nonempty] = np.add.reduceat(cost, self.offsets[:-1][nonempty])
        return out

    def same_as(self, other: PackedPaths) -> np.ndarray:
        """`(n,)` bool: path `i` of `self` equals path `i` of `other`, cell for cell."""
        if len(other) != len(self):
            raise InputError(f"cannot compare {len(self)} paths with {len(other)} paths")
        same = self.lengths == other.lengths
        idx = np.flatnonzero(same)
        if len(idx) == 0:
            return same
        mine, theirs = self.take(idx), other.take(idx)
        differs = np.any(mine.cells != theirs.cells, axis=1)
        same[idx] = np.bincount(mine.owners()[differs], minlength=len(idx)) == 0
        return same

    def check_grid(self, size: int, name: str = "paths") -> None:
        """Raise InputError naming `name` unless every cell lies in the `size x size` grid."""
        if len(self.cells) and (self.cells.min() < 0 or self.cells.max() >= size):
            raise InputError(f"{name}: cells outside the {size}x{size} grid")

    # --- files ----------------------------------------------------------------------------------------------------

    def to_fields(self, prefix: str) -> dict[str, np.ndarray]:
        """The file fields `{prefix}_cells` int16 and `{prefix}_offsets` int64."""
        return {f"{prefix}_cells": self.cells, f"{prefix}_offsets": self.offsets}

    @classmethod
    def read(cls, reader, prefix: str, n: int, size: int) -> PackedPaths:
        """Fields `{prefix}_cells`/`{prefix}_offsets` of an `NpzReader`, checked: `n` paths of at least one cell
        inside the `size x size` grid (errors name the file and the field)."""
        cells = reader.array(f"{prefix}_cells", "i", 2, (None, 2))
        offsets = reader.array(f"{prefix}_offsets", "i", 1).astype(np.int64)
        check_cells_in_grid(reader, f"{prefix}_cells", cells, size)
        check_offsets(reader, f"{prefix}_offsets", offsets, n, len(cells))
        return cls(cells, offsets)


def path_costs(paths: PackedPaths, moves: str) -> np.ndarray:
    """`(n,)` float64 cost of each path under the movement model `moves`: its move count where every move costs 1
    (`moore`, `news`), `PackedPaths.costs` (straight 1, diagonal sqrt 2) on `octile`."""
    if move_model(moves).unit_costs:
        return np.maximum(paths.lengths - 1, 0).astype(np.float64)
    return paths.costs()
