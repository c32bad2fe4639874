"""Path features of a batch of path pairs: `invalid`, `UrP`, `UcP` (DESIGN.md, categories 1-3).

All functions are vectorised over packed paths (see `vinadv.grid.paths`); no Python loop per pair.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vinadv.grid.paths import PackedPaths


def reaches_goal(paths: PackedPaths, goals: np.ndarray) -> np.ndarray:
    """Whether each path ends on its goal (`goals` `(n, 2)`): `(n,)` bool (an empty path never does)."""
    goals = np.asarray(goals).reshape(-1, 2)
    nonempty = paths.lengths > 0
    if len(paths.cells) == 0:
        return np.zeros(len(paths), dtype=bool)
    last = paths.cells[np.maximum(paths.offsets[1:] - 1, 0)]
    return nonempty & np.all(last == goals, axis=1)


@dataclass(frozen=True)
class PathFeatures:
    """The path features of `n` pairs, each `(n,)` bool, exclusive in DESIGN order.

    `invalid`: the original path misses the goal. `unreached` (UrP): the original reaches it, the adversarial
    does not. `unchanged` (UcP): both reach it and the paths are identical. `rest`: none of these (DP or FP).
    """

    invalid: np.ndarray
    unreached: np.ndarray
    unchanged: np.ndarray

    @property
    def rest(self) -> np.ndarray:
        return ~(self.invalid | self.unreached | self.unchanged)


def path_features(path_o: PackedPaths, path_a: PackedPaths, goals: np.ndarray) -> PathFeatures:
    """`invalid`, `UrP`, `UcP` of n path pairs (original and adversarial paths, goals `(n, 2)`; DESIGN.md
    categories 1-3)."""
    reached_o = reaches_goal(path_o, goals)
    reached_a = reaches_goal(path_a, goals)
    invalid = ~reached_o
    unreached = reached_o & ~reached_a
    unchanged = reached_o & reached_a & path_o.same_as(path_a)
    return PathFeatures(invalid, unreached, unchanged)
