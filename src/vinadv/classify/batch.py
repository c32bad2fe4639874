"""A batch of path pairs as flat arrays: the input of every classifier in `vinadv.classify`.

Paths are packed as in `vinadv.grid.paths`: path `i` is `cells[offsets[i]:offsets[i + 1]]`, `(row, col)`
cells, start first. Pair `i` is (original path `i`, adversarial path `i`) on a map of `size x size` cells
with goal `goals[i]`.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vinadv.errors import InputError


def _check_packed(cells: np.ndarray, offsets: np.ndarray, size: int, name: str) -> tuple[np.ndarray, np.ndarray]:
    cells = np.ascontiguousarray(cells, dtype=np.int16).reshape(-1, 2)
    offsets = np.ascontiguousarray(offsets, dtype=np.int64).reshape(-1)
    if len(offsets) == 0 or offsets[0] != 0 or offsets[-1] != len(cells) or np.any(np.diff(offsets) < 0):
        raise InputError(f"{name}: offsets must start at 0, never decrease and end at the number of cells")
    if len(cells) and (cells.min() < 0 or cells.max() >= size):
        raise InputError(f"{name}: cells outside the {size}x{size} grid")
    return cells, offsets


def take_segments(cells: np.ndarray, offsets: np.ndarray, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Packed paths `index` of `(cells, offsets)`, repacked: `(cells (total, 2), offsets (len(index) + 1,))`."""
    index = np.asarray(index, dtype=np.int64).reshape(-1)
    lengths = (offsets[1:] - offsets[:-1])[index]
    new_offsets = np.zeros(len(index) + 1, dtype=np.int64)
    np.cumsum(lengths, out=new_offsets[1:])
    gather = np.repeat(offsets[:-1][index] - new_offsets[:-1], lengths) + np.arange(new_offsets[-1])
    return cells[gather], new_offsets


def pair_ids(offsets: np.ndarray) -> np.ndarray:
    """The pair index of each packed cell, `(total,)` int64."""
    return np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))


@dataclass(frozen=True)
class PathPairBatch:
    """`n` (original, adversarial) path pairs on `size x size` maps.

    Fields: `o_cells, a_cells` int16 `(total, 2)`, `o_offsets, a_offsets` int64 `(n + 1,)`, `goals` int64
    `(n, 2)`, `size` N (cells per side).
    """

    o_cells: np.ndarray
    o_offsets: np.ndarray
    a_cells: np.ndarray
    a_offsets: np.ndarray
    goals: np.ndarray
    size: int

    @classmethod
    def from_arrays(cls, o_cells, o_offsets, a_cells, a_offsets, goals, size: int) -> PathPairBatch:
        """Validated batch from packed arrays (raises InputError naming the bad field)."""
        size = int(size)
        if size < 1:
            raise InputError(f"size must be positive, got {size}")
        o_cells, o_offsets = _check_packed(o_cells, o_offsets, size, "original paths")
        a_cells, a_offsets = _check_packed(a_cells, a_offsets, size, "adversarial paths")
        goals = np.ascontiguousarray(goals, dtype=np.int64).reshape(-1, 2)
        n = len(o_offsets) - 1
        if len(a_offsets) - 1 != n or len(goals) != n:
            raise InputError(
                f"path pairs disagree on their number: {n} original paths, {len(a_offsets) - 1} adversarial, "
                f"{len(goals)} goals"
            )
        return cls(o_cells, o_offsets, a_cells, a_offsets, goals, size)

    @classmethod
    def from_paths(cls, originals: Sequence, adversarials: Sequence, goals, size: int) -> PathPairBatch:
        """Batch from two lists of `(L_i, 2)` cell arrays."""
        from vinadv.grid.paths import pack_paths

        o_cells, o_offsets = pack_paths([np.asarray(p).reshape(-1, 2) for p in originals])
        a_cells, a_offsets = pack_paths([np.asarray(p).reshape(-1, 2) for p in adversarials])
        return cls.from_arrays(o_cells, o_offsets, a_cells, a_offsets, goals, size)

    @classmethod
    def from_pairset(cls, pairs) -> PathPairBatch:
        """The path pairs of a `vinadv.attacks.pairs.PairSet`."""
        return cls.from_arrays(
            pairs.path_o_cells, pairs.path_o_offsets, pairs.path_a_cells, pairs.path_a_offsets,
            pairs.goals, np.asarray(pairs.obstacles_o).shape[-1],
        )

    def __len__(self) -> int:
        return len(self.o_offsets) - 1

    def subset(self, index) -> PathPairBatch:
        """Pairs `index` (an int array or a bool mask), in that order."""
        index = np.asarray(index)
        if index.dtype == bool:
            index = np.flatnonzero(index)
        o_cells, o_offsets = take_segments(self.o_cells, self.o_offsets, index)
        a_cells, a_offsets = take_segments(self.a_cells, self.a_offsets, index)
        return PathPairBatch(o_cells, o_offsets, a_cells, a_offsets, self.goals[index], self.size)

    def transformed(self, transform) -> PathPairBatch:
        """Every pair flipped/rotated by a dihedral transform: one id `0..7` or one per pair (see `images`)."""
        from vinadv.classify.images import transform_cells

        transform = np.asarray(transform, dtype=np.int64)
        if transform.ndim == 0:
            to, ta, tg = transform, transform, transform
        else:
            to = np.repeat(transform, np.diff(self.o_offsets))
            ta = np.repeat(transform, np.diff(self.a_offsets))
            tg = transform
        return PathPairBatch(
            transform_cells(self.o_cells, self.size, to).astype(np.int16),
            self.o_offsets,
            transform_cells(self.a_cells, self.size, ta).astype(np.int16),
            self.a_offsets,
            transform_cells(self.goals, self.size, tg).astype(np.int64),
            self.size,
        )

    def fingerprint(self) -> str:
        """SHA-256 of the pairs' contents: tells whether two batches hold the same pairs."""
        digest = hashlib.sha256()
        for array in (self.o_cells, self.o_offsets, self.a_cells, self.a_offsets, self.goals):
            digest.update(np.ascontiguousarray(array).tobytes())
        digest.update(str(self.size).encode())
        return digest.hexdigest()


def concat_batches(batches: Sequence[PathPairBatch]) -> PathPairBatch:
    """One batch holding the pairs of `batches` in order (all of one size)."""
    if not batches:
        raise InputError("no path pairs to concatenate")
    sizes = {b.size for b in batches}
    if len(sizes) != 1:
        raise InputError(f"path pairs of different map sizes: {sorted(sizes)}")

    def cat(cells_name, offsets_name):
        cells = np.concatenate([getattr(b, cells_name) for b in batches])
        lengths = np.concatenate([np.diff(getattr(b, offsets_name)) for b in batches])
        offsets = np.zeros(len(lengths) + 1, dtype=np.int64)
        np.cumsum(lengths, out=offsets[1:])
        return cells, offsets

    o_cells, o_offsets = cat("o_cells", "o_offsets")
    a_cells, a_offsets = cat("a_cells", "a_offsets")
    goals = np.concatenate([b.goals for b in batches])
    return PathPairBatch(o_cells, o_offsets, a_cells, a_offsets, goals, sizes.pop())
