"""Planned paths of a maps file, one per (map, start); file format "vinadv.paths/1" (written by `vinadv plan`)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from vinadv.grid.checks import check_paths
from vinadv.npzfile import NpzReader, check_cells_in_grid, check_offsets, save_npz
from vinadv.planners.result import TERMINATIONS, PlanResult

PATHS_FORMAT = "vinadv.paths/1"


@dataclass
class PathSet:
    """Paths planned on n maps with S starts each: path `i * S + s` is from start `s` of map `i`.

    Attributes:
        path_cells: `(total, 2)` int16 `(row, col)`; path_offsets: `(n * S + 1,)` int64 (packed, start included).
        reached: `(n * S,)` bool, the path ends at the goal.
        termination: `(n * S,)` str, 'goal' | 'collision' | 'loop' | 'step_limit'.
        n_starts: S. size: N (map side). corner_cutting: the move rule used.
        model: a short description of the planner (e.g. the weights checksum), free text.
    """

    path_cells: np.ndarray
    path_offsets: np.ndarray
    reached: np.ndarray
    termination: np.ndarray
    n_starts: int = 1
    size: int = 28
    corner_cutting: bool = True
    model: str = field(default="")

    def __len__(self) -> int:
        return len(self.reached)

    @property
    def n_maps(self) -> int:
        return len(self) // max(self.n_starts, 1)

    def path(self, i: int, s: int = 0) -> np.ndarray:
        k = i * self.n_starts + s
        return self.path_cells[self.path_offsets[k] : self.path_offsets[k + 1]]

    @classmethod
    def from_result(cls, result: PlanResult, n_starts: int, size: int, corner_cutting: bool = True,
                    model: str = "") -> "PathSet":
        return cls(result.path_cells.astype(np.int16), result.path_offsets.astype(np.int64), result.reached.copy(),
                   result.termination_names, int(n_starts), int(size), bool(corner_cutting), model)

    def save(self, path: str | os.PathLike) -> None:
        save_npz(path, PATHS_FORMAT, {
            "path_cells": self.path_cells.astype(np.int16),
            "path_offsets": self.path_offsets.astype(np.int64),
            "reached": self.reached.astype(bool),
            "termination": np.asarray(self.termination, dtype=str),
            "n_starts": np.array(int(self.n_starts)),
            "size": np.array(int(self.size)),
            "corner_cutting": np.array(bool(self.corner_cutting)),
            "model": np.array(str(self.model)),
        })

    @classmethod
    def load(cls, path: str | os.PathLike) -> "PathSet":
        """Read and validate a paths file; any problem raises InputError naming the file and field."""
        r = NpzReader(path, PATHS_FORMAT)
        size = int(r.scalar("size", "i"))
        if size < 3:
            raise r.fail("size", f"is {size}, expected >= 3")
        n_starts = int(r.scalar("n_starts", "i"))
        reached = r.array("reached", "b", 1)
        n = len(reached)
        if n_starts < 1 or n % n_starts:
            raise r.fail("n_starts", f"is {n_starts}, which does not divide the {n} paths")
        termination = r.array("termination", "U", 1, (n,))
        cells = r.array("path_cells", "i", 2, (None, 2))
        offsets = r.array("path_offsets", "i", 1).astype(np.int64)
        check_cells_in_grid(r, "path_cells", cells, size)
        check_offsets(r, "path_offsets", offsets, n, len(cells))
        bad = ~np.isin(termination, TERMINATIONS)
        if bad.any():
            raise r.fail("termination", f"has '{termination[bad][0]}', expected one of {', '.join(TERMINATIONS)}")
        if not np.array_equal(reached, termination == "goal"):
            raise r.fail("reached", "disagrees with 'termination' (reached means termination == 'goal')")
        check_paths(r.path, "path_cells", cells, offsets, size)
        cells = cells.astype(np.int16)
        if len(cells) > 1:
            step = np.abs(np.diff(cells.astype(np.int64), axis=0)).max(axis=1)
            inside = np.ones(len(step), dtype=bool)
            inside[offsets[1:-1] - 1] = False  # the last cell of a path is not followed by a move
            if np.any(inside & (step != 1)):
                raise r.fail("path_cells", "has two consecutive cells of a path that are not neighbours")
        return cls(cells, offsets, reached.astype(bool), termination.astype(str), n_starts, size,
                   bool(r.scalar("corner_cutting", "b", default=True)), str(r.scalar("model", "U", default="")))
