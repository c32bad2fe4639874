"""Planned paths of a maps file, one per (map, start); file format "vinadv.paths/2" (written by `vinadv plan`).

Version 2 added the movement model (field `moves`); a "vinadv.paths/1" file is read as `octile`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from vinadv.grid.checks import check_paths
from vinadv.grid.columns import Columns
from vinadv.grid.moves import DEFAULT_MOVES, check_moves, read_moves
from vinadv.grid.paths import PackedPaths
from vinadv.npzfile import NpzReader, save_npz
from vinadv.planners.result import PlanResult
from vinadv.vocabulary import GOAL, TERMINATIONS

PATHS_FORMAT = "vinadv.paths/2"
#: the earlier format versions also read (a /1 file as `octile` paths)
OLDER_PATHS_FORMATS = ("vinadv.paths/1",)


@dataclass(kw_only=True, eq=False)
class PathSet(Columns):
    """Paths planned on n maps with S starts each: path `i * S + s` is from start `s` of map `i`.

    Attributes:
        paths: `PackedPaths` of n * S paths, `(row, col)` cells, start included.
        termination: `(n * S,)` str, 'goal' | 'collision' | 'loop' | 'step_limit'.
        n_starts: S. size: N (map side). corner_cutting: the move rule used. moves: the movement model of the maps
            (`vinadv.grid.moves`).
        model: a short description of the planner (e.g. the weights checksum), free text.
    """

    META = ("n_starts", "size", "corner_cutting", "model", "moves")

    paths: PackedPaths
    termination: np.ndarray
    n_starts: int = 1
    size: int = 28
    corner_cutting: bool = True
    model: str = field(default="")
    moves: str = DEFAULT_MOVES

    def __post_init__(self) -> None:
        self.moves = check_moves(self.moves, self.corner_cutting)

    @property
    def reached(self) -> np.ndarray:
        """`(n * S,)` bool, the path ends at the goal."""
        return np.asarray(self.termination) == TERMINATIONS[GOAL]

    @property
    def n_maps(self) -> int:
        return len(self) // max(self.n_starts, 1)

    def path(self, i: int, s: int = 0) -> np.ndarray:
        """The path from start `s` of map `i`, `(L, 2)` int16."""
        return self.paths[i * self.n_starts + s]

    @classmethod
    def from_result(
        cls,
        result: PlanResult,
        n_starts: int,
        size: int,
        corner_cutting: bool = True,
        model: str = "",
        moves: str = DEFAULT_MOVES,
    ) -> PathSet:
        return cls(
            paths=result.paths,
            termination=result.termination_names,
            n_starts=int(n_starts),
            size=int(size),
            corner_cutting=bool(corner_cutting),
            model=model,
            moves=moves,
        )

    def save(self, path: str | os.PathLike) -> None:
        save_npz(
            path,
            PATHS_FORMAT,
            {
                **self.paths.to_fields("path"),
                "reached": self.reached,
                "termination": np.asarray(self.termination, dtype=str),
                "n_starts": np.array(int(self.n_starts)),
                "size": np.array(int(self.size)),
                "corner_cutting": np.array(bool(self.corner_cutting)),
                "model": np.array(str(self.model)),
                "moves": np.array(self.moves),
            },
        )

    @classmethod
    def load(cls, path: str | os.PathLike) -> PathSet:
        """Read and validate a paths file; any problem raises InputError naming the file and field."""
        r = NpzReader(path, PATHS_FORMAT, OLDER_PATHS_FORMATS)
        size = int(r.scalar("size", "i"))
        if size < 3:
            raise r.fail("size", f"is {size}, expected >= 3")
        n_starts = int(r.scalar("n_starts", "i"))
        reached = r.array("reached", "b", 1)
        n = len(reached)
        if n_starts < 1 or n % n_starts:
            raise r.fail("n_starts", f"is {n_starts}, which does not divide the {n} paths")
        termination = r.array("termination", "U", 1, (n,))
        paths = PackedPaths.read(r, "path", n, size)
        bad = ~np.isin(termination, TERMINATIONS)
        if bad.any():
            raise r.fail("termination", f"has '{termination[bad][0]}', expected one of {', '.join(TERMINATIONS)}")
        if not np.array_equal(reached, termination == "goal"):
            raise r.fail("reached", "disagrees with 'termination' (reached means termination == 'goal')")
        corner_cutting = bool(r.scalar("corner_cutting", "b", default=True))
        moves = read_moves(r, corner_cutting)
        check_paths(r.path, "path_cells", paths, size, moves=moves)
        return cls(
            paths=paths,
            termination=termination.astype(str),
            n_starts=n_starts,
            size=size,
            corner_cutting=corner_cutting,
            model=str(r.scalar("model", "U", default="")),
            moves=moves,
        )
