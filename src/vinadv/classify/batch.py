"""A batch of path pairs: the input of every classifier in `vinadv.classify`.

Pair `i` is (original path `i`, adversarial path `i`) on a map of `size x size` cells with goal `goals[i]`; the
paths are `PackedPaths` (`(row, col)` cells, start first). It is the classifier's view of `vinadv.grid.pairs.
PathPairs` (the pairs file, the store's records): the same path arrays, without the maps, which no classifier reads.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.columns import Columns
from vinadv.grid.dihedral import transform_cells
from vinadv.grid.pairs import PathPairs
from vinadv.grid.paths import PackedPaths


@dataclass(kw_only=True, eq=False)
class PathPairBatch(Columns):
    """`n` (original, adversarial) path pairs on `size x size` maps (`take`/`concat` from `Columns`).

    Attributes:
        path_o, path_a: `PackedPaths` of n paths each, cells inside the grid.
        goals: `(n, 2)` int64.
        size: N (cells per side).
    Construction checks all of it (InputError naming the bad field).
    """

    META = ("size",)

    path_o: PackedPaths
    path_a: PackedPaths
    goals: np.ndarray
    size: int

    def __post_init__(self) -> None:
        self.size = int(self.size)
        if self.size < 1:
            raise InputError(f"size must be positive, got {self.size}")
        for field, what in (("path_o", "original paths"), ("path_a", "adversarial paths")):
            paths = getattr(self, field)
            if not isinstance(paths, PackedPaths):
                raise InputError(f"{what}: expected PackedPaths, got {type(paths).__name__}")
            paths.check_grid(self.size, what)
        self.goals = np.ascontiguousarray(self.goals, dtype=np.int64).reshape(-1, 2)
        n = len(self.path_o)
        if len(self.path_a) != n or len(self.goals) != n:
            raise InputError(
                f"path pairs disagree on their number: {n} original paths, {len(self.path_a)} adversarial, "
                f"{len(self.goals)} goals"
            )

    @classmethod
    def empty(cls, size: int) -> PathPairBatch:
        return cls(path_o=PackedPaths.empty(), path_a=PackedPaths.empty(), goals=np.zeros((0, 2)), size=size)

    @classmethod
    def from_paths(cls, originals: Sequence, adversarials: Sequence, goals, size: int) -> PathPairBatch:
        """From two lists of `(L_i, 2)` cell arrays."""
        return cls(path_o=PackedPaths.pack(originals), path_a=PackedPaths.pack(adversarials), goals=goals, size=size)

    @classmethod
    def from_pairs(cls, pairs: PathPairs) -> PathPairBatch:
        """The path pairs of a `PathPairs` (a pairs file, stored records): its arrays, not copies."""
        return cls(path_o=pairs.path_o, path_a=pairs.path_a, goals=pairs.goals, size=pairs.size)

    def transformed(self, transform) -> PathPairBatch:
        """Every pair flipped/rotated by a dihedral transform (`vinadv.grid.dihedral`): one id `0..7` or one per
        pair."""
        transform = np.asarray(transform, dtype=np.int64)

        def move(paths: PackedPaths) -> PackedPaths:
            per_cell = transform if transform.ndim == 0 else np.repeat(transform, paths.lengths)
            return PackedPaths(transform_cells(paths.cells, self.size, per_cell), paths.offsets)

        return PathPairBatch(
            path_o=move(self.path_o),
            path_a=move(self.path_a),
            goals=transform_cells(self.goals, self.size, transform),
            size=self.size,
        )

    def fingerprint(self) -> str:
        """SHA-256 of the pairs' contents: tells whether two batches hold the same pairs."""
        digest = hashlib.sha256()
        for array in (self.path_o.cells, self.path_o.offsets, self.path_a.cells, self.path_a.offsets, self.goals):
            digest.update(np.ascontiguousarray(array).tobytes())
        digest.update(str(self.size).encode())
        return digest.hexdigest()
