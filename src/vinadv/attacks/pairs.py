"""Map pairs (original map + K added obstacles, K >= 1, or minus K freed ones) with both planned paths; file format
"vinadv.pairs/4".

The field `added` is `(n, 2)` in a file of one-obstacle pairs (the one-obstacle layout of every format version) and
`(n, K, 2)` in a file of K > 1 obstacles per pair. Version 2 holds the movement model (field `moves`); a
"vinadv.pairs/1" file reads as `octile`. Version 3 holds each pair's edit (field `edit`, `(n,)` str: `add` or
`remove`, `vocabulary.EDITS`); a /1 or /2 file reads as `add`. Version 4 holds, for a planner that reports its
expansions, both searches' expanded cells packed as the paths are (`expanded_o_cells`/`expanded_o_offsets`,
`expanded_a_*`) and the exact A*'s expansion counts on both maps (`astar_expansions_o`, `astar_expansions_a`, `(n,)`
int64), all four or none; a file without them (every older one) reads with none (DESIGN.md "Search effort").
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from vinadv.grid.checks import check_pairs
from vinadv.grid.moves import DEFAULT_MOVES, check_moves, read_moves
from vinadv.grid.pairs import EXPANSION_FIELDS, PathPairs, int_column
from vinadv.grid.paths import PackedPaths
from vinadv.npzfile import NpzReader, check_cells_in_grid, save_npz
from vinadv.planners.spec import is_planner_spec
from vinadv.vocabulary import ADD, EDITS, REMOVE, TERMINATIONS

PAIRS_FORMAT = "vinadv.pairs/4"
#: the earlier format versions also read (`/1` as `octile` pairs; `/1`, `/2` as edit `add`; none with expansions)
OLDER_PAIRS_FORMATS = ("vinadv.pairs/1", "vinadv.pairs/2", "vinadv.pairs/3")


@dataclass(kw_only=True, eq=False)
class PairSet(PathPairs):
    """n (original, adversarial) map pairs of N x N cells: `PathPairs` (maps, starts, goals, added cells, both
    paths and terminations) plus where they come from.

    Attributes, besides those of `PathPairs`:
        map_index: `(n,)` int64, the map of the source maps file each pair comes from.
        strategy: the attack strategy's name; params: its parameters (JSON-able); corner_cutting: the move rule;
        moves: the movement model of the maps (`vinadv.grid.moves`), which harm follows.
    """

    META = ("strategy", "params", "corner_cutting", "moves")

    map_index: np.ndarray
    strategy: str = "unknown"
    params: dict = field(default_factory=dict)
    corner_cutting: bool = True
    moves: str = DEFAULT_MOVES

    def __post_init__(self) -> None:
        super().__post_init__()
        self.moves = check_moves(self.moves, self.corner_cutting)
        self.map_index = int_column(self.map_index, "PairSet.map_index", (len(self.starts),))

    @classmethod
    def empty(cls, size: int | None = None, **settings) -> PairSet:
        return super().empty(size, map_index=np.zeros(0, np.int64), **settings)

    def save(self, path: str | os.PathLike) -> None:
        save_npz(
            path,
            PAIRS_FORMAT,
            {
                "obstacles_o": self.obstacles_o,
                "obstacles_a": self.obstacles_a,
                "starts": self.starts,
                "goals": self.goals,
                "added": self.added[:, 0] if self.n_added == 1 else self.added,  # one obstacle: (n, 2) as ever
                "map_index": self.map_index,
                **self.path_o.to_fields("path_o"),
                **self.path_a.to_fields("path_a"),
                "term_o": np.asarray(self.term_o, dtype=str),
                "term_a": np.asarray(self.term_a, dtype=str),
                "edit": np.asarray(self.edit, dtype=str),
                "strategy": np.array(self.strategy),
                "params": np.array(json.dumps(self.params, sort_keys=True)),
                "corner_cutting": np.array(bool(self.corner_cutting)),
                "moves": np.array(self.moves),
                **self._effort_fields(),
            },
        )

    def _effort_fields(self) -> dict[str, np.ndarray]:
        """The file fields of the search effort: all four where the pairs carry them, else none."""
        if any(getattr(self, name) is None for name in EXPANSION_FIELDS):
            return {}
        return {
            **self.expanded_o.to_fields("expanded_o"),
            **self.expanded_a.to_fields("expanded_a"),
            "astar_expansions_o": self.astar_expansions_o,
            "astar_expansions_a": self.astar_expansions_a,
        }

    @classmethod
    def load(cls, path: str | os.PathLike) -> PairSet:
        """Read and validate a pairs file; any problem raises InputError naming the file and field."""
        r = NpzReader(path, PAIRS_FORMAT, OLDER_PAIRS_FORMATS)
        obs_o = r.array("obstacles_o", "b", 3)
        n, size = obs_o.shape[:2]
        if obs_o.shape[2] != size:
            raise r.fail("obstacles_o", f"has shape {obs_o.shape}, expected (n, N, N)")
        obs_a = r.array("obstacles_a", "b", 3, obs_o.shape)
        starts = r.array("starts", "i", 2, (n, 2)).astype(np.int64)
        goals = r.array("goals", "i", 2, (n, 2)).astype(np.int64)
        added = _read_added(r, n)
        map_index = r.array("map_index", "i", 1, (n,)).astype(np.int64)
        paths = {side: PackedPaths.read(r, f"path_{side}", n, size) for side in ("o", "a")}
        terms = {}
        for side in ("o", "a"):
            term = r.array(f"term_{side}", "U", 1, (n,))
            bad = ~np.isin(term, TERMINATIONS)
            if bad.any():
                raise r.fail(f"term_{side}", f"has value '{term[bad][0]}', expected one of {'|'.join(TERMINATIONS)}")
            terms[side] = term
        for name, cells in (("starts", starts), ("goals", goals), ("added", added)):
            check_cells_in_grid(r, name, cells, size)
        corner_cutting = bool(r.scalar("corner_cutting", "b", default=True))
        moves = read_moves(r, corner_cutting)
        edit = _read_edit(r, n)
        check_pairs(
            r.path, obs_o, obs_a, starts, goals, added, paths, terms, corner_cutting, moves, removes=edit == REMOVE
        )
        params = r.json("params")
        if not isinstance(params, dict):
            raise r.fail("params", "must be a JSON object")
        if "planner" in params and not is_planner_spec(params["planner"]):  # vinadv < 0.2 wrote none
            raise r.fail("params", "has a 'planner' that is not a planner spec (name, size, config, weights_sha256)")
        return cls(
            obstacles_o=obs_o,
            obstacles_a=obs_a,
            starts=starts,
            goals=goals,
            added=added,
            map_index=map_index,
            path_o=paths["o"],
            path_a=paths["a"],
            term_o=terms["o"],
            term_a=terms["a"],
            edit=edit,
            strategy=str(r.scalar("strategy", "U")),
            params=params,
            corner_cutting=corner_cutting,
            moves=moves,
            **_read_effort(r, n, size),
        )


def _read_effort(r: NpzReader, n: int, size: int) -> dict:
    """The file's search-effort fields (`PairSet._effort_fields`): all four, or none (a /3 file or older, or pairs of
    a planner without expansions)."""
    names = ("expanded_o_offsets", "expanded_a_offsets", "astar_expansions_o", "astar_expansions_a")
    present = [r.has(name) for name in names]
    if not any(present):
        return {}
    if not all(present):
        missing = names[present.index(False)]
        raise r.fail(missing, "is missing: the search-effort fields go together (expanded_o/a, astar_expansions_o/a)")
    out = {f"expanded_{side}": PackedPaths.read(r, f"expanded_{side}", n, size) for side in ("o", "a")}
    for side in ("o", "a"):
        name = f"astar_expansions_{side}"
        counts = r.array(name, "i", 1, (n,)).astype(np.int64)
        if (counts < 1).any():
            raise r.fail(name, f"has value {int(counts[counts < 1][0])}, expected counts >= 1 (the start is expanded)")
        out[name] = counts
    return out


def _read_edit(r: NpzReader, n: int) -> np.ndarray:
    """The file's `edit` `(n,)` (a /1 or /2 file has none: every pair `add`)."""
    if not r.has("edit"):
        return np.full(n, ADD, dtype="<U6")
    edit = r.array("edit", "U", 1, (n,))
    bad = ~np.isin(edit, EDITS)
    if bad.any():
        raise r.fail("edit", f"has value '{edit[bad][0]}', expected one of {'|'.join(EDITS)}")
    return edit.astype("<U6")


def _read_added(r: NpzReader, n: int) -> np.ndarray:
    """The file's `added`: `(n, 2)` (one obstacle per pair) or `(n, K, 2)`, as int64 `(n, K, 2)`."""
    if r.ndim("added") == 3:
        added = r.array("added", "i", 3, (n, None, 2))
        if added.shape[1] < 1:
            raise r.fail("added", f"has shape {added.shape}, expected at least one cell per pair")
        return added.astype(np.int64)
    return r.array("added", "i", 2, (n, 2)).astype(np.int64)[:, None, :]
