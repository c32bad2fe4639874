"""Path features of a batch of path pairs: `invalid`, `UrP`, `UcP` (DESIGN.md, categories 1-3).

All functions are vectorised over packed paths (see `vinadv.grid.paths`); no Python loop per pair.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vinadv.classify.batch import take_segments

#: The five labels, in DESIGN.md order.
LABELS = ("invalid", "UrP", "UcP", "DP", "FP")
#: Labels that mean a successful attack.
SUCCESS_LABELS = ("UrP", "FP")


def reaches_goal(cells: np.ndarray, offsets: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """Whether each packed path ends on its goal: `(n,)` bool (an empty path never does)."""
    offsets = np.asarray(offsets, dtype=np.int64)
    goals = np.asarray(goals).reshape(-1, 2)
    nonempty = offsets[1:] > offsets[:-1]
    if len(cells) == 0:
        return np.zeros(len(offsets) - 1, dtype=bool)
    last = np.asarray(cells)[np.maximum(offsets[1:] - 1, 0)]
    return nonempty & np.all(last == goals, axis=1)


def same_paths(o_cells, o_offsets, a_cells, a_offsets) -> np.ndarray:
    """Whether the two paths of each pair are identical (same cells in the same order): `(n,)` bool."""
    o_offsets = np.asarray(o_offsets, dtype=np.int64)
    a_offsets = np.asarray(a_offsets, dtype=np.int64)
    o_len = np.diff(o_offsets)
    same = o_len == np.diff(a_offsets)
    candidates = np.flatnonzero(same)
    o_sub, sub_offsets = take_segments(np.asarray(o_cells), o_offsets, candidates)
    a_sub, _ = take_segments(np.asarray(a_cells), a_offsets, candidates)
    differs = np.any(o_sub != a_sub, axis=1).astype(np.float64)
    mismatches = np.bincount(
        np.repeat(np.arange(len(candidates)), np.diff(sub_offsets)), weights=differs, minlength=len(candidates)
    )
    same[candidates] = mismatches == 0
    return same


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


def path_features(o_cells, o_offsets, a_cells, a_offsets, goals) -> PathFeatures:
    """`invalid`, `UrP`, `UcP` of a batch of packed path pairs (DESIGN.md categories 1-3)."""
    reached_o = reaches_goal(o_cells, o_offsets, goals)
    reached_a = reaches_goal(a_cells, a_offsets, goals)
    invalid = ~reached_o
    unreached = reached_o & ~reached_a
    unchanged = reached_o & reached_a & same_paths(o_cells, o_offsets, a_cells, a_offsets)
    return PathFeatures(invalid, unreached, unchanged)
