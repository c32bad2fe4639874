"""A dataset of grid-world maps with starts, goals and expert (optimal) paths; file format "vinadv.maps/1"."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from vinadv.grid.checks import check_maps
from vinadv.npzfile import NpzReader, check_cells_in_grid, check_offsets, save_npz

MAPS_FORMAT = "vinadv.maps/1"


@dataclass
class MapSet:
    """n maps of N x N cells with S starts each.

    Attributes:
        obstacles: `(n, N, N)` bool, True = obstacle.
        goals: `(n, 2)` int64 `(row, col)`.
        starts: `(n, S, 2)` int64.
        expert_costs: `(n, S)` float64, optimal cost from each start (1 per orthogonal, sqrt 2 per diagonal move).
        expert_cells, expert_offsets: optimal paths packed flat, path `i * S + s` from start `s` of map `i`.
        corner_cutting: whether a diagonal move may pass between two obstacles on these maps.
        seed: the generator seed (-1 when unknown).
    """

    obstacles: np.ndarray
    goals: np.ndarray
    starts: np.ndarray
    expert_costs: np.ndarray
    expert_cells: np.ndarray
    expert_offsets: np.ndarray
    corner_cutting: bool = True
    seed: int = -1

    def __len__(self) -> int:
        return len(self.obstacles)

    @property
    def size(self) -> int:
        return int(self.obstacles.shape[1])

    @property
    def n_starts(self) -> int:
        return int(self.starts.shape[1])

    def expert_path(self, i: int, s: int = 0) -> np.ndarray:
        k = i * self.n_starts + s
        return self.expert_cells[self.expert_offsets[k] : self.expert_offsets[k + 1]]

    def save(self, path: str | os.PathLike) -> None:
        save_npz(
            path,
            MAPS_FORMAT,
            {
                "obstacles": self.obstacles.astype(bool),
                "goals": self.goals.astype(np.int64),
                "starts": self.starts.astype(np.int64),
                "expert_costs": self.expert_costs.astype(np.float64),
                "expert_cells": self.expert_cells.astype(np.int16),
                "expert_offsets": self.expert_offsets.astype(np.int64),
                "corner_cutting": np.array(bool(self.corner_cutting)),
                "seed": np.array(int(self.seed)),
            },
        )

    @classmethod
    def load(cls, path: str | os.PathLike) -> "MapSet":
        """Read and validate a maps file; any problem raises InputError naming the file and field."""
        r = NpzReader(path, MAPS_FORMAT)
        obstacles = r.array("obstacles", "b", 3)
        n, size = obstacles.shape[0], obstacles.shape[1]
        if obstacles.shape[2] != size or size < 3:
            raise r.fail("obstacles", f"has shape {obstacles.shape}, expected (n, N, N) with N >= 3")
        goals = r.array("goals", "i", 2, (n, 2)).astype(np.int64)
        starts = r.array("starts", "i", 3, (n, None, 2)).astype(np.int64)
        s = starts.shape[1]
        costs = r.array("expert_costs", "f", 2, (n, s)).astype(np.float64)
        cells = r.array("expert_cells", "i", 2, (None, 2)).astype(np.int16)
        offsets = r.array("expert_offsets", "i", 1).astype(np.int64)
        check_cells_in_grid(r, "goals", goals, size)
        check_cells_in_grid(r, "starts", starts, size)
        check_cells_in_grid(r, "expert_cells", cells, size)
        check_offsets(r, "expert_offsets", offsets, n * s, len(cells))
        idx = np.arange(n)
        if n and obstacles[idx, goals[:, 0], goals[:, 1]].any():
            raise r.fail("goals", "has a goal on an obstacle")
        if n and s and obstacles[idx[:, None], starts[..., 0], starts[..., 1]].any():
            raise r.fail("starts", "has a start on an obstacle")
        if np.any(~np.isfinite(costs)) or np.any(costs < 0):
            raise r.fail("expert_costs", "has a negative or non-finite cost")
        check_maps(r.path, obstacles, goals, starts, cells, offsets, bool(r.scalar("corner_cutting", "b", default=True)))
        return cls(
            obstacles=obstacles.astype(bool),
            goals=goals,
            starts=starts,
            expert_costs=costs,
            expert_cells=cells,
            expert_offsets=offsets,
            corner_cutting=bool(r.scalar("corner_cutting", "b", default=True)),
            seed=int(r.scalar("seed", "i", default=-1)),
        )
