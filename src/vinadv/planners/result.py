"""What a planner returns (`PlanResult`), the termination codes, and the input checks planners share."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.columns import Columns
from vinadv.grid.moves import DEFAULT_MOVES
from vinadv.grid.paths import PackedPaths
from vinadv.grid.shortest_paths import shortest_distances
from vinadv.vocabulary import COLLISION, GOAL, LOOP, STEP_LIMIT, TERMINATIONS, termination_names

__all__ = ["COLLISION", "GOAL", "LOOP", "STEP_LIMIT", "TERMINATIONS", "PlanResult", "check_plan_inputs", "step_limits"]


@dataclass(kw_only=True, eq=False)
class PlanResult(Columns):
    """B planned paths (`take`/`concat` from `Columns`).

    Attributes:
        paths: `PackedPaths` of B paths, the visited `(row, col)` cells, start included.
        termination: `(B,)` int8, why each rollout ended: indices into `vocabulary.TERMINATIONS`.
    """

    paths: PackedPaths
    termination: np.ndarray

    def __post_init__(self) -> None:
        self.termination = np.asarray(self.termination, dtype=np.int8)
        if not isinstance(self.paths, PackedPaths) or self.termination.shape != (len(self.paths),):
            raise InputError(
                f"PlanResult: expected PackedPaths and one termination per path, got {self.paths!r} "
                f"and termination of shape {self.termination.shape}"
            )

    @classmethod
    def empty(cls) -> PlanResult:
        return cls(paths=PackedPaths.empty(), termination=np.zeros(0, np.int8))

    @classmethod
    def from_buffers(cls, cells: np.ndarray, lengths: np.ndarray, termination: np.ndarray) -> PlanResult:
        """From rollout buffers, the planners' output: `cells (R, M, 2)` whose first `lengths[r]` rows are rollout
        r's path, and the termination codes `termination (R,)`."""
        offsets = np.zeros(len(lengths) + 1, dtype=np.int64)
        np.cumsum(lengths, out=offsets[1:])
        longest = int(lengths.max(initial=0))
        packed = cells[:, :longest][np.arange(longest)[None, :] < lengths[:, None]]
        return cls(paths=PackedPaths(packed, offsets), termination=termination)

    @classmethod
    def from_paths(cls, paths: list[np.ndarray], termination: np.ndarray) -> PlanResult:
        """From a list of `(L_i, 2)` paths and their termination codes."""
        return cls(paths=PackedPaths.pack(paths), termination=termination)

    @property
    def reached(self) -> np.ndarray:
        """`(B,)` bool, the path ends at the goal."""
        return self.termination == GOAL

    @property
    def termination_names(self) -> np.ndarray:
        """`(B,)` str: 'goal', 'collision', 'loop' or 'step_limit'."""
        return termination_names(self.termination)


def check_plan_inputs(obstacles, starts, goals) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Validate and normalise planner inputs: `(B, N, N)` bool, `(B, 2)` int64, `(B, 2)` int64, cells in the grid.
    `starts` None (what reads the goals alone: a value map) is returned as None."""
    obstacles = np.ascontiguousarray(obstacles, dtype=bool)
    goals = np.ascontiguousarray(goals, dtype=np.int64)
    if obstacles.ndim != 3 or obstacles.shape[1] != obstacles.shape[2]:
        raise InputError(f"obstacles has shape {obstacles.shape}, expected (B, N, N)")
    b, n = obstacles.shape[0], obstacles.shape[1]
    checked = [("goals", goals)]
    if starts is not None:
        starts = np.ascontiguousarray(starts, dtype=np.int64)
        checked.insert(0, ("starts", starts))
    for name, arr in checked:
        if arr.shape != (b, 2):
            raise InputError(f"{name} has shape {arr.shape}, expected ({b}, 2)")
        if arr.size and (arr.min() < 0 or arr.max() >= n):
            raise InputError(f"{name} has a cell outside the {n}x{n} grid")
    return obstacles, starts, goals


def step_limits(
    obstacles: np.ndarray, starts: np.ndarray, goals: np.ndarray, corner_cutting: bool, moves: str = DEFAULT_MOVES
) -> np.ndarray:
    """`(B,)` int64: 2 * L, L the optimal move count from the start under the movement model `moves` (N * N where
    the goal is unreachable)."""
    if len(obstacles) == 0:
        return np.zeros(0, dtype=np.int64)
    _, counts = shortest_distances(obstacles, goals, corner_cutting, moves)
    n = obstacles.shape[1]
    lengths = counts[np.arange(len(obstacles)), starts[:, 0], starts[:, 1]].astype(np.int64)
    return 2 * np.where(lengths < 0, n * n, lengths)
