"""Map pairs (original map + one added obstacle) with both planned paths; file format "vinadv.pairs/1"."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from vinadv.grid.checks import check_pairs
from vinadv.grid.paths import take_paths, unpack_paths
from vinadv.npzfile import NpzReader, check_cells_in_grid, check_offsets, save_npz

PAIRS_FORMAT = "vinadv.pairs/1"
TERMINATION_NAMES = ("goal", "collision", "loop", "step_limit")


@dataclass
class PairSet:
    """n (original, adversarial) map pairs of N x N cells.

    Attributes:
        obstacles_o, obstacles_a: `(n, N, N)` bool; `obstacles_a` is `obstacles_o` plus the cell `added`.
        starts, goals, added: `(n, 2)` int64 `(row, col)`.
        map_index: `(n,)` int64, the map of the source maps file each pair comes from.
        path_o_cells, path_o_offsets, path_a_cells, path_a_offsets: the planned paths on both maps, packed.
        term_o, term_a: `(n,)` str, why each path ended: goal | collision | loop | step_limit.
        strategy: the attack strategy's name; params: its parameters (JSON-able).
    """

    obstacles_o: np.ndarray
    obstacles_a: np.ndarray
    starts: np.ndarray
    goals: np.ndarray
    added: np.ndarray
    map_index: np.ndarray
    path_o_cells: np.ndarray
    path_o_offsets: np.ndarray
    path_a_cells: np.ndarray
    path_a_offsets: np.ndarray
    term_o: np.ndarray
    term_a: np.ndarray
    strategy: str = "unknown"
    params: dict = field(default_factory=dict)
    corner_cutting: bool = True

    def __len__(self) -> int:
        return len(self.obstacles_o)

    @property
    def size(self) -> int:
        return int(self.obstacles_o.shape[1])

    @property
    def reached_o(self) -> np.ndarray:
        return np.asarray(self.term_o) == "goal"

    @property
    def reached_a(self) -> np.ndarray:
        return np.asarray(self.term_a) == "goal"

    def paths_o(self) -> list[np.ndarray]:
        return unpack_paths(self.path_o_cells, self.path_o_offsets)

    def paths_a(self) -> list[np.ndarray]:
        return unpack_paths(self.path_a_cells, self.path_a_offsets)

    def subset(self, indices: np.ndarray) -> "PairSet":
        """The pairs at `indices` (an int array or a bool mask), in that order."""
        idx = np.arange(len(self))[indices]
        po_cells, po_off = take_paths(self.path_o_cells, self.path_o_offsets, idx)
        pa_cells, pa_off = take_paths(self.path_a_cells, self.path_a_offsets, idx)
        return PairSet(
            obstacles_o=self.obstacles_o[idx], obstacles_a=self.obstacles_a[idx], starts=self.starts[idx],
            goals=self.goals[idx], added=self.added[idx], map_index=self.map_index[idx],
            path_o_cells=po_cells, path_o_offsets=po_off, path_a_cells=pa_cells, path_a_offsets=pa_off,
            term_o=np.asarray(self.term_o)[idx], term_a=np.asarray(self.term_a)[idx],
            strategy=self.strategy, params=dict(self.params), corner_cutting=self.corner_cutting,
        )

    def save(self, path: str | os.PathLike) -> None:
        save_npz(
            path,
            PAIRS_FORMAT,
            {
                "obstacles_o": self.obstacles_o.astype(bool),
                "obstacles_a": self.obstacles_a.astype(bool),
                "starts": self.starts.astype(np.int64),
                "goals": self.goals.astype(np.int64),
                "added": self.added.astype(np.int64),
                "map_index": self.map_index.astype(np.int64),
                "path_o_cells": self.path_o_cells.astype(np.int16),
                "path_o_offsets": self.path_o_offsets.astype(np.int64),
                "path_a_cells": self.path_a_cells.astype(np.int16),
                "path_a_offsets": self.path_a_offsets.astype(np.int64),
                "term_o": np.asarray(self.term_o, dtype=str),
                "term_a": np.asarray(self.term_a, dtype=str),
                "strategy": np.array(self.strategy),
                "params": np.array(json.dumps(self.params, sort_keys=True)),
                "corner_cutting": np.array(bool(self.corner_cutting)),
            },
        )

    @classmethod
    def load(cls, path: str | os.PathLike) -> "PairSet":
        """Read and validate a pairs file; any problem raises InputError naming the file and field."""
        r = NpzReader(path, PAIRS_FORMAT)
        obs_o = r.array("obstacles_o", "b", 3)
        n, size = obs_o.shape[:2]
        if obs_o.shape[2] != size:
            raise r.fail("obstacles_o", f"has shape {obs_o.shape}, expected (n, N, N)")
        obs_a = r.array("obstacles_a", "b", 3, obs_o.shape)
        starts = r.array("starts", "i", 2, (n, 2)).astype(np.int64)
        goals = r.array("goals", "i", 2, (n, 2)).astype(np.int64)
        added = r.array("added", "i", 2, (n, 2)).astype(np.int64)
        map_index = r.array("map_index", "i", 1, (n,)).astype(np.int64)
        paths = {}
        for side in ("o", "a"):
            cells = r.array(f"path_{side}_cells", "i", 2, (None, 2)).astype(np.int16)
            offsets = r.array(f"path_{side}_offsets", "i", 1).astype(np.int64)
            check_cells_in_grid(r, f"path_{side}_cells", cells, size)
            check_offsets(r, f"path_{side}_offsets", offsets, n, len(cells))
            paths[side] = (cells, offsets)
        terms = {}
        for side in ("o", "a"):
            term = r.array(f"term_{side}", "U", 1, (n,))
            bad = ~np.isin(term, TERMINATION_NAMES)
            if bad.any():
                raise r.fail(f"term_{side}", f"has value '{term[bad][0]}', expected one of {'|'.join(TERMINATION_NAMES)}")
            terms[side] = term
        for name, cells in (("starts", starts), ("goals", goals), ("added", added)):
            check_cells_in_grid(r, name, cells, size)
        idx = np.arange(n)
        diff = obs_a != obs_o
        if n and (np.any(diff.sum(axis=(1, 2)) != 1) or not np.all(diff[idx, added[:, 0], added[:, 1]])):
            raise r.fail("obstacles_a", "must differ from obstacles_o in exactly the cell 'added', made an obstacle")
        if n and obs_o[idx, added[:, 0], added[:, 1]].any():
            raise r.fail("added", "has a cell that is already an obstacle on the original map")
        check_pairs(r.path, obs_o, obs_a, starts, goals, added, paths, terms, r.scalar("corner_cutting", "b", True))
        params = r.json("params")
        if not isinstance(params, dict):
            raise r.fail("params", "must be a JSON object")
        return cls(
            obstacles_o=obs_o.astype(bool), obstacles_a=obs_a.astype(bool), starts=starts, goals=goals,
            added=added, map_index=map_index,
            path_o_cells=paths["o"][0], path_o_offsets=paths["o"][1],
            path_a_cells=paths["a"][0], path_a_offsets=paths["a"][1],
            term_o=terms["o"], term_a=terms["a"], strategy=str(r.scalar("strategy", "U")), params=params,
            corner_cutting=bool(r.scalar("corner_cutting", "b", default=True)),
        )

