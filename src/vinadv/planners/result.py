"""What a planner returns (`PlanResult`), the termination codes, and the input checks planners share."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.paths import pack_paths, unpack_paths
from vinadv.grid.shortest_paths import shortest_distances

#: why a rollout ended; `PlanResult.termination` holds indices into this tuple.
TERMINATIONS = ("goal", "collision", "loop", "step_limit")
GOAL, COLLISION, LOOP, STEP_LIMIT = 0, 1, 2, 3


@dataclass
class PlanResult:
    """B planned paths.

    Attributes:
        path_cells: `(total, 2)` int16 `(row, col)`; path `i` is `path_cells[path_offsets[i]:path_offsets[i + 1]]`,
            the visited cells, start included.
        path_offsets: `(B + 1,)` int64.
        reached: `(B,)` bool, the path ends at the goal.
        termination: `(B,)` int8, indices into `TERMINATIONS`.
    """

    path_cells: np.ndarray
    path_offsets: np.ndarray
    reached: np.ndarray
    termination: np.ndarray

    def __len__(self) -> int:
        return len(self.reached)

    @property
    def termination_names(self) -> np.ndarray:
        """`(B,)` str: 'goal', 'collision', 'loop' or 'step_limit'."""
        return np.array(TERMINATIONS)[self.termination]

    @property
    def lengths(self) -> np.ndarray:
        """`(B,)` int64 number of cells of each path (moves + 1)."""
        return np.diff(self.path_offsets)

    def path(self, i: int) -> np.ndarray:
        return self.path_cells[self.path_offsets[i] : self.path_offsets[i + 1]]

    def paths(self) -> list[np.ndarray]:
        return unpack_paths(self.path_cells, self.path_offsets)

    @classmethod
    def from_paths(cls, paths: list[np.ndarray], termination: np.ndarray) -> "PlanResult":
        cells, offsets = pack_paths(paths)
        termination = np.asarray(termination, dtype=np.int8)
        return cls(cells, offsets, termination == GOAL, termination)

    @classmethod
    def concatenate(cls, parts: list["PlanResult"]) -> "PlanResult":
        if not parts:
            return cls(np.zeros((0, 2), np.int16), np.zeros(1, np.int64), np.zeros(0, bool), np.zeros(0, np.int8))
        offsets = [parts[0].path_offsets]
        for p in parts[1:]:
            offsets.append(p.path_offsets[1:] + offsets[-1][-1])
        return cls(
            np.concatenate([p.path_cells for p in parts]),
            np.concatenate(offsets),
            np.concatenate([p.reached for p in parts]),
            np.concatenate([p.termination for p in parts]),
        )


def check_plan_inputs(obstacles, starts, goals) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate and normalise planner inputs: `(B, N, N)` bool, `(B, 2)` int64, `(B, 2)` int64, cells in the grid."""
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    starts = np.ascontiguousarray(starts, dtype=np.int64)
    goals = np.ascontiguousarray(goals, dtype=np.int64)
    if obstacles.ndim != 3 or obstacles.shape[1] != obstacles.shape[2]:
        raise InputError(f"obstacles has shape {obstacles.shape}, expected (B, N, N)")
    b, n = obstacles.shape[0], obstacles.shape[1]
    for name, arr in (("starts", starts), ("goals", goals)):
        if arr.shape != (b, 2):
            raise InputError(f"{name} has shape {arr.shape}, expected ({b}, 2)")
        if arr.size and (arr.min() < 0 or arr.max() >= n):
            raise InputError(f"{name} has a cell outside the {n}x{n} grid")
    return obstacles, starts, goals


def step_limits(obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool) -> np.ndarray:
    """`(B,)` int64: 2 * L, L the optimal move count from the start (N * N where the goal is unreachable)."""
    if len(obstacles) == 0:
        return np.zeros(0, dtype=np.int64)
    _, moves = shortest_distances(obstacles, goals, corner_cutting)
    n = obstacles.shape[1]
    lengths = moves[np.arange(len(obstacles)), starts[:, 0], starts[:, 1]].astype(np.int64)
    return 2 * np.where(lengths < 0, n * n, lengths)
