"""A dataset of grid-world maps with starts, goals and expert (optimal) paths; file format "vinadv.maps/3".

Version 2 holds the movement model (field `moves`); a "vinadv.maps/1" file, which has none, reads as `octile`.
Version 3 adds two optional parts: `frozen` `(n, N, N)` bool, the cells no attack may add an obstacle to or free
(an importer's padding of a map that was not square), and each map's provenance, `source` `(n,)` (the file's name,
"" unknown), `source_sha256` `(n,)` (its hex digest, "" unknown) and `origin` `(n, 2)` (the row and column of the
map's cell (0, 0) in the source: a crop's window). A /1 or /2 file reads with neither.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from vinadv.errors import InputError
from vinadv.grid.checks import check_maps
from vinadv.grid.moves import DEFAULT_MOVES, check_moves, read_moves
from vinadv.grid.paths import PackedPaths
from vinadv.npzfile import NpzReader, check_cells_in_grid, save_npz

MAPS_FORMAT = "vinadv.maps/3"
#: the earlier format versions also read (a /1 file as `octile` maps; /1 and /2 without frozen cells or provenance)
OLDER_MAPS_FORMATS = ("vinadv.maps/1", "vinadv.maps/2")
#: the provenance fields, written and read together
PROVENANCE = ("source", "source_sha256", "origin")
_HEX = frozenset("0123456789abcdef")


@dataclass(kw_only=True, eq=False)
class MapSet:
    """n maps of N x N cells with S starts each.

    Attributes:
        obstacles: `(n, N, N)` bool, True = obstacle.
        goals: `(n, 2)` int64 `(row, col)`.
        starts: `(n, S, 2)` int64.
        expert_costs: `(n, S)` float64, optimal cost from each start under `moves`.
        expert: `PackedPaths` of n * S optimal paths, path `i * S + s` from start `s` of map `i` (file fields
            `expert_cells`, `expert_offsets`).
        corner_cutting: whether a diagonal move may pass between two obstacles on these maps.
        moves: the movement model (`vinadv.grid.moves`: "octile", "moore" or "news"): the moves and their costs.
        seed: the generator seed (-1 when unknown).
        start_counts: `(n,)` int64 or None. Maps imported from other codebases may have fewer starts than others:
            map `i` then has `start_counts[i]` real starts and its slots `s >= start_counts[i]` are explicit padding
            (start = the goal, cost 0, a one-cell path), to be skipped through `start_mask`. None: all S are real.
        frozen: `(n, N, N)` bool or None: the cells no attack may add an obstacle to or free (an importer's padding
            of a map that was not square; `vinadv.attacks.validity`). None: no cell is frozen.
        source, source_sha256: `(n,)` str or None: each map's source file (its name) and the file's sha256 (hex),
            "" where unknown. origin: `(n, 2)` int64 or None: the source cell (row, col) of each map's cell (0, 0)
            (a crop's window; (0, 0) for a whole map). The three are given together or not at all.
    """

    obstacles: np.ndarray
    goals: np.ndarray
    starts: np.ndarray
    expert_costs: np.ndarray
    expert: PackedPaths
    corner_cutting: bool = True
    seed: int = -1
    start_counts: np.ndarray | None = None
    moves: str = DEFAULT_MOVES
    frozen: np.ndarray | None = None
    source: np.ndarray | None = None
    source_sha256: np.ndarray | None = None
    origin: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.moves = check_moves(self.moves, self.corner_cutting)
        if self.frozen is not None:
            self.frozen = np.asarray(self.frozen, dtype=bool)
            if self.frozen.shape != self.obstacles.shape:
                raise InputError(f"frozen has shape {self.frozen.shape}, the obstacles {self.obstacles.shape}")
        given = [getattr(self, f) is not None for f in PROVENANCE]
        if any(given) and not all(given):
            raise InputError("source, source_sha256 and origin go together (a map's provenance)", *PROVENANCE)
        if all(given):
            n = len(self.obstacles)
            self.source = np.asarray(self.source, dtype=str).reshape(n)
            self.source_sha256 = np.asarray(self.source_sha256, dtype=str).reshape(n)
            self.origin = np.asarray(self.origin, dtype=np.int64).reshape(n, 2)

    @property
    def has_provenance(self) -> bool:
        return self.source is not None

    def frozen_or_none(self) -> np.ndarray:
        """`(n, N, N)` bool: the frozen cells (all False where the set has no mask)."""
        return np.zeros(self.obstacles.shape, dtype=bool) if self.frozen is None else self.frozen

    @property
    def start_mask(self) -> np.ndarray:
        """`(n, S)` bool: which start slots are real starts (all True unless `start_counts` pads some)."""
        if self.start_counts is None:
            return np.ones(self.starts.shape[:2], dtype=bool)
        return np.arange(self.n_starts)[None, :] < np.asarray(self.start_counts)[:, None]

    def __len__(self) -> int:
        return len(self.obstacles)

    @property
    def size(self) -> int:
        return int(self.obstacles.shape[1])

    @property
    def n_starts(self) -> int:
        return int(self.starts.shape[1])

    def take(self, index) -> MapSet:
        """The maps at `index` (int array, bool mask or slice), in that order, with all their starts."""
        idx = np.arange(len(self))[index]
        rows = (idx[:, None] * self.n_starts + np.arange(self.n_starts)[None, :]).reshape(-1)
        return MapSet(
            obstacles=self.obstacles[idx],
            goals=self.goals[idx],
            starts=self.starts[idx],
            expert_costs=self.expert_costs[idx],
            expert=self.expert.take(rows),
            corner_cutting=self.corner_cutting,
            seed=self.seed,
            start_counts=None if self.start_counts is None else np.asarray(self.start_counts)[idx],
            moves=self.moves,
            frozen=None if self.frozen is None else self.frozen[idx],
            **({f: getattr(self, f)[idx] for f in PROVENANCE} if self.has_provenance else {}),
        )

    @classmethod
    def concat(cls, parts: list[MapSet], names: list[str] | None = None) -> MapSet:
        """The maps of `parts`, in order: one set of the same size, starts per map, corner cutting and movement
        model (a part that differs raises InputError naming it, `names[i]` or its index, and the field). The seed is
        the parts' common one, else -1 (unknown: the maps came from several). Frozen cells and provenance are kept:
        where some parts have them, the others' maps have no frozen cell and an unknown source ("", origin (0, 0))."""
        if not parts:
            raise InputError("no maps sets to concatenate")
        names = names or [f"part {i}" for i in range(len(parts))]
        first = parts[0]
        for name, part in zip(names[1:], parts[1:], strict=True):
            for field, want, got in (
                ("size", first.size, part.size),
                ("starts per map", first.n_starts, part.n_starts),
                ("corner_cutting", first.corner_cutting, part.corner_cutting),
                ("moves", first.moves, part.moves),
            ):
                if want != got:
                    raise InputError(
                        f"{name}: {field} is {got!r}, {names[0]}'s is {want!r}: only like sets concatenate"
                    )
        padded = any(p.start_counts is not None for p in parts)
        frozen = any(p.frozen is not None for p in parts)
        seeds = {int(p.seed) for p in parts}
        return cls(
            obstacles=np.concatenate([p.obstacles for p in parts]),
            goals=np.concatenate([p.goals for p in parts]),
            starts=np.concatenate([p.starts for p in parts]),
            expert_costs=np.concatenate([p.expert_costs for p in parts]),
            expert=PackedPaths.concat([p.expert for p in parts]),
            corner_cutting=first.corner_cutting,
            seed=seeds.pop() if len(seeds) == 1 else -1,
            start_counts=np.concatenate([p.start_mask.sum(axis=1) for p in parts]).astype(np.int64) if padded else None,
            moves=first.moves,
            frozen=np.concatenate([p.frozen_or_none() for p in parts]) if frozen else None,
            **(_joined_provenance(parts) if any(p.has_provenance for p in parts) else {}),
        )

    @classmethod
    def from_ascii(
        cls, text: str, *, pad_to: int | None = None, corner_cutting: bool = True, moves: str = DEFAULT_MOVES
    ) -> MapSet:
        """One map drawn in ASCII: `#` or `@` an obstacle, `.` free, `S` a start, `G` the goal, one line a row;
        padded with obstacles into a square of side `pad_to` at least (`vinadv.grid.drawn`)."""
        from vinadv.grid.drawn import from_ascii  # noqa: PLC0415 (drawn builds on this module)

        return from_ascii(text, pad_to=pad_to, corner_cutting=corner_cutting, moves=moves)

    def expert_path(self, i: int, s: int = 0) -> np.ndarray:
        """The optimal path from start `s` of map `i`, `(L, 2)` int16."""
        return self.expert[i * self.n_starts + s]

    def save(self, path: str | os.PathLike) -> None:
        """Write the maps to `path` (format `MAPS_FORMAT`, atomically). A maps file holds at least one map: an empty
        set is refused (InputError naming `path`), so no command meets a file it has nothing to do with."""
        if len(self) == 0:
            raise InputError(f"{path}: no maps to write (a maps file holds at least one map)")
        save_npz(
            path,
            MAPS_FORMAT,
            {
                "obstacles": self.obstacles.astype(bool),
                "goals": self.goals.astype(np.int64),
                "starts": self.starts.astype(np.int64),
                "expert_costs": self.expert_costs.astype(np.float64),
                **self.expert.to_fields("expert"),
                "corner_cutting": np.array(bool(self.corner_cutting)),
                "moves": np.array(self.moves),
                "seed": np.array(int(self.seed)),
                **({} if self.start_counts is None else {"start_counts": np.asarray(self.start_counts, np.int64)}),
                **({} if self.frozen is None else {"frozen": self.frozen.astype(bool)}),
                **(
                    {
                        "source": np.asarray(self.source, dtype=str),
                        "source_sha256": np.asarray(self.source_sha256, dtype=str),
                        "origin": np.asarray(self.origin, dtype=np.int64),
                    }
                    if self.has_provenance
                    else {}
                ),
            },
        )

    @classmethod
    def load(cls, path: str | os.PathLike) -> MapSet:
        """Read and validate a maps file; any problem (no maps included) raises InputError naming the file and
        field."""
        r = NpzReader(path, MAPS_FORMAT, OLDER_MAPS_FORMATS)
        obstacles = r.array("obstacles", "b", 3)
        n, size = obstacles.shape[0], obstacles.shape[1]
        if obstacles.shape[2] != size or size < 3:
            raise r.fail("obstacles", f"has shape {obstacles.shape}, expected (n, N, N) with N >= 3")
        if n == 0:  # `save` refuses an empty set: such a file was not written by it
            raise r.fail("obstacles", "holds no maps")
        goals = r.array("goals", "i", 2, (n, 2)).astype(np.int64)
        starts = r.array("starts", "i", 3, (n, None, 2)).astype(np.int64)
        s = starts.shape[1]
        costs = r.array("expert_costs", "f", 2, (n, s)).astype(np.float64)
        check_cells_in_grid(r, "goals", goals, size)
        check_cells_in_grid(r, "starts", starts, size)
        expert = PackedPaths.read(r, "expert", n * s, size)
        if np.any(~np.isfinite(costs)) or np.any(costs < 0):
            raise r.fail("expert_costs", "has a negative or non-finite cost")
        counts = r.array("start_counts", "i", 1, (n,)).astype(np.int64) if r.has("start_counts") else None
        if counts is not None and n and (counts.min() < 1 or counts.max() > s):
            raise r.fail("start_counts", f"has a count outside 1..{s} (the starts per map)")
        corner_cutting = bool(r.scalar("corner_cutting", "b", default=True))
        moves = read_moves(r, corner_cutting)
        check_maps(r.path, obstacles, goals, starts, expert, corner_cutting, counts, moves)
        frozen = r.array("frozen", "b", 3, obstacles.shape) if r.has("frozen") else None
        return cls(
            obstacles=obstacles.astype(bool),
            goals=goals,
            starts=starts,
            expert_costs=costs,
            expert=expert,
            corner_cutting=corner_cutting,
            seed=int(r.scalar("seed", "i", default=-1)),
            start_counts=counts,
            moves=moves,
            frozen=frozen,
            **_read_provenance(r, n),
        )


def _read_provenance(r: NpzReader, n: int) -> dict:
    """The provenance fields of the maps file `r` of `n` maps, checked: all three or none (a /1 or /2 file: none)."""
    present = [f for f in PROVENANCE if r.has(f)]
    if not present:
        return {}
    if len(present) < len(PROVENANCE):
        missing = next(f for f in PROVENANCE if f not in present)
        raise r.fail(missing, f"is missing (it goes with {', '.join(present)}: a map's provenance)")
    source = r.array("source", "U", 1, (n,))
    digests = r.array("source_sha256", "U", 1, (n,))
    for d in digests:
        if d and (len(d) != 64 or not set(d) <= _HEX):
            raise r.fail("source_sha256", f"has {str(d)[:20]!r}, not a sha256 in hex (64 digits) or ''")
    origin = r.array("origin", "i", 2, (n, 2)).astype(np.int64)
    if origin.size and origin.min() < 0:
        raise r.fail("origin", "has a negative row or column")
    return {"source": source, "source_sha256": digests, "origin": origin}


def _joined_provenance(parts: list[MapSet]) -> dict:
    """The provenance of the parts' maps in order, unknown ("", origin (0, 0)) for the maps of a part without."""
    out: dict[str, list] = {f: [] for f in PROVENANCE}
    for p in parts:
        n = len(p)
        out["source"].append(p.source if p.has_provenance else np.full(n, ""))
        out["source_sha256"].append(p.source_sha256 if p.has_provenance else np.full(n, ""))
        out["origin"].append(p.origin if p.has_provenance else np.zeros((n, 2), np.int64))
    return {f: np.concatenate(v) for f, v in out.items()}
